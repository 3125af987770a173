//! The frame loop the position-level solvers (XPBD, VBD) share: the frame in `n` steps; a frame
//! that leaves any particle non-finite or faster than the limit is redone from its start with
//! twice the steps, twice; then the offending particles are put back where the frame started, at
//! rest. Stepping never fails: what happened is counted in the report.

use tryon_core::frames::{CoarseFrame, StepReport};
use tryon_core::math::{Real, Vec3, is_finite};

/// Runs `step(frame, t, h)` over a frame of `dt` from `frame.time` in as many equal steps as keep
/// `h` under `longest`, retrying as the module says. `step` returns how many particles it left
/// bad; `bad_input` is how many the caller found bad and reset before the frame (counted as
/// rollbacks). `backup` is scratch for the frame's start. Returns the report; `frame.time` ends at
/// the frame's end. A non-finite or non-positive `dt` steps nothing.
pub fn frame_with_retries(
    frame: &mut CoarseFrame,
    dt: Real,
    longest: Real,
    max_speed: Real,
    bad_input: u32,
    backup: &mut (Vec<Vec3>, Vec<Vec3>),
    mut step: impl FnMut(&mut CoarseFrame, Real, Real) -> u32,
) -> StepReport {
    let mut report = StepReport {
        rollbacks: bad_input,
        non_finite_events: bad_input,
        ..StepReport::default()
    };
    if !(dt.is_finite() && dt > 0.0) {
        return report;
    }
    backup.0.clone_from(&frame.positions);
    backup.1.clone_from(&frame.velocities);
    let t0 = frame.time;
    let mut n = (dt / longest).ceil().clamp(1.0, 1e6) as usize;
    for attempt in 0..3 {
        let h = dt / n as Real;
        let mut worst = 0;
        for s in 0..n {
            worst = worst.max(step(frame, t0 + s as Real * h, h));
        }
        report.substeps += n as u32;
        report.min_substep = h;
        if worst == 0 {
            break;
        }
        report.non_finite_events += frame.positions.iter().filter(|p| !is_finite(p)).count() as u32;
        if attempt == 2 {
            for i in 0..frame.positions.len() {
                let (x, v) = (frame.positions[i], frame.velocities[i]);
                if !is_finite(&x) || !(v.norm() <= max_speed) {
                    frame.positions[i] = backup.0[i];
                    frame.velocities[i] = Vec3::zeros();
                    report.rollbacks += 1;
                }
            }
            break;
        }
        report.retries += 1;
        frame.positions.clone_from(&backup.0);
        frame.velocities.clone_from(&backup.1);
        n *= 2;
    }
    frame.time = t0 + dt;
    report
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame() -> CoarseFrame {
        CoarseFrame {
            time: 1.0,
            positions: vec![Vec3::new(1.0, 2.0, 3.0), Vec3::zeros()],
            velocities: vec![Vec3::x(), Vec3::y()],
            ..CoarseFrame::default()
        }
    }

    #[test]
    fn a_bad_frame_is_redone_with_twice_the_steps_then_rolled_back() {
        let mut backup = (Vec::new(), Vec::new());
        // Bad at 2 and 4 steps, good at 8.
        let mut f = frame();
        let mut calls = Vec::new();
        let r = frame_with_retries(&mut f, 0.1, 0.05, 10.0, 0, &mut backup, |fr, t, h| {
            calls.push((t, h));
            fr.positions[0] += Vec3::x() * h;
            u32::from((h - 0.1 / 8.0).abs() > 1e-12)
        });
        assert_eq!((r.retries, r.rollbacks, r.substeps), (2, 0, 14));
        assert!((r.min_substep - 0.0125).abs() < 1e-12 && (f.time - 1.1).abs() < 1e-12);
        // Each attempt started from the frame's start: only the last one's motion remains.
        assert!((f.positions[0].x - 1.1).abs() < 1e-12, "{}", f.positions[0]);
        assert_eq!(calls.first(), Some(&(1.0, 0.05)));
        // Always bad: after the third attempt the non-finite particle goes back, at rest; the
        // good one keeps its step.
        let mut f = frame();
        let r = frame_with_retries(&mut f, 0.1, 0.1, 10.0, 2, &mut backup, |fr, _, _| {
            fr.positions[1] = Vec3::repeat(Real::NAN);
            fr.positions[0] = Vec3::new(5.0, 5.0, 5.0);
            1
        });
        // Two reset by the caller, one rolled back here; three more seen in the attempts.
        assert_eq!((r.retries, r.rollbacks), (2, 3));
        assert_eq!(r.non_finite_events, 5);
        assert_eq!(f.positions[1], Vec3::zeros());
        assert_eq!(f.velocities[1], Vec3::zeros());
        assert_eq!(f.positions[0], Vec3::new(5.0, 5.0, 5.0));
        // No frame to step: nothing moves, the caller's count stands.
        let mut f = frame();
        let r = frame_with_retries(&mut f, Real::NAN, 0.1, 10.0, 1, &mut backup, |_, _, _| 1);
        assert_eq!((r.substeps, r.rollbacks, f.time), (0, 1, 1.0));
    }
}
