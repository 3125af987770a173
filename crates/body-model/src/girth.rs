//! Girths measured the way a tape does: slice the mesh with a horizontal plane, group the cut into
//! connected pieces, take the piece nearest a vertical axis and return its convex hull's perimeter.

use tryon_core::math::{Real, Vec3};

/// The girth of the cut through `y = h` around the vertical axis through (`x`, `z`), or `None` when
/// the plane misses the mesh.
pub fn girth_at(
    positions: &[Vec3],
    triangles: &[[u32; 3]],
    h: Real,
    x: Real,
    z: Real,
) -> Option<Real> {
    // Cut points are keyed by the mesh element they lie on (a vertex or an edge) so that pieces can
    // be joined by union-find.
    let mut keys: Vec<(u32, u32)> = Vec::new();
    let mut pts: Vec<[Real; 2]> = Vec::new();
    let mut segs: Vec<(usize, usize)> = Vec::new();
    let mut key_of = |k: (u32, u32), p: [Real; 2], keys: &mut Vec<(u32, u32)>| -> usize {
        if let Some(i) = keys.iter().rposition(|&q| q == k) {
            return i;
        }
        keys.push(k);
        pts.push(p);
        keys.len() - 1
    };
    for t in triangles {
        let s = t.map(|v| positions[v as usize].y - h);
        let mut found: Vec<usize> = Vec::with_capacity(3);
        for e in 0..3 {
            let (a, b) = (t[e], t[(e + 1) % 3]);
            let (sa, sb) = (s[e], s[(e + 1) % 3]);
            let (pa, pb) = (positions[a as usize], positions[b as usize]);
            if sa == 0.0 {
                found.push(key_of((a, a), [pa.x, pa.z], &mut keys));
            } else if sa * sb < 0.0 {
                let u = sa / (sa - sb);
                let p = pa + (pb - pa) * u;
                found.push(key_of((a.min(b), a.max(b)), [p.x, p.z], &mut keys));
            }
        }
        found.dedup();
        if found.len() == 2 && found[0] != found[1] {
            segs.push((found[0], found[1]));
        }
    }
    if pts.is_empty() {
        return None;
    }
    let mut parent: Vec<usize> = (0..pts.len()).collect();
    fn root(p: &mut [usize], mut i: usize) -> usize {
        while p[i] != i {
            p[i] = p[p[i]];
            i = p[i];
        }
        i
    }
    for &(a, b) in &segs {
        let (ra, rb) = (root(&mut parent, a), root(&mut parent, b));
        parent[ra] = rb;
    }
    // The piece whose centroid is nearest the axis.
    let mut groups: std::collections::BTreeMap<usize, Vec<[Real; 2]>> = Default::default();
    for i in 0..pts.len() {
        let r = root(&mut parent, i);
        groups.entry(r).or_default().push(pts[i]);
    }
    let piece = groups
        .into_values()
        .filter(|g| g.len() >= 3)
        .min_by(|a, b| {
            let d = |g: &Vec<[Real; 2]>| {
                let n = g.len() as Real;
                let cx = g.iter().map(|p| p[0]).sum::<Real>() / n;
                let cz = g.iter().map(|p| p[1]).sum::<Real>() / n;
                (cx - x).powi(2) + (cz - z).powi(2)
            };
            d(a).total_cmp(&d(b))
        })?;
    Some(hull_perimeter(piece))
}

/// Perimeter of the convex hull of 2-D points (Andrew's monotone chain).
pub fn hull_perimeter(mut p: Vec<[Real; 2]>) -> Real {
    p.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
    p.dedup();
    if p.len() < 2 {
        return 0.0;
    }
    let cross = |o: [Real; 2], a: [Real; 2], b: [Real; 2]| {
        (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
    };
    let mut hull: Vec<[Real; 2]> = Vec::with_capacity(2 * p.len());
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &[Real; 2]>> = if pass == 0 {
            Box::new(p.iter())
        } else {
            Box::new(p.iter().rev())
        };
        for &q in iter {
            while hull.len() >= start + 2
                && cross(hull[hull.len() - 2], hull[hull.len() - 1], q) <= 0.0
            {
                hull.pop();
            }
            hull.push(q);
        }
        hull.pop();
    }
    (0..hull.len())
        .map(|i| {
            let (a, b) = (hull[i], hull[(i + 1) % hull.len()]);
            ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt()
        })
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use tryon_core::shapes::icosphere;

    #[test]
    fn hull_of_a_square_with_inner_points() {
        let p = vec![
            [0.0, 0.0],
            [1.0, 0.0],
            [1.0, 1.0],
            [0.0, 1.0],
            [0.5, 0.5],
            [0.2, 0.7],
        ];
        assert!((hull_perimeter(p) - 4.0).abs() < 1e-12);
    }

    #[test]
    fn sphere_equator_girth_is_near_two_pi_r() {
        let s = icosphere(0.5, 4, Vec3::zeros());
        let (tris, _) = s.triangulate();
        let g = girth_at(&s.positions, &tris, 0.013, 0.0, 0.0).unwrap();
        let exact = std::f64::consts::TAU * (0.25f64 - 0.013 * 0.013).sqrt();
        assert!((g / exact - 1.0).abs() < 0.01, "{g} vs {exact}");
        assert!(girth_at(&s.positions, &tris, 0.6, 0.0, 0.0).is_none());
    }
}
