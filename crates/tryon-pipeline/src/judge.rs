//! The referee's part of the frame loop: judging a due frame.

use crate::metrics::{penetration_of, stretch_counted};
use crate::pipeline::Pipeline;
use crate::run::{RunContext, RunState};
use crate::stats::FrameStats;
use crate::timers::Timers;
use tryon_core::frames::{BodyFrame, StepReport};
use tryon_core::math::Vec3;

impl Pipeline {
    /// Judges output frame `k` with the exact referee into `state`'s statistics.
    pub(crate) fn judge(
        &mut self,
        ctx: &RunContext,
        state: &mut RunState,
        (k, report, coarse_x, body_frame): (usize, &StepReport, &[Vec3], &BodyFrame),
        timers: &mut Timers,
    ) {
        let stats = &mut state.stats;
        stats.metrics.judged_frames += 1;
        if let Some(j) = timers.time("referee", || {
            self.surface_stages
                .iter()
                .find_map(|s| s.length_error(&self.surface))
        }) {
            state.length.add(&j);
        }
        let output = if ctx.refines {
            &self.surface.positions
        } else {
            coarse_x
        };
        let referee = &mut self.referee;
        let depth = &mut state.depth;
        let stretches = &mut state.stretches;
        let (pen, (smin, smax, smean), cloth) = timers.time("referee", || {
            if ctx.moving {
                tryon_core::stages::Collider::update(referee, body_frame);
            }
            let signed = crate::metrics::distances(referee, output);
            depth.clear();
            depth.extend(signed.iter().map(|d| tryon_io::depth_code(-d)));
            (
                penetration_of(&signed, &ctx.start_distances),
                stretch_counted(&ctx.info.edges, &ctx.info.rest, coarse_x, stretches),
                body_collide::crossings::judge(output, &ctx.garment_triangles),
            )
        });
        let m = &mut stats.metrics;
        m.max_penetration_m = m.max_penetration_m.max(pen.max);
        m.p99_penetration_m = m.p99_penetration_m.max(pen.p99);
        m.max_stretch = m.max_stretch.max(smax);
        m.min_stretch = if m.judged_frames == 1 {
            smin
        } else {
            m.min_stretch.min(smin)
        };
        m.detached_share = m.detached_share.max(pen.detached_share);
        m.cloth_intersections = m.cloth_intersections.max(cloth.crossings);
        m.cloth_min_gap_m = if m.judged_frames == 1 {
            cloth.min_gap
        } else {
            m.cloth_min_gap_m.min(cloth.min_gap)
        };
        state.sums[0] += smean;
        state.sums[1] += pen.share_over_1mm;
        stats.per_frame.push(FrameStats {
            frame: k,
            max_penetration_m: pen.max,
            p99_penetration_m: pen.p99,
            max_stretch: smax,
            detached_share: pen.detached_share,
            cloth_intersections: cloth.crossings,
            contacts: report.contacts,
            retries: report.retries,
            body_parts: report.body_parts,
            fold_retention: (self.folds).retention(&self.cloth.positions, &ctx.fold_triangles),
        });
        stats.frame_ms.push(timers.open());
    }
}
