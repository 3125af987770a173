//! A batch manifest (`tryon batch MANIFEST`): jobs listed one by one (`[[job]]`) and cross
//! products (`[[cross]]`: every combination of the values under `vary`, each a `--set`), expanded
//! into a list of jobs in a fixed order, each with its own output folder name.
//!
//! ```toml
//! out = "out/batch"                       # the jobs' folders (relative to this file)
//! [[job]]
//! scene = "embedded:demo"                 # the embedded default, or a scene file
//! frames = 60
//! [[cross]]
//! name = "mh"
//! scene = "../data/scenes/makehuman-dress-walk.toml"
//! set = ["scene.duration=2.0"]
//! [cross.vary]
//! "motion.file" = ["cmu-mocap-bvh/10_04.bvh", "cmu-mocap-bvh/131_01.bvh"]
//! "cloth.solver" = ["vbd", "p1"]
//! ```

use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The scene of the embedded default, as a manifest names it.
pub const EMBEDDED_DEMO: &str = "embedded:demo";
/// At most this many jobs in one manifest (a cross product can grow fast).
const MAX_JOBS: usize = 100_000;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Manifest {
    out: Option<PathBuf>,
    #[serde(default)]
    job: Vec<JobEntry>,
    #[serde(default)]
    cross: Vec<CrossEntry>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct JobEntry {
    scene: String,
    name: Option<String>,
    #[serde(default)]
    set: Vec<String>,
    frames: Option<usize>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct CrossEntry {
    scene: String,
    name: Option<String>,
    #[serde(default)]
    set: Vec<String>,
    frames: Option<usize>,
    /// Each key a scene value (`TABLE.KEY`), each value the list it takes.
    vary: BTreeMap<String, Vec<toml::Value>>,
}

/// One job of a batch: a scene, its overrides and frames, and its folder's name.
#[derive(Clone, Debug, PartialEq)]
pub struct Job {
    pub name: String,
    /// A scene file (resolved against the manifest's folder), or [`EMBEDDED_DEMO`].
    pub scene: PathBuf,
    pub sets: Vec<String>,
    pub frames: Option<usize>,
}

impl Job {
    /// Whether the job runs the embedded default.
    pub fn is_demo(&self) -> bool {
        self.scene == Path::new(EMBEDDED_DEMO)
    }
}

/// A manifest read and expanded.
#[derive(Debug)]
pub struct Batch {
    pub out: PathBuf,
    pub jobs: Vec<Job>,
}

/// Reads the manifest at `path`; errors name the file and the line, key or value at fault.
pub fn read(path: &Path) -> Result<Batch, String> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| format!("{}: cannot read: {e}", path.display()))?;
    parse(&text, path)
}

/// Parses a manifest's `text` (read from `path`, against whose folder relative paths resolve).
pub fn parse(text: &str, path: &Path) -> Result<Batch, String> {
    let file = path.display();
    let m: Manifest = toml::from_str(text).map_err(|e| {
        let at = e.span().map(|s| line_col(text, s.start));
        let at = at.map_or(String::new(), |(l, c)| format!(":{l}:{c}"));
        format!("{file}{at}: {}", e.message())
    })?;
    let base = path.parent().unwrap_or(Path::new(""));
    let resolve = |scene: &str| match scene {
        EMBEDDED_DEMO => PathBuf::from(EMBEDDED_DEMO),
        s => base.join(s),
    };
    let mut jobs = Vec::new();
    for (k, j) in m.job.iter().enumerate() {
        let what = format!("{file}: job {}", k + 1);
        check_frames(&what, j.frames)?;
        let name = j.name.clone().unwrap_or_else(|| default_name(&j.scene));
        jobs.push(Job {
            name: folder_name(&name),
            scene: resolve(&j.scene),
            sets: j.set.clone(),
            frames: j.frames,
        });
    }
    for (k, c) in m.cross.iter().enumerate() {
        let what = format!("{file}: cross {}", k + 1);
        check_frames(&what, c.frames)?;
        let name = c.name.clone().unwrap_or_else(|| default_name(&c.scene));
        for (key, values) in &c.vary {
            if values.is_empty() {
                return Err(format!("{what}: vary.\"{key}\" lists no values"));
            }
            if !key.contains('.') {
                return Err(format!(
                    "{what}: vary.\"{key}\": a key is TABLE.KEY, as --set takes it"
                ));
            }
        }
        let total = c
            .vary
            .values()
            .try_fold(1usize, |n, v| n.checked_mul(v.len()));
        if total.is_none_or(|n| n + jobs.len() > MAX_JOBS) {
            return Err(format!("{what}: more than {MAX_JOBS} jobs"));
        }
        for combo in combinations(&c.vary) {
            let mut sets = c.set.clone();
            let mut label = name.clone();
            for (key, value) in &combo {
                sets.push(format!("{key}={value}"));
                label += &format!("_{}", short(value));
            }
            jobs.push(Job {
                name: folder_name(&label),
                scene: resolve(&c.scene),
                sets,
                frames: c.frames,
            });
        }
    }
    if jobs.is_empty() {
        return Err(format!(
            "{file}: no jobs (add a [[job]] with a scene, or a [[cross]] with a scene and vary)"
        ));
    }
    let mut seen = BTreeMap::new();
    for (k, j) in jobs.iter().enumerate() {
        if let Some(first) = seen.insert(j.name.clone(), k) {
            return Err(format!(
                "{file}: jobs {} and {} both have the folder name `{}` (give them names)",
                first + 1,
                k + 1,
                j.name
            ));
        }
    }
    let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("batch");
    let out = match m.out {
        Some(o) => base.join(o),
        None => Path::new("out").join("batch").join(folder_name(stem)),
    };
    Ok(Batch { out, jobs })
}

fn check_frames(what: &str, frames: Option<usize>) -> Result<(), String> {
    match frames {
        Some(0) => Err(format!("{what}: frames = 0: a run has at least 1 frame")),
        _ => Ok(()),
    }
}

/// Every combination of `vary`'s values, the last key varying fastest.
fn combinations(vary: &BTreeMap<String, Vec<toml::Value>>) -> Vec<Vec<(&str, String)>> {
    let mut out: Vec<Vec<(&str, String)>> = vec![Vec::new()];
    for (key, values) in vary {
        out = (out.iter())
            .flat_map(|c| {
                values.iter().map(move |v| {
                    let mut c = c.clone();
                    c.push((key.as_str(), v.to_string()));
                    c
                })
            })
            .collect();
    }
    out
}

/// A value's part of a job's name: a path's file stem, a string without quotes, a number.
fn short(value: &str) -> String {
    let v = value.trim_matches('"');
    let last = v.rsplit(['/', '\\']).next().unwrap_or(v);
    match last.rsplit_once('.') {
        Some((stem, ext)) if !stem.is_empty() && ext.chars().all(char::is_alphabetic) => {
            stem.to_string()
        }
        _ => last.to_string(),
    }
}

fn default_name(scene: &str) -> String {
    match scene {
        EMBEDDED_DEMO => "demo".into(),
        s => short(s),
    }
}

/// `name` as a folder name: letters, digits, `-`, `_` and `.`, not starting with a dot.
fn folder_name(name: &str) -> String {
    let s: String = (name.chars())
        .map(|c| match c {
            c if c.is_ascii_alphanumeric() || "-_.".contains(c) => c,
            _ => '_',
        })
        .collect();
    match s.trim_start_matches('.') {
        "" => "job".into(),
        t => t.chars().take(120).collect(),
    }
}

fn line_col(text: &str, at: usize) -> (usize, usize) {
    let before = &text[..at.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, col)
}

/// The jobs of shard `index` of `count` (job k goes to shard k mod count).
pub fn shard(jobs: &[Job], (index, count): (usize, usize)) -> Vec<(usize, &Job)> {
    (jobs.iter().enumerate())
        .filter(|(k, _)| k % count == index)
        .collect()
}

/// `--shard I/N`: 0 <= I < N.
pub fn shard_arg(s: &str) -> Result<(usize, usize), String> {
    let bad = || format!("`{s}`: a shard is I/N with 0 <= I < N (e.g. 0/4)");
    let (i, n) = s.split_once('/').ok_or_else(bad)?;
    let (i, n) = (i.trim().parse::<usize>(), n.trim().parse::<usize>());
    match (i, n) {
        (Ok(i), Ok(n)) if i < n => Ok((i, n)),
        _ => Err(bad()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const TEXT: &str = r#"
out = "runs"
[[job]]
scene = "embedded:demo"
frames = 5
[[job]]
scene = "scenes/skirt-walk.toml"
set = ["scene.duration=1.0"]
[[cross]]
name = "mh"
scene = "scenes/makehuman-dress-walk.toml"
set = ["scene.settle=0.1"]
[cross.vary]
"motion.file" = ["cmu-mocap-bvh/10_04.bvh", "cmu-mocap-bvh/131_01.bvh"]
"cloth.solver" = ["vbd", "p1", "xpbd"]
"#;

    #[test]
    fn a_manifest_expands_its_cross_products_in_order() {
        let b = parse(TEXT, Path::new("/m/list.toml")).unwrap();
        assert_eq!(b.out, Path::new("/m/runs"));
        let names: Vec<_> = b.jobs.iter().map(|j| j.name.as_str()).collect();
        assert_eq!(
            names,
            [
                "demo",
                "skirt-walk",
                "mh_vbd_10_04",
                "mh_vbd_131_01",
                "mh_p1_10_04",
                "mh_p1_131_01",
                "mh_xpbd_10_04",
                "mh_xpbd_131_01",
            ]
        );
        assert!(b.jobs[0].is_demo());
        assert_eq!(b.jobs[1].scene, Path::new("/m/scenes/skirt-walk.toml"));
        assert_eq!(
            b.jobs[3].sets,
            [
                "scene.settle=0.1",
                "cloth.solver=\"vbd\"",
                "motion.file=\"cmu-mocap-bvh/131_01.bvh\""
            ]
        );
        assert_eq!((b.jobs[0].frames, b.jobs[1].frames), (Some(5), None));
    }

    #[test]
    fn shards_are_disjoint_and_cover_the_jobs() {
        let b = parse(TEXT, Path::new("list.toml")).unwrap();
        assert_eq!(b.out, Path::new("runs"));
        let plain = parse(&TEXT.replace("out = \"runs\"", ""), Path::new("list.toml"));
        assert_eq!(plain.unwrap().out, Path::new("out/batch/list"));
        for n in 1..=9 {
            let mut all: Vec<usize> = (0..n)
                .flat_map(|i| shard(&b.jobs, (i, n)).into_iter().map(|(k, _)| k))
                .collect();
            all.sort_unstable();
            assert_eq!(all, (0..b.jobs.len()).collect::<Vec<_>>(), "{n} shards");
        }
        assert_eq!(shard_arg("1/4"), Ok((1, 4)));
        for bad in ["4/4", "1", "a/2", "0/0", "-1/3"] {
            assert!(shard_arg(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn bad_manifests_name_the_line_key_or_job() {
        let err = |t: &str| parse(t, Path::new("b.toml")).unwrap_err();
        let e = err("[[job]]\nscene = \"a.toml\"\nframs = 3\n");
        assert!(e.starts_with("b.toml:3:1: unknown field `frams`"), "{e}");
        assert!(err("").contains("no jobs"));
        let e = err("[[job]]\nscene = \"a.toml\"\nframes = 0\n");
        assert!(e.contains("job 1: frames = 0"), "{e}");
        let e = err("[[cross]]\nscene = \"a.toml\"\n[cross.vary]\n\"cloth.solver\" = []\n");
        assert!(
            e.contains("cross 1: vary.\"cloth.solver\" lists no values"),
            "{e}"
        );
        let e = err("[[cross]]\nscene = \"a.toml\"\n[cross.vary]\nsolver = [1]\n");
        assert!(e.contains("a key is TABLE.KEY"), "{e}");
        let e = err("[[job]]\nscene = \"a.toml\"\n[[job]]\nscene = \"x/a.toml\"\n");
        assert!(
            e.contains("jobs 1 and 2 both have the folder name `a`"),
            "{e}"
        );
        let big: String = (0..6)
            .map(|k| format!("\"t.k{k}\" = [{}]\n", ["1"; 10].join(",")))
            .collect();
        let e = err(&format!(
            "[[cross]]\nscene = \"a.toml\"\n[cross.vary]\n{big}"
        ));
        assert!(e.contains("more than 100000 jobs"), "{e}");
    }

    #[test]
    fn folder_names_stay_inside_the_batch_folder() {
        assert_eq!(folder_name("../../etc/passwd"), "_.._etc_passwd");
        assert_eq!(folder_name("..."), "job");
        assert_eq!(folder_name("a b/c"), "a_b_c");
        assert_eq!(short("\"cmu-mocap-bvh/10_04.bvh\""), "10_04");
        assert_eq!(short("0.25"), "0.25");
    }
}
