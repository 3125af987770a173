//! A batch's summary: one row a job of the manifest (every part's, so a shared folder's summary
//! shows the whole batch), from each job's job.json and stats.json, as summary.md (a Markdown
//! table, also printed) and summary.csv, both written atomically into the batch's folder.

use super::{JobRecord, RECORD};
use crate::batch::manifest::Batch;
use std::fmt::Write as _;
use std::path::Path;

const COLUMNS: [&str; 10] = [
    "job",
    "status",
    "wall s",
    "frames",
    "ms/frame",
    "max pen mm",
    "p99 pen mm",
    "max stretch",
    "rollbacks",
    "detached %",
];

/// Writes summary.md and summary.csv for `batch` (from the manifest at `manifest`); returns the
/// Markdown table.
pub(super) fn write(batch: &Batch, manifest: &Path) -> Result<String, String> {
    let rows: Vec<[String; 10]> = (batch.jobs.iter())
        .map(|j| row(&j.name, &batch.out.join(&j.name)))
        .collect();
    let mut md = format!(
        "# Batch {}\n\n| {} |\n|{}\n",
        manifest.display(),
        COLUMNS.join(" | "),
        "---|".repeat(COLUMNS.len())
    );
    for r in &rows {
        let _ = writeln!(md, "| {} |", r.join(" | "));
    }
    let mut csv = COLUMNS.join(",") + "\n";
    for r in &rows {
        let cells: Vec<String> = r.iter().map(|c| csv_cell(c)).collect();
        csv += &(cells.join(",") + "\n");
    }
    std::fs::create_dir_all(&batch.out).map_err(|e| format!("{}: {e}", batch.out.display()))?;
    for (name, text) in [("summary.md", &md), ("summary.csv", &csv)] {
        let path = batch.out.join(name);
        tryon_io::write_atomic(&path, text.as_bytes())
            .map_err(|e| format!("{}: {e}", path.display()))?;
    }
    Ok(md)
}

/// A job's row: its status from job.json, its figures from stats.json when it is done.
fn row(name: &str, dir: &Path) -> [String; 10] {
    let rec: Option<JobRecord> = std::fs::read_to_string(dir.join(RECORD))
        .ok()
        .and_then(|t| serde_json::from_str(&t).ok());
    let status = rec.as_ref().map_or("not run", |r| r.status.as_str());
    let stats: Option<serde_json::Value> = (status == "done")
        .then(|| std::fs::read_to_string(dir.join("stats.json")).ok())
        .flatten()
        .and_then(|t| serde_json::from_str(&t).ok());
    let num = |path: &[&str]| -> Option<f64> {
        let mut v = stats.as_ref()?;
        for k in path {
            v = v.get(k)?;
        }
        v.as_f64()
    };
    let fmt = |v: Option<f64>, scale: f64, digits: usize| {
        v.map_or("-".to_string(), |v| format!("{:.*}", digits, v * scale))
    };
    let frames = num(&["frames"]);
    let ms = match (num(&["loop_s"]), frames) {
        (Some(s), Some(f)) if f > 0.0 => Some(1000.0 * s / f),
        _ => None,
    };
    [
        name.to_string(),
        status.to_string(),
        fmt(rec.as_ref().map(|r| r.wall_s).filter(|&w| w > 0.0), 1.0, 1),
        fmt(frames, 1.0, 0),
        fmt(ms, 1.0, 1),
        fmt(num(&["metrics", "max_penetration_m"]), 1000.0, 1),
        fmt(num(&["metrics", "p99_penetration_m"]), 1000.0, 1),
        fmt(num(&["metrics", "max_stretch"]), 1.0, 3),
        fmt(num(&["metrics", "rollbacks"]), 1.0, 0),
        fmt(num(&["metrics", "detached_share"]), 100.0, 2),
    ]
}

fn csv_cell(c: &str) -> String {
    match c.contains([',', '"', '\n']) {
        true => format!("\"{}\"", c.replace('"', "\"\"")),
        false => c.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_jobs_row_reads_its_record_and_stats() {
        let dir = std::env::temp_dir().join(format!("tryon-summary-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        assert_eq!(row("a", &dir)[1], "not run");
        let rec = r#"{"name":"a","scene":"s","sets":[],"frames":null,"fingerprint":"0",
            "status":"done","exit_code":0,"wall_s":2.25,"error":null}"#;
        std::fs::write(dir.join(RECORD), rec).unwrap();
        let stats = r#"{"frames":40,"loop_s":2.0,"metrics":{"max_penetration_m":0.0012,
            "p99_penetration_m":0.0004,"max_stretch":1.0456,"rollbacks":3,"detached_share":0.0}}"#;
        std::fs::write(dir.join("stats.json"), stats).unwrap();
        let r = row("a", &dir);
        assert_eq!(
            r,
            [
                "a", "done", "2.2", "40", "50.0", "1.2", "0.4", "1.046", "3", "0.00"
            ]
            .map(String::from)
        );
        assert_eq!(csv_cell("x,\"y\""), "\"x,\"\"y\"\"\"");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
