//! One colour's sweep of vertex block descent: every block's Newton step found in parallel, then
//! applied in order (each move kept within its self-contact bound, when the cloth has them).

use super::{PAR_CHUNK, VbdSim, pairs};
use rayon::prelude::*;
use tryon_core::math::{Real, Vec3, is_finite};

impl VbdSim {
    /// Moves the blocks of colour range `r` by their steps `dx` (non-finite steps are dropped),
    /// and their hinges' angles with them. Every member is kept within its self-contact bound,
    /// kinematic ones too: a band vertex set at its target by `begin` is drawn back to within its
    /// bound of where detection saw it, so bands move no faster than the cloth pressed on them
    /// (exempting them measured the same; docs/decisions, *reopening cap*).
    pub(super) fn apply(
        &mut self,
        x: &mut [Vec3],
        r: std::ops::Range<usize>,
        dx: &[[Vec3; 2]],
    ) -> usize {
        let mut clamped = 0;
        for (d, &b) in dx.iter().zip(&self.order[r]) {
            for (dv, &v) in d.iter().zip(&self.blocks[b as usize]) {
                if v != pairs::ALONE && is_finite(dv) {
                    let (v, old) = (v as usize, x[v as usize]);
                    x[v] += dv;
                    if let Some(sc) = &self.layers
                        && sc.clamp(v, &mut x[v])
                    {
                        clamped += 1;
                    }
                    self.hinges.moved(v, &(x[v] - old));
                }
            }
        }
        clamped
    }

    /// One Newton step on every vertex of one colour, into `dx`: the steps are found in parallel
    /// (no two vertices of a colour share a spring or a hinge, so each reads only vertices it does
    /// not move) and applied after (`apply`), so the result is the same for any number of threads.
    pub(super) fn sweep_colour(&self, x: &[Vec3], ids: &[u32], h: Real, dx: &mut Vec<[Vec3; 2]>) {
        dx.clear();
        dx.resize(ids.len(), [Vec3::zeros(); 2]);
        let xs = x;
        dx.par_iter_mut()
            .with_min_len(PAR_CHUNK)
            .zip(ids.par_iter())
            .for_each(|(d, &b)| *d = self.descend(xs, b as usize, h));
    }
}
