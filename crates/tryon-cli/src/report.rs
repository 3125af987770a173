//! A run with its progress bar, and the summary printed after it.

use crate::{Failure, mark_generated};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal;
use std::path::Path;
use tryon_pipeline::Pipeline;
use tryon_pipeline::checkpoint::Checkpoint;
use tryon_pipeline::resume::{Checkpointing, ResumeError};

/// How a run starts: from its first frame, or from a checkpoint.
pub(crate) enum Start {
    Fresh {
        frames: Option<usize>,
        checkpoints: Checkpointing,
    },
    Resume {
        checkpoint: Box<Checkpoint>,
        every: usize,
    },
}

/// Runs `p` into `out` with a progress bar, then prints the summary. Returns whether the
/// garment left the body (the summary then warns).
pub(crate) fn run(mut p: Pipeline, out: &Path, start: Start, quiet: bool) -> Result<bool, Failure> {
    let (total, done) = match &start {
        Start::Fresh { frames, .. } => (frames.unwrap_or(p.frames), 0),
        Start::Resume { checkpoint, .. } => (checkpoint.run.stats.frames, checkpoint.frame),
    };
    let bar = ProgressBar::new(total as u64);
    bar.set_position(done as u64);
    if quiet || !std::io::stderr().is_terminal() {
        bar.set_draw_target(ProgressDrawTarget::hidden());
    }
    bar.set_style(
        ProgressStyle::with_template(
            "{prefix} [{bar:40}] {pos}/{len} frames, {elapsed} elapsed, eta {eta}",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .progress_chars("=> "),
    );
    bar.set_prefix(p.scene.scene.name.clone());
    let progress = |k: usize, _| bar.set_position(k as u64);
    let result = match start {
        Start::Fresh {
            frames,
            checkpoints,
        } => (p.run_checkpointed(out, frames, &checkpoints, progress))
            .map_err(|e| Failure::Internal(e.to_string())),
        Start::Resume { checkpoint, every } => p
            .resume_from(out, *checkpoint, every, progress)
            .map_err(|e| match e {
                ResumeError::Checkpoint(e) => Failure::BadInput(e.to_string()),
                e => Failure::Internal(e.to_string()),
            }),
    };
    bar.finish_and_clear();
    mark_generated(out);
    let written = result?;
    if let Some(why) = &written.no_checkpoints {
        eprintln!("warning: no checkpoints were written: {why}");
    }
    let (stats, files) = (written.stats, written.files);
    let left = stats.metrics.detached_share > 0.0;
    if !quiet {
        let s = &stats;
        let m = &s.metrics;
        println!(
            "{}: {} frames at {} fps in {:.1} s ({} coarse particles, {} body vertices, {} substep {:.5} s, collider {})",
            s.scene,
            s.frames,
            s.fps,
            s.loop_s,
            s.counts.coarse_vertices,
            s.counts.body_vertices,
            s.integrator,
            s.substep_s,
            s.collider
        );
        println!(
            "penetration max {:.2} mm, p99 {:.2} mm; stretch {:.3}..{:.3}, mean {:.3}; detached {}; retries {}, rollbacks {}, non-finite {}",
            m.max_penetration_m * 1e3,
            m.p99_penetration_m * 1e3,
            m.min_stretch,
            m.max_stretch,
            m.mean_stretch,
            percent(m.detached_share),
            m.substep_retries,
            m.rollbacks,
            m.non_finite_events
        );
        if let Some(r) = s.retarget.filter(|r| r.arm_frames_moved > 0) {
            println!(
                "retargeting turned an upper arm in {} of the clip's frames (counted per arm; at most {:.0} degrees) to keep the arms off the hips and the hands off the head",
                r.arm_frames_moved, r.max_arm_turn_deg
            );
        }
        if !m.fold_retention.is_empty() {
            let list = |v: &[Option<f64>]| {
                v.iter()
                    .map(|r| r.map_or("?".into(), |r| format!("{r:.2}")))
                    .collect::<Vec<String>>()
                    .join(", ")
            };
            println!(
                "folds: height over the drawn height {} at the end ({} as shaped)",
                list(&m.fold_retention),
                list(&m.fold_retention_shaped)
            );
        }
        if left {
            let worst = s
                .per_frame
                .iter()
                .max_by(|a, b| a.detached_share.total_cmp(&b.detached_share))
                .map_or(0, |f| f.frame);
            eprintln!(
                "warning: at frame {worst}, {} of the garment's vertices had left the body: more than 10 cm farther from it than at the start, and torn off, slid off what held them or fallen (stats.json per_frame has every frame)",
                percent(m.detached_share)
            );
        }
        for (name, t) in &s.stages {
            println!(
                "  {name:<16} {:8.3} ms mean {:8.3} ms max",
                t.ms_mean, t.ms_max
            );
        }
        for f in files {
            println!("wrote {}", f.display());
        }
    }
    Ok(left)
}

/// A share as a percentage with enough digits that a small one does not read as 0.0%.
pub(crate) fn percent(share: f64) -> String {
    let pct = share * 100.0;
    let digits = if pct == 0.0 || pct >= 1.0 {
        1
    } else if pct >= 0.1 {
        2
    } else {
        3
    };
    format!("{pct:.digits$}%")
}
