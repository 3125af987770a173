//! Elastic bands. A real waistband, collar or cuff is elastic and grips the skin, which a mass-spring
//! garment modelled at its worn size cannot do by friction alone: shorts on a running body ratchet
//! down a little at every stride until they fall. A band is a boundary loop of the garment that lies
//! close to the body along (nearly) its whole length when fitted; the pipeline binds its vertices to
//! the body's surface and moves them with it.

use crate::find_root as find;
use tryon_core::math::{Real, Vec3};
use tryon_core::mesh::PolyMesh;
use tryon_core::topology::{Topology, TopologyError};

/// The boundary of a mesh split into connected loops: each loop's vertices, ascending; loops
/// ordered by their smallest vertex.
pub fn boundary_loops(mesh: &PolyMesh) -> Result<Vec<Vec<u32>>, TopologyError> {
    let topo = Topology::build(mesh)?;
    let n = mesh.positions.len();
    let mut parent: Vec<usize> = (0..n).collect();
    let mut on = vec![false; n];
    for &e in &topo.boundary_edges {
        let [a, b] = topo.edges[e as usize];
        on[a as usize] = true;
        on[b as usize] = true;
        let (ra, rb) = (find(&mut parent, a as usize), find(&mut parent, b as usize));
        parent[ra] = rb;
    }
    let mut slot = vec![usize::MAX; n];
    let mut loops: Vec<Vec<u32>> = Vec::new();
    for v in 0..n {
        if !on[v] {
            continue;
        }
        let r = find(&mut parent, v);
        if slot[r] == usize::MAX {
            slot[r] = loops.len();
            loops.push(Vec::new());
        }
        loops[slot[r]].push(v as u32);
    }
    Ok(loops)
}

/// How close to the body a modelled garment's border loops must lie to grip it as elastic bands
/// unless a scene says otherwise (m); patterns have none.
pub const MODELLED_BAND_GAP: Real = 0.006;

/// The loops that are bands: at least `min_len` vertices, and 90% of them within `max_gap` of the
/// body (`gap(v)` is vertex v's distance outside the body). Returns the band vertices, ascending.
pub fn select_bands(
    loops: &[Vec<u32>],
    min_len: usize,
    max_gap: Real,
    mut gap: impl FnMut(u32) -> Real,
) -> Vec<u32> {
    let mut out = Vec::new();
    for l in loops.iter().filter(|l| l.len() >= min_len.max(1)) {
        let mut d: Vec<Real> = l.iter().map(|&v| gap(v)).collect();
        d.sort_by(|a, b| a.total_cmp(b));
        let p90 = d[(d.len() * 9 / 10).min(d.len() - 1)];
        if p90 <= max_gap {
            out.extend_from_slice(l);
        }
    }
    out.sort_unstable();
    out
}

/// How far from the body a waist may lie and still be held as a belt holds it, unless a scene
/// says otherwise (m).
pub const MODELLED_WAIST_GAP: Real = 0.04;

/// Share of the body's height (from its lowest point) that a piece must reach to hang from the
/// shoulders; a piece below it (trousers, shorts, a skirt, a strapless top) rests on nothing.
pub const SHOULDER_SHARE: Real = 0.75;

/// The waists: of each piece (`piece[v]`: vertex v's piece) whose highest vertex lies below
/// `shoulder` (height, y up), its highest loop (by mean height), when that loop has at least
/// `min_len` vertices and 90% of them within `max_gap` of the body (`gap(v)`). Such a piece has
/// nothing to hang from: modelled with ease at the waist, it slides down the legs at every stride,
/// where a real one is held by its waistband, a belt or a drawstring. Returns the waist vertices,
/// ascending.
pub fn select_waists(
    loops: &[Vec<u32>],
    (piece, positions): (&[usize], &[Vec3]),
    shoulder: Real,
    (min_len, max_gap): (usize, Real),
    mut gap: impl FnMut(u32) -> Real,
) -> Vec<u32> {
    let pieces = piece.iter().copied().max().map_or(0, |m| m + 1);
    let mut top = vec![Real::NEG_INFINITY; pieces];
    for (v, &c) in piece.iter().enumerate() {
        top[c] = top[c].max(positions.get(v).map_or(Real::NEG_INFINITY, |p| p.y));
    }
    let mean_y = |l: &Vec<u32>| {
        l.iter().map(|&v| positions[v as usize].y).sum::<Real>() / l.len().max(1) as Real
    };
    let mut best: Vec<Option<(Real, usize)>> = vec![None; pieces];
    for (k, l) in loops.iter().enumerate() {
        let Some(&c) = l.first().and_then(|&v| piece.get(v as usize)) else {
            continue;
        };
        let y = mean_y(l);
        if best[c].is_none_or(|(b, _)| y > b) {
            best[c] = Some((y, k));
        }
    }
    let mut out = Vec::new();
    for (c, b) in best.iter().enumerate() {
        if let Some((_, k)) = b
            && top[c] < shoulder
        {
            out.extend(select_bands(&loops[*k..=*k], min_len, max_gap, &mut gap));
        }
    }
    out.sort_unstable();
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use tryon_core::math::Vec3;
    use tryon_core::mesh::Face;

    /// An open tube: `rings` rings of `k` quads, radius 1, ring r at height r.
    fn tube(k: usize, rings: usize) -> PolyMesh {
        let mut pos = Vec::new();
        for r in 0..=rings {
            for i in 0..k {
                let a = i as Real / k as Real * std::f64::consts::TAU;
                pos.push(Vec3::new(a.cos(), r as Real, a.sin()));
            }
        }
        let mut quads = Vec::new();
        for r in 0..rings {
            for i in 0..k {
                let (a, b) = ((r * k + i) as u32, (r * k + (i + 1) % k) as u32);
                quads.push([a, b, b + k as u32, a + k as u32]);
            }
        }
        PolyMesh::new(pos, quads.into_iter().map(Face::Quad).collect()).unwrap()
    }

    #[test]
    fn a_tube_has_two_loops_and_the_tight_one_is_a_band() {
        let m = tube(12, 3);
        let loops = boundary_loops(&m).unwrap();
        assert_eq!(loops.len(), 2);
        assert_eq!(loops[0], (0..12).collect::<Vec<u32>>());
        assert_eq!(loops[1], (36..48).collect::<Vec<u32>>());
        // The bottom ring is 2 mm from the body, the top ring 2 cm, with one bottom vertex far out.
        let gap = |v: u32| match v {
            0 => 0.05,
            v if v < 12 => 0.002,
            _ => 0.02,
        };
        assert_eq!(
            select_bands(&loops, 8, 0.006, gap),
            (0..12).collect::<Vec<u32>>()
        );
        // Too short a loop is not a band.
        assert!(select_bands(&loops, 13, 0.006, gap).is_empty());
        // A closed mesh has none.
        let s = tryon_core::shapes::icosphere(1.0, 1, Vec3::zeros());
        assert!(boundary_loops(&s).unwrap().is_empty());
    }

    #[test]
    fn the_top_loop_of_a_piece_below_the_shoulders_is_its_waist_and_only_that_one() {
        // Two tubes: trousers (rings at heights 0..=3, top loop 36..48) and a top reaching
        // height 13 (rings 10..=13, vertices 48..96).
        let lower = tube(12, 3);
        let mut upper = tube(12, 3);
        for p in &mut upper.positions {
            p.y += 10.0;
        }
        let mut pos = lower.positions.clone();
        pos.extend(upper.positions.iter().copied());
        let mut faces = lower.faces.clone();
        faces.extend(upper.faces.iter().map(|f| match f {
            Face::Quad(q) => Face::Quad(q.map(|v| v + 48)),
            Face::Tri(t) => Face::Tri(t.map(|v| v + 48)),
        }));
        let m = PolyMesh::new(pos, faces).unwrap();
        let loops = boundary_loops(&m).unwrap();
        let piece = crate::attach::components(&m);
        // Every loop 3 cm from the body: none is a band at 6 mm.
        let gap = |_: u32| 0.03;
        assert!(select_bands(&loops, 8, 0.006, gap).is_empty());
        let waists = select_waists(&loops, (&piece, &m.positions), 12.0, (8, 0.04), gap);
        assert_eq!(waists, (36..48).collect::<Vec<u32>>());
        // With the shoulders above both pieces, both pieces' top loops are waists.
        let both = select_waists(&loops, (&piece, &m.positions), 20.0, (8, 0.04), gap);
        let mut want: Vec<u32> = (36..48).collect();
        want.extend(84..96);
        assert_eq!(both, want);
        // A waist farther out than the allowed gap is left free, as is one on a short loop.
        assert!(select_waists(&loops, (&piece, &m.positions), 12.0, (8, 0.02), gap).is_empty());
        assert!(select_waists(&loops, (&piece, &m.positions), 12.0, (13, 0.04), gap).is_empty());
    }
}
