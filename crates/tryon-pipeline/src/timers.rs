//! Wall time per stage and per frame, as stats.json reports it (mean and max over frames).

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::time::Instant;
use tryon_core::math::Real;
use tryon_core::stages::Clock;

/// Time spent in one stage per frame (ms).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct StageTime {
    pub ms_mean: Real,
    pub ms_max: Real,
    #[serde(skip)]
    sum: Real,
    #[serde(skip)]
    count: usize,
}

/// Wall time per stage. A stage timed in several parts within one frame (following: carry
/// before the step, record after it) counts as one: parts add up until `end_frame`.
#[derive(Debug, Default)]
pub struct Timers {
    totals: BTreeMap<&'static str, StageTime>,
    frame: BTreeMap<&'static str, Real>,
}

impl Timers {
    /// Runs `f`, adding its wall time to stage `name` in the open frame.
    pub fn time<T>(&mut self, name: &'static str, f: impl FnOnce() -> T) -> T {
        let t0 = Instant::now();
        let r = f();
        *self.frame.entry(name).or_default() += t0.elapsed().as_secs_f64() * 1e3;
        r
    }

    /// Adds another set of timers' open frame into this one (for work done on another thread).
    pub fn absorb(&mut self, other: &mut Timers) {
        for (name, ms) in std::mem::take(&mut other.frame) {
            *self.frame.entry(name).or_default() += ms;
        }
    }

    /// The open frame's time so far per stage (ms, to the microsecond).
    pub fn open(&self) -> BTreeMap<String, Real> {
        (self.frame.iter())
            .map(|(name, ms)| (name.to_string(), (ms * 1e3).round() / 1e3))
            .collect()
    }

    /// Closes the frame: each stage's time this frame goes into its mean and max.
    pub fn end_frame(&mut self) {
        for (name, ms) in std::mem::take(&mut self.frame) {
            let e = self.totals.entry(name).or_default();
            e.sum += ms;
            e.count += 1;
            e.ms_max = e.ms_max.max(ms);
        }
    }

    /// Closes the open frame and gives every stage's mean and max.
    pub fn finish(mut self) -> BTreeMap<String, StageTime> {
        self.end_frame();
        self.totals
            .into_iter()
            .map(|(name, mut t)| {
                t.ms_mean = t.sum / t.count.max(1) as Real;
                (name.to_string(), t)
            })
            .collect()
    }
}

/// Timers as a checkpoint keeps them: per stage, its name, summed and largest time (ms) and
/// frames counted.
pub type SavedTimers = Vec<(String, Real, Real, usize)>;

impl Timers {
    /// The closed frames' totals, for a checkpoint (taken between frames).
    pub fn saved(&self) -> SavedTimers {
        (self.totals.iter())
            .map(|(name, t)| (name.to_string(), t.sum, t.ms_max, t.count))
            .collect()
    }

    /// Timers that go on from `saved`, the stages named as in `names` (a name not there is
    /// dropped: only its time is lost).
    pub fn restored(saved: &SavedTimers, names: &[&'static str]) -> Timers {
        let mut t = Timers::default();
        for (name, sum, max, count) in saved {
            if let Some(&n) = names.iter().find(|n| **n == name.as_str()) {
                let e = t.totals.entry(n).or_default();
                (e.sum, e.ms_max, e.count) = (*sum, *max, *count);
            }
        }
        t
    }
}

impl Clock for Timers {
    fn time(&mut self, part: &'static str, work: &mut dyn FnMut()) {
        Timers::time(self, part, work)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parts_of_a_stage_add_up_within_a_frame_and_frames_average() {
        let mut t = Timers::default();
        let spin = |ms: u64| std::thread::sleep(std::time::Duration::from_millis(ms));
        t.time("a", || spin(2));
        Clock::time(&mut t, "a", &mut || spin(2));
        t.end_frame();
        t.time("a", || ());
        let mut other = Timers::default();
        other.time("b", || spin(1));
        t.absorb(&mut other);
        let s = t.finish();
        assert_eq!(s.keys().collect::<Vec<_>>(), ["a", "b"]);
        // Frame 1 had two parts of at least 2 ms; frame 2 almost nothing.
        assert!(s["a"].ms_max >= 4.0, "{:?}", s["a"]);
        assert!(s["a"].ms_mean >= 2.0 && s["a"].ms_mean < s["a"].ms_max);
        assert!(s["b"].ms_mean >= 1.0);
    }
}
