//! The `tryon` command line's arguments: the subcommands and the flags they share.

use clap::{Parser, Subcommand};
use std::path::PathBuf;
use tryon_pipeline::budget::Limits;

#[derive(Parser, Debug)]
#[command(
    name = "tryon",
    version,
    about = "Real-time cloth simulation and virtual try-on"
)]
pub(crate) struct Cli {
    #[command(subcommand)]
    pub(crate) command: Command,
}

/// How a run is made, shared by `demo` and `run`.
#[derive(clap::Args, Debug)]
pub(crate) struct RunFlags {
    /// Simulate only this many frames, at least 1 (default: the scene's duration times its fps).
    #[arg(long, value_parser = frame_count)]
    pub(crate) frames: Option<usize>,
    /// No progress bar or summary.
    #[arg(long, short)]
    pub(crate) quiet: bool,
    /// Exit with status 3 when the garment left the body (stats.json's detached_share over 0),
    /// after writing every output.
    #[arg(long)]
    pub(crate) strict: bool,
    /// Write a checkpoint into the output folder every N frames (0: none); a killed run goes on
    /// from the last one with `tryon run --resume DIR`.
    #[arg(long, value_name = "N", default_value_t = 100)]
    pub(crate) checkpoint_every: usize,
    #[command(flatten)]
    pub(crate) budget: BudgetFlags,
}

/// The limits a scene's estimate is held against before it runs.
#[derive(clap::Args, Debug)]
pub(crate) struct BudgetFlags {
    /// Raise (or lower) a limit the scene's estimate is held against before it runs, e.g.
    /// `--limit hours=12` (repeatable; keys: frames, particles, fine_vertices, substeps,
    /// memory_gb, hours, glb_gb).
    #[arg(long = "limit", value_name = "KEY=VALUE", value_parser = limit_arg)]
    pub(crate) limits: Vec<String>,
}

impl BudgetFlags {
    pub(crate) fn limits(&self) -> Limits {
        let mut l = Limits::default();
        for a in &self.limits {
            // Checked as the arguments were parsed.
            let _ = l.set(a);
        }
        l
    }
}

/// `--limit`: one `KEY=VALUE` the limits take.
fn limit_arg(s: &str) -> Result<String, String> {
    Limits::default().set(s).map(|()| s.to_string())
}

#[derive(Subcommand, Debug)]
pub(crate) enum Command {
    /// Run the embedded default: the mannequin in a dress, walking (no files needed).
    Demo {
        /// Output directory (scene.glb, preview.png, stats.json).
        #[arg(long, default_value = "out/demo")]
        out: PathBuf,
        #[command(flatten)]
        flags: RunFlags,
        /// Override a value of the embedded scene, e.g. `--set effects.wrinkles=true` (repeatable).
        #[arg(long = "set", value_name = "TABLE.KEY=VALUE")]
        sets: Vec<String>,
    },
    /// Run a scene file, or go on with a killed run (`--resume DIR`).
    Run {
        /// The scene file (TOML; see docs/scenes.md for every key).
        #[arg(required_unless_present = "resume")]
        scene: Option<PathBuf>,
        /// Output directory; default out/<scene name>.
        #[arg(long)]
        out: Option<PathBuf>,
        /// Go on with the run whose output folder is DIR from its last checkpoint, as it was
        /// asked for (scene, overrides, frames, limits); the outputs end as an uninterrupted
        /// run's would.
        #[arg(long, value_name = "DIR", conflicts_with_all = ["scene", "out", "sets", "frames", "limits"])]
        resume: Option<PathBuf>,
        #[command(flatten)]
        flags: RunFlags,
        /// Override a scene value, e.g. `--set effects.body_collision=sdf` (repeatable).
        #[arg(long = "set", value_name = "TABLE.KEY=VALUE")]
        sets: Vec<String>,
    },
    /// Validate a scene file (parse, check values, assemble) without running it, and list the
    /// stages it assembles.
    Check {
        /// The scene file (TOML).
        scene: PathBuf,
        /// Override a scene value before checking, as `run --set` does (repeatable).
        #[arg(long = "set", value_name = "TABLE.KEY=VALUE")]
        sets: Vec<String>,
        #[command(flatten)]
        budget: BudgetFlags,
    },
    /// Write the picture folds are drawn on (P3): the scene's garment as dressed on the body at
    /// the start, framed as the preview frames it, at `[output] preview_width` x `preview_height`.
    /// A `[[fold]] screen` line is given in this picture's pixels.
    Canvas {
        /// The scene file (TOML).
        scene: PathBuf,
        /// The PNG to write; default out/<scene name>/canvas.png.
        #[arg(long)]
        out: Option<PathBuf>,
        /// Override a scene value, as `run --set` does (repeatable).
        #[arg(long = "set", value_name = "TABLE.KEY=VALUE")]
        sets: Vec<String>,
    },
    /// Fit a kimono to body measurements (P2): tailoring dimensions by the standard formulas, the
    /// blend-shape fit per sub-mesh, the print correction. Writes kimono.glb (with the bolt's
    /// print), before.png and after.png (the print before and after its correction) and fit.json
    /// (Table 1: target, initial, fitted value and relative error per dimension).
    Kimono {
        /// Height, m.
        #[arg(long)]
        height: f64,
        /// Bust girth, m.
        #[arg(long)]
        bust: f64,
        /// Waist girth, m.
        #[arg(long)]
        waist: f64,
        /// Hip girth, m.
        #[arg(long)]
        hip: f64,
        /// 裄: back-neck centre to the wrist bone, arm 45° down, m (default: height x 0.4 + 0.02).
        #[arg(long)]
        yuki: Option<f64>,
        /// 袖丈: sleeve length, m (default: height x 0.3).
        #[arg(long)]
        sleeve_length: Option<f64>,
        /// The target shapes blended: laid flat (the default: the bounds hold there), or
        /// worn on mannequins of their sizes (made by `cargo xtask kimono-targets`, built in;
        /// their crumpled back collar fits to 13% and their print is measured on a crumpled
        /// surface).
        #[arg(long, value_enum, default_value_t = TargetShapes::Flat)]
        targets: TargetShapes,
        /// Output directory.
        #[arg(long, default_value = "out/kimono")]
        out: PathBuf,
        /// No table.
        #[arg(long, short)]
        quiet: bool,
    },
    /// Run many scenes in parallel, one job a core, each into its own folder under the
    /// manifest's `out` (see docs/scale.md): a job already done is skipped, an interrupted one
    /// goes on from its checkpoint. Writes summary.md and summary.csv (one row a job).
    Batch {
        /// The manifest (TOML): `[[job]]` entries and `[[cross]]` products of values.
        manifest: PathBuf,
        #[command(flatten)]
        flags: crate::batch::BatchFlags,
    },
    /// Watch a run in the browser: serves it on 127.0.0.1 and prints the page's address. A run's
    /// folder plays the finished run (play, scrub, toggle body, garment and coarse cloth, colour
    /// by stretch, the per-frame figures); a scene file (or `--demo`) runs live, and a press on
    /// the cloth grabs it and drags it while frames stream in. Runs until stopped (Ctrl-C).
    View {
        /// A run's output folder (it holds view.bin), or a scene file to run live.
        #[arg(required_unless_present = "demo")]
        path: Option<PathBuf>,
        /// Run the embedded default scene live.
        #[arg(long, conflicts_with = "path")]
        demo: bool,
        /// Override a value of a live scene, e.g. `--set effects.wrinkles=true` (repeatable).
        #[arg(long = "set", value_name = "TABLE.KEY=VALUE")]
        sets: Vec<String>,
        /// The port (0: any free one).
        #[arg(long, default_value_t = 8737)]
        port: u16,
        #[command(flatten)]
        budget: BudgetFlags,
    },
    /// Summarise an asset: OBJ, BVH or MakeHuman file (counts, joints, frames, fps, bounding box,
    /// likely units).
    Inspect {
        /// The file: .obj, .bvh, .mhskel, .mhw, .target, .mhclo or .proxy.
        file: PathBuf,
    },
}

/// `--frames`: a whole number of frames, at least 1.
fn frame_count(s: &str) -> Result<usize, String> {
    match s.parse::<usize>() {
        Ok(0) => Err("a run has at least 1 frame".into()),
        Ok(n) => Ok(n),
        Err(_) => Err(format!(
            "`{s}` is not a whole number of frames (at least 1)"
        )),
    }
}

/// `tryon kimono --targets`.
#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub(crate) enum TargetShapes {
    Worn,
    Flat,
}
