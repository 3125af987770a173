//! `cargo xtask fuzz`: structure-aware mutation over every reader the product has (OBJ, BVH,
//! .mhskel, .mhw, .target, .mhclo/.proxy, scene TOML with `--set` overrides), from a corpus of
//! the data folder's real files (`fuzz_mutate`). Each case must return `Ok` or an error: a panic
//! is a failure, and a case running past 60 s is a hang. Failing inputs are written to
//! target/fuzz/failures/ to become named tests; the counts go to target/fuzz/summary.md (the
//! full run's are recorded in docs/reliability.md).

use crate::fuzz_mutate::{Rng, mutate, overrides, seeds};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

const READERS: &[&str] = &[
    "obj", "bvh", "retarget", "mhskel", "mhw", "target", "mhclo", "scene",
];
/// A case running longer than this is a hang.
const HANG: Duration = Duration::from_secs(60);

/// What one reader's run found.
#[derive(Default)]
struct Tally {
    cases: usize,
    ok: usize,
    errors: usize,
    panics: Vec<(usize, String)>,
    slowest_ms: f64,
    seconds: f64,
}

/// Parses `text` as `reader` reads it; `Ok(true)` when accepted, `Ok(false)` when refused.
fn read_case(reader: &str, text: &str, sets: &[String]) -> bool {
    let file = Path::new("fuzz-case");
    match reader {
        "obj" => tryon_io::parse_obj(text, file).is_ok_and(|m| {
            let mesh = tryon_core::mesh::PolyMesh {
                positions: m.positions,
                faces: m.faces,
            };
            mesh.welded().0.validate().is_ok()
        }),
        "bvh" => tryon_io::parse_bvh(text, file).is_ok(),
        "retarget" => retargeted(text),
        "mhskel" => tryon_io::makehuman::parse_mhskel(text, file).is_ok(),
        "mhw" => tryon_io::makehuman::parse_mhw(text, file).is_ok(),
        "target" => tryon_io::makehuman::parse_target(text, file).is_ok(),
        "mhclo" => tryon_io::makehuman::parse_binding(text, file).is_ok(),
        _ => tryon_pipeline::Scene::parse_with_overrides(text, file, sets).is_ok(),
    }
}

/// A BVH read as `tryon run` reads it (the unit guessed from its skeleton) and retargeted onto
/// the mannequin, sampled across its length: the clip's values reach the solver this way.
fn retargeted(text: &str) -> bool {
    use tryon_core::stages::MotionSource;
    static MANNEQUIN: std::sync::OnceLock<Option<body_model::Mannequin>> =
        std::sync::OnceLock::new();
    let Some(man) = MANNEQUIN.get_or_init(|| body_model::Mannequin::new(&Default::default()).ok())
    else {
        return false;
    };
    let Ok(f) = tryon_io::parse_bvh(text, Path::new("fuzz-case")) else {
        return false;
    };
    let unit = tryon_io::guess_unit(&f.skeleton, &f.end_sites).0;
    let clip = f.into_clip(unit);
    let rig = mocap_retarget::Rig::new(
        man.skeleton.clone(),
        man.joint_rest.clone(),
        vec![None; man.joint_rest.len()],
    );
    let opt = mocap_retarget::RetargetOptions {
        fps: 30.0,
        placement: mocap_retarget::Placement::StartAtTarget,
        start: 0.0,
        duration: None,
        ease_in: 0.5,
        skip_synthetic: true,
    };
    let Ok(motion) = mocap_retarget::retarget(&clip, &rig, &opt) else {
        return false;
    };
    let mut pose = tryon_core::pose::Pose::default();
    let d = motion.duration();
    for k in 0..=4 {
        motion.sample(d * k as f64 / 4.0, &mut pose);
    }
    true
}

/// One worker's place: which case it is on and since when (the watchdog reads it).
struct Slot {
    reader: &'static str,
    case: usize,
    text: String,
    sets: Vec<String>,
    since: Option<Instant>,
}

fn fuzz_reader(
    reader: &'static str,
    cases: usize,
    data: &Path,
    root: &Path,
    slot: &Mutex<Slot>,
) -> Result<Tally, String> {
    let seeds = seeds(reader, data, root)?;
    let start = Instant::now();
    let mut t = Tally {
        cases,
        ..Tally::default()
    };
    let index = READERS.iter().position(|r| *r == reader).unwrap_or(0) as u64;
    for i in 0..cases {
        let mut rng = Rng::new((index << 40) ^ i as u64);
        let seed = &seeds.texts[rng.below(seeds.texts.len())];
        let text = mutate(seed, &mut rng);
        let sets = if reader == "scene" {
            overrides(seed, &mut rng)
        } else {
            Vec::new()
        };
        if let Ok(mut s) = slot.lock() {
            *s = Slot {
                reader,
                case: i,
                text: text.clone(),
                sets: sets.clone(),
                since: Some(Instant::now()),
            };
        }
        let began = Instant::now();
        match catch_unwind(AssertUnwindSafe(|| read_case(reader, &text, &sets))) {
            Ok(true) => t.ok += 1,
            Ok(false) => t.errors += 1,
            Err(p) => {
                let what = p
                    .downcast_ref::<String>()
                    .cloned()
                    .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
                    .unwrap_or_default();
                save(reader, i, &text, &sets, &format!("panic: {what}"))?;
                t.panics.push((i, what));
            }
        }
        t.slowest_ms = t.slowest_ms.max(began.elapsed().as_secs_f64() * 1e3);
    }
    t.seconds = start.elapsed().as_secs_f64();
    Ok(t)
}

fn failures_dir() -> PathBuf {
    Path::new("target/fuzz/failures").to_path_buf()
}

/// Writes a failing case where a person turns it into a named test.
fn save(reader: &str, case: usize, text: &str, sets: &[String], what: &str) -> Result<(), String> {
    let dir = failures_dir();
    std::fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let path = dir.join(format!("{reader}-{case}.txt"));
    std::fs::write(&path, text).map_err(|e| format!("{}: {e}", path.display()))?;
    let note = format!("{what}\nsets: {sets:?}\n");
    std::fs::write(path.with_extension("why"), note).map_err(|e| format!("{e}"))?;
    eprintln!(
        "fuzz: {reader} case {case}: {what} (input in {})",
        path.display()
    );
    Ok(())
}

/// `cargo xtask fuzz [--cases N | --quick] [READER..]`.
pub fn run(args: &[String]) -> Result<(), String> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    std::env::set_current_dir(&root).map_err(|e| format!("{}: {e}", root.display()))?;
    let mut cases = 1_000_000;
    let mut readers: Vec<&'static str> = Vec::new();
    let mut it = args.iter();
    while let Some(a) = it.next() {
        match a.as_str() {
            "--quick" => cases = 3_000,
            "--cases" => {
                cases = it
                    .next()
                    .and_then(|n| n.parse().ok())
                    .filter(|&n| n > 0)
                    .ok_or("--cases takes a whole number, at least 1")?;
            }
            r => readers.push(
                READERS
                    .iter()
                    .find(|x| **x == r)
                    .ok_or_else(|| format!("unknown reader `{r}`: one of {READERS:?}"))?,
            ),
        }
    }
    if readers.is_empty() {
        readers = READERS.to_vec();
    }
    let data = tryon_io::data_root().ok_or(
        "the data folder was not found: set TRYON_DATA or put ../shared/data beside the repository",
    )?;
    // Panics are counted and saved, not printed one by one.
    std::panic::set_hook(Box::new(|_| {}));
    let threads = std::thread::available_parallelism()
        .map_or(1, |n| n.get())
        .min(readers.len());
    let next = AtomicUsize::new(0);
    let slots: Vec<Mutex<Slot>> = (0..threads)
        .map(|_| {
            Mutex::new(Slot {
                reader: "",
                case: 0,
                text: String::new(),
                sets: Vec::new(),
                since: None,
            })
        })
        .collect();
    let results: Mutex<Vec<(&str, Result<Tally, String>)>> = Mutex::new(Vec::new());
    let done = AtomicUsize::new(0);
    std::thread::scope(|scope| {
        for slot in &slots {
            let (next, results, done, readers, data, root) =
                (&next, &results, &done, &readers, &data, &root);
            scope.spawn(move || {
                loop {
                    let k = next.fetch_add(1, Ordering::SeqCst);
                    let Some(&reader) = readers.get(k) else { break };
                    let r = fuzz_reader(reader, cases, data, root, slot);
                    if let Ok(t) = &r {
                        eprintln!(
                            "fuzz: {reader}: {} cases in {:.0} s, {} accepted, {} refused, {} panics",
                            t.cases, t.seconds, t.ok, t.errors, t.panics.len()
                        );
                    }
                    if let Ok(mut v) = results.lock() {
                        v.push((reader, r));
                    }
                }
                if let Ok(mut s) = slot.lock() {
                    s.since = None;
                }
                done.fetch_add(1, Ordering::SeqCst);
            });
        }
        watch(&slots, &done, threads);
    });
    // Panics print again.
    drop(std::panic::take_hook());
    let results = results.into_inner().map_err(|_| "a fuzz worker failed")?;
    report(&readers, results, cases)
}

/// Stops the run when a case passes [`HANG`], saving it.
fn watch(slots: &[Mutex<Slot>], done: &AtomicUsize, threads: usize) {
    while done.load(Ordering::SeqCst) < threads {
        std::thread::sleep(Duration::from_millis(500));
        for slot in slots {
            let Ok(s) = slot.lock() else { continue };
            if let Some(since) = s.since
                && since.elapsed() > HANG
            {
                let _ = save(s.reader, s.case, &s.text, &s.sets, "hang: over 60 s");
                eprintln!("fuzz: stopped at a hang");
                std::process::exit(1);
            }
        }
    }
}

fn report(
    readers: &[&str],
    mut results: Vec<(&str, Result<Tally, String>)>,
    cases: usize,
) -> Result<(), String> {
    results.sort_by_key(|(r, _)| readers.iter().position(|x| x == r));
    let mut table = String::from(
        "| reader | cases | accepted | refused | panics | hangs | slowest case (ms) | time (s) |\n|---|---|---|---|---|---|---|---|\n",
    );
    let mut failed = Vec::new();
    for (reader, r) in results {
        let t = r?;
        table += &format!(
            "| {reader} | {} | {} | {} | {} | 0 | {:.1} | {:.0} |\n",
            t.cases,
            t.ok,
            t.errors,
            t.panics.len(),
            t.slowest_ms,
            t.seconds
        );
        if let Some((case, what)) = t.panics.first() {
            failed.push(format!("{reader} (case {case}: {what})"));
        }
    }
    std::fs::create_dir_all("target/fuzz").map_err(|e| e.to_string())?;
    std::fs::write("target/fuzz/summary.md", &table).map_err(|e| e.to_string())?;
    println!("{table}");
    println!("{cases} cases per reader; summary in target/fuzz/summary.md");
    if failed.is_empty() {
        Ok(())
    } else {
        Err(format!(
            "panics in {}; inputs under {}",
            failed.join(", "),
            failures_dir().display()
        ))
    }
}
