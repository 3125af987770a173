//! Procedural closed shapes for fixtures and tests (icospheres and their affine images).

use crate::math::{Real, Vec3};
use crate::mesh::{Face, PolyMesh};
use std::collections::HashMap;

/// An icosphere of the given radius and centre: a closed, outward-facing triangle mesh with
/// `10 * 4^subdivisions + 2` vertices.
pub fn icosphere(radius: Real, subdivisions: u32, center: Vec3) -> PolyMesh {
    let t = (1.0 + (5.0 as Real).sqrt()) / 2.0;
    let mut pos: Vec<Vec3> = [
        (-1.0, t, 0.0),
        (1.0, t, 0.0),
        (-1.0, -t, 0.0),
        (1.0, -t, 0.0),
        (0.0, -1.0, t),
        (0.0, 1.0, t),
        (0.0, -1.0, -t),
        (0.0, 1.0, -t),
        (t, 0.0, -1.0),
        (t, 0.0, 1.0),
        (-t, 0.0, -1.0),
        (-t, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| Vec3::new(x, y, z).normalize())
    .collect();
    let mut tris: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..subdivisions {
        let mut mid: HashMap<(u32, u32), u32> = HashMap::new();
        let mut midpoint = |a: u32, b: u32, pos: &mut Vec<Vec3>| -> u32 {
            let key = (a.min(b), a.max(b));
            *mid.entry(key).or_insert_with(|| {
                pos.push(((pos[a as usize] + pos[b as usize]) * 0.5).normalize());
                (pos.len() - 1) as u32
            })
        };
        let mut next = Vec::with_capacity(tris.len() * 4);
        for [a, b, c] in tris {
            let ab = midpoint(a, b, &mut pos);
            let bc = midpoint(b, c, &mut pos);
            let ca = midpoint(c, a, &mut pos);
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        tris = next;
    }
    PolyMesh {
        positions: pos.into_iter().map(|p| center + p * radius).collect(),
        faces: tris.into_iter().map(Face::Tri).collect(),
    }
}

/// Applies `p -> center + axes * (p - center)` per axis (an axis-aligned scaling about `center`).
pub fn scale_about(mesh: &mut PolyMesh, center: Vec3, scale: Vec3) {
    for p in &mut mesh.positions {
        *p = center + (*p - center).component_mul(&scale);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::topology::Topology;

    #[test]
    fn icosphere_is_closed_and_outward() {
        let m = icosphere(0.3, 3, Vec3::new(0.0, 1.0, 0.0));
        assert_eq!(m.positions.len(), 642);
        let t = Topology::build(&m).unwrap();
        assert!(t.is_closed());
        let (tris, _) = m.triangulate();
        let mut volume = 0.0;
        for [a, b, c] in tris {
            let (a, b, c) = (
                m.positions[a as usize],
                m.positions[b as usize],
                m.positions[c as usize],
            );
            volume += a.dot(&b.cross(&c)) / 6.0;
        }
        let exact = 4.0 / 3.0 * std::f64::consts::PI * 0.027;
        assert!(
            volume > 0.95 * exact && volume < exact,
            "volume {volume} vs sphere {exact}"
        );
    }
}
