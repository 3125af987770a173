//! Procedural closed shapes: icospheres and their affine images (fixtures, tests, the sphere body)
//! and the table slab an object body stands on (P4's scene).

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

/// A closed box `side` x `thick` x `side` with its top face at y = 0, the top and bottom split
/// into `cells` x `cells` quads (so nearest-vertex tracking has vertices everywhere), faces
/// wound outward.
pub fn table_slab(side: Real, thick: Real, cells: usize) -> PolyMesh {
    let n = cells.max(1);
    let mut index: HashMap<(usize, usize, usize), u32> = HashMap::new();
    let mut positions = Vec::new();
    let mut vertex = |i: usize, j: usize, k: usize| -> u32 {
        *index.entry((i, j, k)).or_insert_with(|| {
            positions.push(Vec3::new(
                side * (i as Real / n as Real - 0.5),
                if j == 1 { 0.0 } else { -thick },
                side * (k as Real / n as Real - 0.5),
            ));
            (positions.len() - 1) as u32
        })
    };
    let mut quads: Vec<[u32; 4]> = Vec::new();
    for a in 0..n {
        for c in 0..n {
            for j in [0, 1] {
                quads.push([
                    vertex(a, j, c),
                    vertex(a + 1, j, c),
                    vertex(a + 1, j, c + 1),
                    vertex(a, j, c + 1),
                ]);
            }
        }
        for edge in [0, n] {
            quads.push([
                vertex(a, 0, edge),
                vertex(a + 1, 0, edge),
                vertex(a + 1, 1, edge),
                vertex(a, 1, edge),
            ]);
            quads.push([
                vertex(edge, 0, a),
                vertex(edge, 0, a + 1),
                vertex(edge, 1, a + 1),
                vertex(edge, 1, a),
            ]);
        }
    }
    let centre = Vec3::new(0.0, -thick / 2.0, 0.0);
    let faces = quads
        .into_iter()
        .map(|q| {
            let p = q.map(|v| positions[v as usize]);
            let normal = (p[1] - p[0]).cross(&(p[2] - p[0]));
            let mid = (p[0] + p[1] + p[2] + p[3]) / 4.0;
            if normal.dot(&(mid - centre)) < 0.0 {
                Face::Quad([q[3], q[2], q[1], q[0]])
            } else {
                Face::Quad(q)
            }
        })
        .collect();
    PolyMesh { positions, faces }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::topology::Topology;

    #[test]
    fn table_slab_is_closed_outward_and_its_top_is_at_zero() {
        let m = table_slab(1.5, 0.04, 7);
        assert!(Topology::build(&m).unwrap().is_closed());
        let v = m.signed_volume();
        assert!((v - 1.5 * 1.5 * 0.04).abs() < 1e-9, "volume {v}");
        let top = m.positions.iter().map(|p| p.y).fold(Real::MIN, Real::max);
        assert_eq!(top, 0.0);
        // The top and bottom are split into cells x cells quads: (cells + 1)^2 vertices each.
        assert_eq!(m.positions.iter().filter(|p| p.y == 0.0).count(), 64);
    }

    #[test]
    fn icosphere_is_closed_and_outward() {
        let m = icosphere(0.3, 3, Vec3::new(0.0, 1.0, 0.0));
        assert_eq!(m.positions.len(), 642);
        let t = Topology::build(&m).unwrap();
        assert!(t.is_closed());
        let volume = m.signed_volume();
        let exact = 4.0 / 3.0 * std::f64::consts::PI * 0.027;
        assert!(
            volume > 0.95 * exact && volume < exact,
            "volume {volume} vs sphere {exact}"
        );
    }
}
