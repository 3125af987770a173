//! `tryon batch MANIFEST`: many runs at once. Each job is a child `tryon` process (so one job's
//! failure or memory never touches another), writing into its own folder under the manifest's
//! `out` with its log in `log.txt` and its state in `job.json`. A job whose `job.json` says done
//! for the same scene, overrides and frames is skipped; one that was interrupted goes on from its
//! checkpoint (`tryon run --resume`) or starts again. Progress goes to stderr; at the end
//! summary.md and summary.csv list every job of the manifest.

pub(crate) mod manifest;
mod summary;

use crate::Failure;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use manifest::Job;
use serde::{Deserialize, Serialize};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// How a batch is run (`tryon batch` flags).
#[derive(clap::Args, Debug)]
pub(crate) struct BatchFlags {
    /// Run only the I-th of N disjoint parts (0 <= I < N; job k is in part k mod N), so one
    /// manifest spreads over machines (a Slurm array task or a Kubernetes job index as I).
    #[arg(long, value_name = "I/N", value_parser = crate::batch::manifest::shard_arg)]
    pub shard: Option<(usize, usize)>,
    /// Jobs at a time (default: one per core).
    #[arg(long, short, value_parser = clap::value_parser!(u32).range(1..=1024))]
    pub jobs: Option<u32>,
    /// Threads each job's solver uses (default: cores / jobs, and every core for the last jobs
    /// to start, which end the batch alone).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=1024))]
    pub threads: Option<u32>,
    /// List the jobs (of this part) and whether each is done, without running anything.
    #[arg(long, conflicts_with = "summary")]
    pub list: bool,
    /// Only write (and print) summary.md and summary.csv from the jobs' folders as they
    /// are, running nothing: after the parts of a sharded batch have ended.
    #[arg(long)]
    pub summary: bool,
    /// No progress lines or summary table.
    #[arg(long, short)]
    pub quiet: bool,
}

/// A job's `job.json`: what it ran and how it ended.
#[derive(Debug, Default, Serialize, Deserialize)]
pub(crate) struct JobRecord {
    pub name: String,
    pub scene: String,
    pub sets: Vec<String>,
    pub frames: Option<usize>,
    /// Of the scene file's text, the overrides and the frames: a changed job runs again.
    pub fingerprint: String,
    /// "running", "done" or "failed".
    pub status: String,
    pub exit_code: Option<i32>,
    pub wall_s: f64,
    /// The last line the job wrote to its log, when it failed.
    pub error: Option<String>,
}

const RECORD: &str = "job.json";

/// Runs the manifest at `path` as `flags` ask.
pub(crate) fn run(path: &Path, flags: &BatchFlags) -> Result<(), Failure> {
    let batch = manifest::read(path).map_err(Failure::BadInput)?;
    if flags.summary {
        let table = summary::write(&batch, path).map_err(Failure::Internal)?;
        if !flags.quiet {
            print!("{table}");
        }
        return Ok(());
    }
    let part = flags.shard.unwrap_or((0, 1));
    let mine = manifest::shard(&batch.jobs, part);
    let mut planned = Vec::with_capacity(mine.len());
    for (k, job) in mine {
        let fingerprint = fingerprint(job).map_err(|e| {
            Failure::BadInput(format!("{}: job `{}`: {e}", path.display(), job.name))
        })?;
        let dir = batch.out.join(&job.name);
        let start = start_of(&dir, &fingerprint);
        planned.push(Planned {
            index: k,
            job,
            dir,
            fingerprint,
            start,
        });
    }
    if flags.list {
        for p in &planned {
            let state = match p.start {
                Start::Done => "done",
                Start::Resume => "interrupted (resumes)",
                Start::Fresh => "to run",
            };
            println!("{:>5}  {:<40} {state}", p.index, p.job.name);
        }
        return Ok(());
    }
    crate::mark_generated(&batch.out);
    std::fs::create_dir_all(&batch.out)
        .map_err(|e| Failure::Internal(format!("{}: {e}", batch.out.display())))?;
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let width = flags.jobs.map_or(cores, |j| j as usize).max(1);
    let threads = Threads {
        cores,
        width,
        fixed: flags.threads.map(|t| t as usize),
    };
    let exe = std::env::current_exe()
        .map_err(|e| Failure::Internal(format!("cannot find the tryon program: {e}")))?;
    let mut progress = Progress::new(planned.len(), width, flags.quiet);
    let failed = run_all(&exe, planned, width, threads, &mut progress);
    progress.finish();
    let table = summary::write(&batch, path).map_err(Failure::Internal)?;
    if !flags.quiet {
        print!("{table}");
        println!("wrote {}", batch.out.join("summary.md").display());
    }
    match failed {
        0 => Ok(()),
        n => Err(Failure::JobsFailed(format!(
            "{n} job(s) failed; their log.txt says why (rerun the batch to retry them)"
        ))),
    }
}

/// The threads each job's solver gets.
#[derive(Clone, Copy)]
struct Threads {
    cores: usize,
    width: usize,
    /// `--threads`.
    fixed: Option<usize>,
}

impl Threads {
    /// A job started with `queued` jobs still waiting: a fair share of the cores while others
    /// will follow, every core for the last ones (the batch's tail, when the others end, is left
    /// to them; docs/decisions, *batch*).
    fn for_job(&self, queued: usize) -> usize {
        let share = match queued {
            0 => self.cores,
            _ => self.cores / self.width,
        };
        self.fixed.unwrap_or(share).max(1)
    }
}

/// A job of this part, its folder and how it starts.
struct Planned<'a> {
    index: usize,
    job: &'a Job,
    dir: PathBuf,
    fingerprint: String,
    start: Start,
}

#[derive(Clone, Copy, PartialEq)]
enum Start {
    /// Done before with the same fingerprint: skipped.
    Done,
    /// Interrupted with a checkpoint: `tryon run --resume`.
    Resume,
    Fresh,
}

/// A job's fingerprint: FNV-1a of its scene's text, overrides and frames.
fn fingerprint(job: &Job) -> Result<String, String> {
    let text = if job.is_demo() {
        tryon_pipeline::DEMO_SCENE.to_string()
    } else {
        std::fs::read_to_string(&job.scene)
            .map_err(|e| format!("{}: cannot read: {e}", job.scene.display()))?
    };
    // The job's scene and overrides must parse before any job runs (a typo in a cross product
    // fails now, not after hours).
    let parsed = match job.is_demo() {
        true => tryon_pipeline::Scene::parse_with_overrides(&text, &job.scene, &job.sets),
        false => tryon_pipeline::Scene::load_with_overrides(&job.scene, &job.sets),
    };
    parsed.map_err(|e| e.to_string())?;
    let mut bytes = text.into_bytes();
    for s in &job.sets {
        bytes.push(0);
        bytes.extend_from_slice(s.as_bytes());
    }
    bytes.extend_from_slice(format!("\0{:?}", job.frames).as_bytes());
    Ok(format!("{:016x}", tryon_core::state::fnv1a(&bytes)))
}

fn read_record(dir: &Path) -> Option<JobRecord> {
    let text = std::fs::read_to_string(dir.join(RECORD)).ok()?;
    serde_json::from_str(&text).ok()
}

fn start_of(dir: &Path, fingerprint: &str) -> Start {
    let rec = read_record(dir).filter(|r| r.fingerprint == fingerprint);
    match rec {
        Some(r) if r.status == "done" && dir.join("stats.json").exists() => Start::Done,
        Some(_) if dir.join("checkpoint.tryon").exists() => Start::Resume,
        _ => Start::Fresh,
    }
}

/// A job's child process.
struct Running<'a> {
    plan: Planned<'a>,
    child: Child,
    began: Instant,
}

/// Runs the planned jobs, `width` at a time; returns how many failed.
fn run_all(
    exe: &Path,
    planned: Vec<Planned<'_>>,
    width: usize,
    threads: Threads,
    progress: &mut Progress,
) -> usize {
    let mut queue: std::collections::VecDeque<_> = planned.into();
    let mut running: Vec<Running> = Vec::new();
    let mut failed = 0;
    loop {
        while running.len() < width
            && let Some(plan) = queue.pop_front()
        {
            if plan.start == Start::Done {
                progress.skipped();
                continue;
            }
            match spawn(exe, &plan, threads.for_job(queue.len())) {
                Ok(child) => running.push(Running {
                    plan,
                    child,
                    began: Instant::now(),
                }),
                Err(e) => {
                    failed += 1;
                    let rec = record(&plan, "failed", None, 0.0, Some(e));
                    let _ = tryon_io::write_json(&plan.dir.join(RECORD), &rec);
                    progress.ended(false, 0.0);
                }
            }
        }
        if running.is_empty() {
            return failed;
        }
        progress.tick(running.len(), queue.len());
        std::thread::sleep(Duration::from_millis(100));
        let mut k = 0;
        while k < running.len() {
            match running[k].child.try_wait() {
                Ok(None) => k += 1,
                Ok(Some(status)) => {
                    let mut r = running.swap_remove(k);
                    // A checkpoint the run refuses (exit 2: its scene changed, or damaged) is
                    // dropped and the job starts again.
                    if r.plan.start == Start::Resume && status.code() == Some(2) {
                        r.plan.start = Start::Fresh;
                        if let Ok(child) = spawn(exe, &r.plan, threads.for_job(queue.len())) {
                            r.child = child;
                            running.push(r);
                            continue;
                        }
                    }
                    let wall = r.began.elapsed().as_secs_f64();
                    let ok = status.success();
                    failed += usize::from(!ok);
                    let error = (!ok).then(|| last_line(&r.plan.dir.join("log.txt")));
                    let state = if ok { "done" } else { "failed" };
                    let rec = record(&r.plan, state, status.code(), wall, error);
                    let _ = tryon_io::write_json(&r.plan.dir.join(RECORD), &rec);
                    progress.ended(ok, wall);
                }
                Err(_) => k += 1,
            }
        }
    }
}

fn record(
    plan: &Planned<'_>,
    status: &str,
    exit_code: Option<i32>,
    wall_s: f64,
    error: Option<String>,
) -> JobRecord {
    JobRecord {
        name: plan.job.name.clone(),
        scene: plan.job.scene.display().to_string(),
        sets: plan.job.sets.clone(),
        frames: plan.job.frames,
        fingerprint: plan.fingerprint.clone(),
        status: status.into(),
        exit_code,
        wall_s,
        error,
    }
}

/// Starts a job's `tryon` process, its output going to the job's log.txt, and records it as
/// running.
fn spawn(exe: &Path, plan: &Planned<'_>, threads: usize) -> Result<Child, String> {
    let dir = &plan.dir;
    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let rec = record(plan, "running", None, 0.0, None);
    tryon_io::write_json(&dir.join(RECORD), &rec).map_err(|e| format!("{RECORD}: {e}"))?;
    let log_path = dir.join("log.txt");
    let log = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(&log_path)
        .map_err(|e| format!("{}: {e}", log_path.display()))?;
    let err = log.try_clone().map_err(|e| e.to_string())?;
    let mut cmd = Command::new(exe);
    let job = plan.job;
    match (plan.start, job.is_demo()) {
        (Start::Resume, _) => {
            cmd.args(["run", "--quiet", "--resume"]).arg(dir);
        }
        (_, true) => {
            cmd.args(["demo", "--quiet", "--out"]).arg(dir);
        }
        (_, false) => {
            cmd.arg("run")
                .arg(&job.scene)
                .args(["--quiet", "--out"])
                .arg(dir);
        }
    }
    if plan.start != Start::Resume {
        job.sets.iter().for_each(|s| {
            cmd.arg("--set").arg(s);
        });
        if let Some(n) = job.frames {
            cmd.arg("--frames").arg(n.to_string());
        }
    }
    cmd.env("RAYON_NUM_THREADS", threads.to_string())
        .stdin(Stdio::null())
        .stdout(log)
        .stderr(err)
        .spawn()
        .map_err(|e| format!("cannot start {}: {e}", exe.display()))
}

/// The last non-empty line of a log (what a failed run said).
fn last_line(path: &Path) -> String {
    let text = std::fs::read_to_string(path).unwrap_or_default();
    let line = text.lines().rev().find(|l| !l.trim().is_empty());
    line.unwrap_or("(no output)").chars().take(400).collect()
}

/// The batch's progress on stderr: a bar on a terminal, a line a change (and a minute) in a log.
struct Progress {
    total: usize,
    width: usize,
    done: usize,
    failed: usize,
    skipped: usize,
    walls: Vec<f64>,
    bar: ProgressBar,
    tty: bool,
    quiet: bool,
    last_line: Option<(String, Instant)>,
}

impl Progress {
    fn new(total: usize, width: usize, quiet: bool) -> Progress {
        let tty = std::io::stderr().is_terminal();
        let bar = ProgressBar::new(total as u64);
        if quiet || !tty {
            bar.set_draw_target(ProgressDrawTarget::hidden());
        }
        let style = ProgressStyle::with_template("batch [{bar:30}] {pos}/{len} {msg}");
        bar.set_style(style.unwrap_or_else(|_| ProgressStyle::default_bar()));
        Progress {
            total,
            width,
            done: 0,
            failed: 0,
            skipped: 0,
            walls: Vec::new(),
            bar,
            tty,
            quiet,
            last_line: None,
        }
    }

    fn skipped(&mut self) {
        self.skipped += 1;
        self.bar.inc(1);
    }

    fn ended(&mut self, ok: bool, wall: f64) {
        match ok {
            true => self.done += 1,
            false => self.failed += 1,
        }
        self.walls.push(wall);
        self.bar.inc(1);
    }

    /// How long the jobs left will take: the mean job's time over the jobs at a time.
    fn time_left(&self, running: usize, queued: usize) -> String {
        if self.walls.is_empty() {
            return "time left: after the first job".into();
        }
        let mean = self.walls.iter().sum::<f64>() / self.walls.len() as f64;
        let s = mean * (queued as f64 + 0.5 * running as f64) / self.width as f64;
        format!("about {} left", clock(s))
    }

    fn tick(&mut self, running: usize, queued: usize) {
        let line = format!(
            "{} done, {running} running, {} failed, {} done before; {}",
            self.done,
            self.failed,
            self.skipped,
            self.time_left(running, queued)
        );
        self.bar.set_message(line.clone());
        if self.quiet || self.tty {
            return;
        }
        // In a log: a line when the counts change, and one a minute.
        let counts = line.split(';').next().unwrap_or("").to_string();
        let stale = (self.last_line.as_ref())
            .is_none_or(|(c, at)| *c != counts || at.elapsed() > Duration::from_secs(60));
        if stale {
            let ended = self.done + self.failed + self.skipped;
            eprintln!("batch: {ended} of {} jobs ended: {line}", self.total);
            self.last_line = Some((counts, Instant::now()));
        }
    }

    fn finish(&self) {
        self.bar.finish_and_clear();
        if !self.quiet {
            eprintln!(
                "batch: {} done, {} failed, {} done before",
                self.done, self.failed, self.skipped
            );
        }
    }
}

/// Seconds as `1h02m`, `3m05s` or `12s`.
fn clock(s: f64) -> String {
    let s = s.max(0.0).round() as u64;
    match s {
        0..60 => format!("{s}s"),
        60..3600 => format!("{}m{:02}s", s / 60, s % 60),
        _ => format!("{}h{:02}m", s / 3600, (s % 3600) / 60),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn times_left_read_as_a_clock() {
        assert_eq!(clock(12.4), "12s");
        assert_eq!(clock(185.0), "3m05s");
        assert_eq!(clock(3720.0), "1h02m");
    }

    #[test]
    fn the_last_jobs_get_every_core() {
        let t = Threads {
            cores: 8,
            width: 3,
            fixed: None,
        };
        assert_eq!((t.for_job(5), t.for_job(1), t.for_job(0)), (2, 2, 8));
        let one = Threads { width: 16, ..t };
        assert_eq!(one.for_job(3), 1, "at least one");
        let fixed = Threads {
            fixed: Some(3),
            ..t
        };
        assert_eq!((fixed.for_job(4), fixed.for_job(0)), (3, 3));
    }
}
