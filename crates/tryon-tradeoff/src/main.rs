//! `tryon-tradeoff` (run by `cargo xtask tradeoff [--quick]`): what accuracy costs in time.
//!
//! Sweeps, each point a real run of the pipeline or the solver:
//! (a) every collider and resolution on the drape, demo and MakeHuman scenes: penetration by the
//!     exact referee (max, p99, share deeper than 1 mm) against ms per frame;
//! (b) every integrator and step on the drape: error against RK4 at a tiny step, against ms per
//!     frame; and the largest stable step against stretch stiffness;
//! (c) refinement level 0..4 on the demo: fine vertices, ms, deviation from a level-6 surface;
//! (d) wrinkles off and on: length restoration against ms;
//! (e) P4's scene: fine penetration with and without the depth-map correction, and what running
//!     the coarse step and the fine correction at the same time gains;
//! (f) the stretch guard on the demo walk (P1's solver);
//! (g) the garment solvers (P1, XPBD, VBD) on every scene.
//!
//! Writes `report.md`, `results.json`-like tables and SVG plots (Pareto fronts marked) under the
//! output folder, and a short summary (`--summary FILE`). `--quick` runs few frames and checks
//! that every curve has points.

mod plot;
mod sweeps;

use clap::Parser;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Parser, Debug)]
#[command(name = "tryon-tradeoff", about = "What accuracy costs in time")]
struct Args {
    /// Few frames and settings: checks that every curve has points (CI).
    #[arg(long)]
    quick: bool,
    /// Output folder for report.md and the SVG plots.
    #[arg(long, default_value = "target/tradeoff")]
    out: PathBuf,
    /// Also write the short summary here (e.g. docs/tradeoff.md).
    #[arg(long)]
    summary: Option<PathBuf>,
}

fn main() -> ExitCode {
    let args = Args::parse();
    match sweeps::run_all(args.quick, &args.out, args.summary.as_deref()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("tradeoff: {e}");
            ExitCode::FAILURE
        }
    }
}
