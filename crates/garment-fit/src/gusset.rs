//! Gussets under the arms. A surface cut from the skin follows the crease where the arm's underside
//! meets the torso's side into its apex, and contact then gathers its vertices onto the crease (the
//! closest point outside is the same for all of them). A shirt is sewn otherwise: a piece of cloth
//! spans the crease below its apex. Here the cut surface near the crease is taken out and the
//! narrow hole left is zipped across with straight triangles, taut from the torso to the arm.

use crate::patterns::PatternError;
use tryon_core::math::{Real, Vec3};
use tryon_core::mesh::{Face, PolyMesh};

/// The arms' "up": perpendicular to the arm and in the vertical plane through it.
fn up_of(dir: Vec3) -> Vec3 {
    (Vec3::y() - dir * dir.y)
        .try_normalize(1e-9)
        .unwrap_or_else(Vec3::y)
}

/// The border of `mesh` as ordered cycles, each along its faces' winding (a triangle mesh).
pub(crate) fn boundary_cycles(mesh: &PolyMesh) -> Vec<Vec<u32>> {
    let (tris, _) = mesh.triangulate();
    let mut half = std::collections::HashSet::new();
    for t in &tris {
        for k in 0..3 {
            half.insert((t[k], t[(k + 1) % 3]));
        }
    }
    // In the faces' order, so that a vertex two openings share (a pinch) always joins the same way.
    let mut next = std::collections::HashMap::new();
    for t in &tris {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            if !half.contains(&(b, a)) {
                next.entry(a).or_insert(b);
            }
        }
    }
    let mut starts: Vec<u32> = next.keys().copied().collect();
    starts.sort_unstable();
    let mut seen = std::collections::HashSet::new();
    let mut cycles = Vec::new();
    for s in starts {
        if seen.contains(&s) {
            continue;
        }
        let mut cycle = vec![s];
        seen.insert(s);
        let mut v = s;
        while let Some(&w) = next.get(&v) {
            if w == s || !seen.insert(w) {
                break;
            }
            cycle.push(w);
            v = w;
        }
        cycles.push(cycle);
    }
    cycles
}

/// Takes out the surface within `reach` of the lower rim where each arm (`label` 0 or 1) leaves
/// the torso, on the arm's underside, and zips each hole across. Returns the new mesh and its
/// labels.
pub(crate) fn underarm_gussets(
    mesh: &PolyMesh,
    label: &[Option<u8>],
    arms: &[(Vec3, Vec3); 2],
    reach: Real,
) -> Result<(PolyMesh, Vec<Option<u8>>), PatternError> {
    let (tris, _) = mesh.triangulate();
    let x = &mesh.positions;
    let below = |v: usize, a: usize| (x[v] - arms[a].0).dot(&up_of(arms[a].1)) < 0.0;
    // The rim's lower half: torso vertices sharing a triangle with the arm, below it.
    let mut rim: [Vec<Vec3>; 2] = [Vec::new(), Vec::new()];
    for t in &tris {
        for a in 0..2u8 {
            if t.iter().any(|&v| label[v as usize] == Some(a)) {
                for &v in t.iter().filter(|&&v| label[v as usize].is_none()) {
                    if below(v as usize, a as usize) {
                        rim[a as usize].push(x[v as usize]);
                    }
                }
            }
        }
    }
    let keep: Vec<bool> = (0..x.len())
        .map(|v| !(0..2).any(|a| below(v, a) && rim[a].iter().any(|r| (x[v] - r).norm() < reach)))
        .collect();
    let cut = crate::shirt::cut(mesh, &keep);
    let mut labels: Vec<Option<u8>> = (0..x.len())
        .filter(|&v| keep[v])
        .map(|v| label[v])
        .collect();
    let before = boundary_cycles(mesh).len();
    let cycles = boundary_cycles(&cut);
    if cycles.len() != before + 2 {
        return Err(PatternError::Cut(format!(
            "taking out the crease under the arms left {} openings, not {}",
            cycles.len(),
            before + 2
        )));
    }
    // The new openings are those holding a vertex next to one taken out.
    let old_border: std::collections::HashSet<Vec3Key> = boundary_cycles(mesh)
        .iter()
        .flatten()
        .map(|&v| key(x[v as usize]))
        .collect();
    let mut out = cut;
    for c in cycles {
        if c.iter()
            .all(|&v| old_border.contains(&key(out.positions[v as usize])))
        {
            continue;
        }
        fill(&mut out, &c);
    }
    labels.resize(out.positions.len(), None);
    // Evened out around the gusset: where the zip meets the surface kept beside it, that surface
    // still dips toward the crease and folds over the zip's faces.
    let near: Vec<bool> = out
        .positions
        .iter()
        .map(|p| rim.iter().flatten().any(|r| (p - r).norm() < 2.0 * reach))
        .collect();
    even_out(&mut out, &near, EVEN_ROUNDS);
    Ok((out, labels))
}

/// Rounds of Laplacian smoothing around each gusset.
const EVEN_ROUNDS: usize = 10;

/// `rounds` Jacobi passes of half a Laplacian step at the vertices `at` (not on a border).
fn even_out(mesh: &mut PolyMesh, at: &[bool], rounds: usize) {
    let topo = match tryon_core::topology::Topology::build(mesh) {
        Ok(t) => t,
        Err(_) => return,
    };
    let n = mesh.positions.len();
    let mut ring: Vec<Vec<u32>> = vec![Vec::new(); n];
    for [a, b] in &topo.edges {
        ring[*a as usize].push(*b);
        ring[*b as usize].push(*a);
    }
    let mut border = vec![false; n];
    for &e in &topo.boundary_edges {
        let [a, b] = topo.edges[e as usize];
        border[a as usize] = true;
        border[b as usize] = true;
    }
    for _ in 0..rounds {
        let x = mesh.positions.clone();
        for v in (0..n).filter(|&v| at[v] && !border[v] && !ring[v].is_empty()) {
            let mean = ring[v].iter().map(|&u| x[u as usize]).sum::<Vec3>() / ring[v].len() as Real;
            mesh.positions[v] = x[v] + (mean - x[v]) * 0.5;
        }
    }
}

type Vec3Key = [u64; 3];
fn key(p: Vec3) -> Vec3Key {
    [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()]
}

/// Fills the hole bounded by `cycle` (along the existing faces' winding) by clipping ears, always
/// the one whose new edge is shortest among those that are not flat: a long narrow hole is zipped
/// across, not fanned (the hole's border is not planar, so no side is asked of an ear). Ears whose diagonal is already an edge are never clipped while another is
/// left.
fn fill(mesh: &mut PolyMesh, cycle: &[u32]) {
    let mut c: Vec<u32> = cycle.to_vec();
    let x = |v: u32| mesh.positions[v as usize];
    let (tris, _) = mesh.triangulate();
    let mut joined: std::collections::HashSet<(u32, u32)> = tris
        .iter()
        .flat_map(|t| (0..3).map(move |k| (t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3]))))
        .collect();
    let mut faces = Vec::new();
    while c.len() > 3 {
        let n = c.len();
        let ear = |k: usize| {
            let (p, q, r) = (x(c[(k + n - 1) % n]), x(c[k]), x(c[(k + 1) % n]));
            let d = (p - r).norm();
            // A flat ear (three points in a line) would be a degenerate face.
            let bad = (q - r).cross(&(p - r)).norm() < 0.1 * d * d;
            // A diagonal that is already an edge would join three faces.
            let (a, b) = (c[(k + n - 1) % n], c[(k + 1) % n]);
            (bad || joined.contains(&(a.min(b), a.max(b))), d)
        };
        let k = (0..n)
            .min_by(|&a, &b| {
                let (ea, eb) = (ear(a), ear(b));
                (ea.0, ea.1)
                    .partial_cmp(&(eb.0, eb.1))
                    .unwrap_or(std::cmp::Ordering::Equal)
            })
            .unwrap_or(0);
        let (p, q, r) = (c[(k + n - 1) % n], c[k], c[(k + 1) % n]);
        // The border runs p -> q -> r in existing faces: the new face takes them reversed.
        faces.push(Face::Tri([r, q, p]));
        joined.insert((p.min(r), p.max(r)));
        c.remove(k);
    }
    faces.push(Face::Tri([c[2], c[1], c[0]]));
    mesh.faces.extend(faces);
}

#[cfg(test)]
mod tests {
    use super::*;
    use tryon_core::mesh::grid_xz;

    fn triangles(mesh: &PolyMesh) -> PolyMesh {
        let (tris, _) = mesh.triangulate();
        PolyMesh {
            positions: mesh.positions.clone(),
            faces: tris.into_iter().map(Face::Tri).collect(),
        }
    }

    #[test]
    fn a_sheet_has_one_border_cycle_along_its_faces() {
        let sheet = triangles(&grid_xz(4, 3, 0.4, 0.3, 0.0));
        let cycles = boundary_cycles(&sheet);
        assert_eq!(cycles.len(), 1);
        assert_eq!(cycles[0].len(), 2 * (4 + 3));
        // Consecutive cycle vertices are joined by an edge.
        let e = tryon_core::topology::Topology::build(&sheet).unwrap().edges;
        for k in 0..cycles[0].len() {
            let (a, b) = (cycles[0][k], cycles[0][(k + 1) % cycles[0].len()]);
            assert!(e.contains(&[a.min(b), a.max(b)]), "{a}-{b}");
        }
    }

    #[test]
    fn a_narrow_hole_is_zipped_shut_with_the_faces_wound_alike() {
        // A 9 x 5 sheet with most of its middle row taken out: a long narrow hole.
        let sheet = triangles(&grid_xz(8, 4, 0.8, 0.4, 0.0));
        let keep: Vec<bool> = sheet
            .positions
            .iter()
            .map(|p| !(p.z.abs() < 1e-9 && p.x.abs() < 0.25))
            .collect();
        let mut holed = crate::shirt::cut(&sheet, &keep);
        let cycles = boundary_cycles(&holed);
        assert_eq!(cycles.len(), 2);
        let inner = cycles.iter().min_by_key(|c| c.len()).unwrap().clone();
        let before = holed.faces.len();
        fill(&mut holed, &inner);
        assert_eq!(holed.faces.len() - before, inner.len() - 2);
        assert_eq!(boundary_cycles(&holed).len(), 1);
        // Consistent winding: every directed edge once, and every new face's normal along +-y as
        // the sheet's.
        let (tris, _) = holed.triangulate();
        let mut half = std::collections::HashSet::new();
        for t in &tris {
            for k in 0..3 {
                assert!(half.insert((t[k], t[(k + 1) % 3])), "{t:?}");
            }
        }
        let up = |t: &[u32; 3]| {
            let x = t.map(|v| holed.positions[v as usize]);
            (x[1] - x[0]).cross(&(x[2] - x[0])).y
        };
        let sign = up(&tris[0]).signum();
        for t in &tris {
            assert!(
                up(t) * sign > 0.0,
                "{t:?} {:?}",
                t.map(|v| holed.positions[v as usize])
            );
        }
        // Zipped across: no new edge longer than the hole is wide plus a column.
        for t in &tris[tris.len() - (inner.len() - 2)..] {
            for k in 0..3 {
                let d = holed.positions[t[k] as usize] - holed.positions[t[(k + 1) % 3] as usize];
                assert!(d.norm() < 0.25, "{}", d.norm());
            }
        }
    }
}
