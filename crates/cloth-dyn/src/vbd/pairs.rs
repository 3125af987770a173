//! Sliver blocks. A vertex joined to another by a spring far stiffer than its other springs (the
//! short edge of a sliver triangle or of a doubled hem: k = stretch / rest) is badly served by
//! descent one vertex at a time: each of the two is held by the other, so their common motion
//! advances by tiny steps, and where contact pushes one before the other the short edge loses its
//! direction (it stands up or flips), after which its stiff spring tears the cloth around it. Such
//! pairs are solved together: one Newton step on their 6 x 6 block, in which the stiff spring is
//! internal. Vertices are matched greedily, stiffest first; every other vertex is a block alone.
//!
//! A spring alone cannot hold such a pair's direction: the short edge folded over (the two ends
//! swapped) changes the length of every longer spring around it by no more than its own length, so
//! the folded state costs almost nothing, and under tension the pair turns across the cloth to
//! unfold, one end going into the body. Inside a pair the stiff spring is therefore replaced by an
//! energy on the pair's whole offset: `k/2 |(x_i - x_j) - R d0|^2`, where `d0` is the rest offset and
//! `R` the rotation that best carries the ring of vertices around the pair from its rest shape to
//! where it is at the step's start (polar decomposition, lagged one step as friction is). The ring's
//! edges are long, so `R` does not see the sliver fold; the energy is convex (Hessian `k I`).

use super::Arm;
use tryon_core::math::{Mat3, Real, Vec3, is_finite};

/// A spring pairs its ends when the product of its shares of the summed spring stiffness at each
/// end is at least this: one vertex at a time, each sweep leaves about that share of the error
/// along the spring. On a regular grid a spring's share is about 0.15 at each
/// end (product 0.02), so nothing pairs; a 0.5 mm sliver between 6.7 cm cells has about 0.95 at
/// each (product 0.9).
pub const PAIR_COUPLING: Real = 0.25;

/// A pair's energy is this many times as stiff as the springs joining it. In a spring network the
/// tension across a sliver is carried by its short spring alone (the shear springs of a sliver cell
/// run along it, not across), so at its own stiffness a 0.5 mm sliver between 6.7 cm cells
/// stretched 1.18 where its neighbours stretched 1.08; solved inside its block, the pair can be
/// made stiffer at no cost to convergence: 1.02 at 10 times (1.008 at 100).
pub const PAIR_STIFFEN: Real = 10.0;

/// The second member of a block that has one vertex.
pub const ALONE: u32 = u32::MAX;

/// A 6 x 6 matrix of a pair's block.
pub type Mat6 = nalgebra::Matrix6<Real>;
/// A 6-vector of a pair's block.
pub type Vec6 = nalgebra::Vector6<Real>;

/// Blocks covering every vertex once: pairs `[i, j]` joined by a dominating spring (neither end
/// kinematic, `inv_mass` != 0), and singles `[i, ALONE]`. Deterministic (ties by vertex index).
pub fn blocks(offsets: &[u32], arms: &[Arm], inv_mass: &[Real]) -> Vec<[u32; 2]> {
    let n = offsets.len() - 1;
    let sum: Vec<Real> = (0..n)
        .map(|i| arms_of(offsets, arms, i).iter().map(|a| a.k).sum())
        .collect();
    let mut candidates: Vec<(Real, u32, u32)> = Vec::new();
    for i in 0..n {
        for a in arms_of(offsets, arms, i) {
            let j = a.other as usize;
            if j <= i || inv_mass[i] == 0.0 || inv_mass[j] == 0.0 {
                continue;
            }
            let coupling = a.k / sum[i] * (a.k / sum[j]);
            if coupling >= PAIR_COUPLING {
                candidates.push((coupling, i as u32, j as u32));
            }
        }
    }
    candidates.sort_by(|a, b| b.0.total_cmp(&a.0).then((a.1, a.2).cmp(&(b.1, b.2))));
    let mut used = vec![false; n];
    let mut out = Vec::with_capacity(n);
    for (_, i, j) in candidates {
        if !used[i as usize] && !used[j as usize] {
            used[i as usize] = true;
            used[j as usize] = true;
            out.push([i, j]);
        }
    }
    out.extend(
        (0..n as u32)
            .filter(|&i| !used[i as usize])
            .map(|i| [i, ALONE]),
    );
    out.sort_by_key(|b| b[0].min(b[1]));
    out
}

/// Each block's neighbouring blocks (blocks sharing a spring with it), for the colouring.
pub fn neighbours(offsets: &[u32], arms: &[Arm], blocks: &[[u32; 2]]) -> Vec<Vec<u32>> {
    let mut block_of = vec![0u32; offsets.len() - 1];
    for (b, members) in blocks.iter().enumerate() {
        for &v in members.iter().filter(|&&v| v != ALONE) {
            block_of[v as usize] = b as u32;
        }
    }
    blocks
        .iter()
        .enumerate()
        .map(|(b, members)| {
            let mut nb: Vec<u32> = members
                .iter()
                .filter(|&&v| v != ALONE)
                .flat_map(|&v| arms_of(offsets, arms, v as usize))
                .map(|a| block_of[a.other as usize])
                .filter(|&o| o != b as u32)
                .collect();
            nb.sort_unstable();
            nb.dedup();
            nb
        })
        .collect()
}

/// The springs at vertex `i`.
pub fn arms_of<'a>(offsets: &[u32], arms: &'a [Arm], i: usize) -> &'a [Arm] {
    &arms[offsets[i] as usize..offsets[i + 1] as usize]
}

/// The frame a pair is held in: the ring of vertices around it with their rest offsets from the
/// pair's rest centre, the pair's rest offset `d0` (`x_i - x_j`) and its stiffness.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Ring {
    pub ids: Vec<u32>,
    pub rest: Vec<Vec3>,
    pub d0: Vec3,
    pub k: Real,
}

impl Ring {
    /// The ring of pair `[i, j]`: every vertex sharing a spring with either, at rest positions
    /// `rest` scaled by `scale` about the pair's centre; its stiffness is that of the springs
    /// joining the two.
    pub fn new(
        offsets: &[u32],
        arms: &[Arm],
        [i, j]: [u32; 2],
        rest: &[Vec3],
        scale: Real,
    ) -> Ring {
        let (iu, ju) = (i as usize, j as usize);
        let centre = (rest[iu] + rest[ju]) * 0.5;
        let mut ids: Vec<u32> = arms_of(offsets, arms, iu)
            .iter()
            .chain(arms_of(offsets, arms, ju))
            .map(|a| a.other)
            .filter(|&o| o != i && o != j)
            .collect();
        ids.sort_unstable();
        ids.dedup();
        let k = arms_of(offsets, arms, iu)
            .iter()
            .filter(|a| a.other == j)
            .map(|a| a.k)
            .sum();
        Ring {
            rest: ids
                .iter()
                .map(|&o| (rest[o as usize] - centre) * scale)
                .collect(),
            ids,
            d0: (rest[iu] - rest[ju]) * scale,
            k,
        }
    }

    /// The pair's target offset `R d0` with the ring at `x` (pair `[i, j]`); `None` where the ring
    /// does not fix a rotation (fewer than two directions, or non-finite).
    pub fn target(&self, x: &[Vec3], [i, j]: [u32; 2]) -> Option<Vec3> {
        let centre = (x[i as usize] + x[j as usize]) * 0.5;
        let mut a = Mat3::zeros();
        for (&o, r) in self.ids.iter().zip(&self.rest) {
            a += (x[o as usize] - centre) * r.transpose();
        }
        let svd = a.svd(true, true);
        let (u, vt) = (svd.u?, svd.v_t?);
        let s = svd.singular_values;
        if !(s[1] > 1e-6 * s[0]) {
            return None;
        }
        let mut fix = Mat3::identity();
        fix[(2, 2)] = (u * vt).determinant().signum();
        let t = u * fix * vt * self.d0;
        is_finite(&t).then_some(t)
    }

    /// The target offset of pair `[i, j]` for a step starting at `x`: [`Ring::target`], or where
    /// the ring fixes no rotation, the pair's present direction at its rest length.
    pub fn target_or_spring(&self, x: &[Vec3], [i, j]: [u32; 2]) -> Vec3 {
        self.target(x, [i, j]).unwrap_or_else(|| {
            let d = x[i as usize] - x[j as usize];
            d.try_normalize(1e-12)
                .filter(is_finite)
                .map_or(self.d0, |n| n * self.d0.norm())
        })
    }
}

/// Newton step of a pair: each end's force and Hessian from everything but the springs joining
/// them (`fi, hi`, `fj, hj`), and the pair's energy `k/2 |(x_i - x_j) - target|^2` coupling them.
pub fn pair_step(
    (xi, fi, hi): (Vec3, Vec3, Mat3),
    (xj, fj, hj): (Vec3, Vec3, Mat3),
    (target, k): (Vec3, Real),
) -> Option<(Vec3, Vec3)> {
    let fs = -(xi - xj - target) * k;
    let kk = Mat3::identity() * k;
    let mut f = Vec6::zeros();
    let mut h = Mat6::zeros();
    f.fixed_rows_mut::<3>(0).copy_from(&(fi + fs));
    f.fixed_rows_mut::<3>(3).copy_from(&(fj - fs));
    h.fixed_view_mut::<3, 3>(0, 0).copy_from(&(hi + kk));
    h.fixed_view_mut::<3, 3>(3, 3).copy_from(&(hj + kk));
    h.fixed_view_mut::<3, 3>(0, 3).copy_from(&-kk);
    h.fixed_view_mut::<3, 3>(3, 0).copy_from(&-kk);
    let d = h.cholesky()?.solve(&f);
    Some((d.fixed_rows::<3>(0).into(), d.fixed_rows::<3>(3).into()))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn arm(other: u32, rest: Real) -> Arm {
        Arm {
            other,
            rest,
            k: 1.0 / rest,
        }
    }

    /// A chain 0 - 1 - 2 - 3 with edges of `lens`, as offsets and arms.
    fn chain(lens: [Real; 3]) -> (Vec<u32>, Vec<Arm>) {
        let mut lists = vec![Vec::new(); 4];
        for (e, &l) in lens.iter().enumerate() {
            lists[e].push(arm(e as u32 + 1, l));
            lists[e + 1].push(arm(e as u32, l));
        }
        let mut offsets = vec![0];
        let mut arms = Vec::new();
        for l in lists {
            arms.extend(l);
            offsets.push(arms.len() as u32);
        }
        (offsets, arms)
    }

    #[test]
    fn a_short_edge_between_long_ones_pairs_its_ends_and_even_edges_pair_nothing() {
        let (o, a) = chain([0.1, 0.001, 0.1]);
        let b = blocks(&o, &a, &[1.0; 4]);
        assert_eq!(b, vec![[0, ALONE], [1, 2], [3, ALONE]]);
        // Equal edges: a spring has all of an end's stiffness and half of an inner vertex's
        // (coupling 0.5), so the chain pairs as two pairs; at a tenth of its neighbours' length
        // the middle spring (coupling 0.83) pairs first and leaves the ends alone.
        let (o, a) = chain([0.1, 0.1, 0.1]);
        assert_eq!(blocks(&o, &a, &[1.0; 4]), vec![[0, 1], [2, 3]]);
        let (o, a) = chain([0.1, 0.01, 0.1]);
        assert_eq!(
            blocks(&o, &a, &[1.0; 4]),
            vec![[0, ALONE], [1, 2], [3, ALONE]]
        );
        // A kinematic end is never paired.
        let (o, a) = chain([0.1, 0.001, 0.1]);
        let b = blocks(&o, &a, &[1.0, 0.0, 1.0, 1.0]);
        assert_eq!(b, vec![[0, ALONE], [1, ALONE], [2, ALONE], [3, ALONE]]);
    }

    #[test]
    fn the_pairs_step_solves_its_quadratic_model_exactly() {
        // A stiff pair at its target along x, each end pulled up by a unit force with unit
        // stiffness: the pair rises together by the force over the stiffness, keeping its offset.
        let (xi, xj) = (Vec3::zeros(), Vec3::new(-0.001, 0.0, 0.0));
        let joint = (xi - xj, 1000.0);
        let up = Vec3::new(0.0, 1.0, 0.0);
        let (di, dj) = pair_step(
            (xi, up, Mat3::identity()),
            (xj, up, Mat3::identity()),
            joint,
        )
        .unwrap();
        assert!(
            (di - up).norm() < 1e-9 && (dj - up).norm() < 1e-9,
            "{di} {dj}"
        );
        // Pulled apart: they move apart only by f / (k_own + 2 k_pair) each.
        let x = Vec3::new(1.0, 0.0, 0.0);
        let (di, dj) =
            pair_step((xi, x, Mat3::identity()), (xj, -x, Mat3::identity()), joint).unwrap();
        let expect = 1.0 / (1.0 + 2.0 * 1000.0);
        assert!(
            (di.x - expect).abs() < 1e-9 && (dj.x + expect).abs() < 1e-9,
            "{di} {dj}"
        );
    }

    #[test]
    fn a_rings_target_turns_with_the_ring_and_ignores_the_pair() {
        // A pair 1 mm apart along x at the origin, in a ring of four points 5 cm around it.
        let mut rest = vec![Vec3::new(0.0005, 0.0, 0.0), Vec3::new(-0.0005, 0.0, 0.0)];
        for (x, z) in [(0.05, 0.0), (-0.05, 0.0), (0.0, 0.05), (0.0, -0.05)] {
            rest.push(Vec3::new(x, 0.0, z));
        }
        let mut lists: Vec<Vec<Arm>> = vec![Vec::new(); 6];
        for o in 2..6u32 {
            for e in [0u32, 1] {
                lists[e as usize].push(arm(o, 0.05));
                lists[o as usize].push(arm(e, 0.05));
            }
        }
        lists[0].push(arm(1, 0.001));
        lists[1].push(arm(0, 0.001));
        let mut offsets = vec![0];
        let mut arms = Vec::new();
        for l in lists {
            arms.extend(l);
            offsets.push(arms.len() as u32);
        }
        let ring = Ring::new(&offsets, &arms, [0, 1], &rest, 1.0);
        assert_eq!(ring.ids, vec![2, 3, 4, 5]);
        assert!((ring.k - 1000.0).abs() < 1e-9);
        // Turned 90 degrees about y and moved, with the pair itself swapped (folded over): the
        // target follows the ring, not the pair.
        let rot =
            nalgebra::Rotation3::from_axis_angle(&Vec3::y_axis(), std::f64::consts::FRAC_PI_2);
        let shift = Vec3::new(0.3, 0.2, 0.1);
        let mut x: Vec<Vec3> = rest.iter().map(|p| rot * p + shift).collect();
        x.swap(0, 1);
        let t = ring.target(&x, [0, 1]).unwrap();
        let expect = rot * Vec3::new(0.001, 0.0, 0.0);
        assert!((t - expect).norm() < 1e-12, "{t} vs {expect}");
        // A ring on one line fixes no rotation.
        let line: Vec<Vec3> = (0..6)
            .map(|k| Vec3::new(k as Real * 0.01, 0.0, 0.0))
            .collect();
        assert!(ring.target(&line, [0, 1]).is_none());
    }
}
