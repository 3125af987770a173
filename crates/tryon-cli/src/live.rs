//! `tryon view SCENE` and `tryon view --demo`: the scene runs live (tryon-pipeline's `Live`) and
//! tryon-view serves it to the page, which grabs and drags the cloth and draws folds on it (the
//! scene is then built again from its text with the fold appended as a `[[fold]]` table, so a
//! drawn line goes through every check a scene file's does).

use crate::Failure;
use crate::args::BudgetFlags;
use std::path::PathBuf;
use tryon_core::math::Vec3;
use tryon_io::{LiveFrame, ViewHeader};
use tryon_pipeline::live::Live;
use tryon_pipeline::pipeline::{Options, Pipeline};
use tryon_pipeline::scene::Scene;

/// Where a live scene's text came from, to build it again with folds.
pub(crate) struct Source {
    pub(crate) text: String,
    /// The file (or the embedded demo's name) errors name and relative paths start from.
    pub(crate) file: PathBuf,
    pub(crate) from_file: bool,
    pub(crate) sets: Vec<String>,
}

impl Source {
    /// The scene with `folds` (TOML `[[fold]]` tables) appended.
    fn scene(&self, folds: &str) -> Result<Scene, String> {
        let text = format!("{}\n{folds}", self.text);
        let mut s = Scene::parse_with_overrides(&text, &self.file, &self.sets)
            .map_err(|e| e.to_string())?;
        // Drawn lines are carried to the garment the live scene started from. A scene without
        // folds of its own started undraped (`[folding] drape` acts on folded scenes), so its
        // drawn folds go on the garment as placed, where their points lie, not on a drape of it.
        let drawn = folds.matches("[[fold]]").count();
        if drawn > 0 && s.fold.len() == drawn {
            s.folding.drape = 0.0;
        }
        if self.from_file {
            s.source = Some(self.file.clone());
        }
        Ok(s)
    }
}

/// The live scene as the server drives it.
struct LiveScene {
    live: Live,
    source: Source,
    limits: tryon_pipeline::budget::Limits,
    /// The folds drawn so far, as `[[fold]]` tables.
    folds: String,
}

impl tryon_view::live::LiveSim for LiveScene {
    fn header(&self) -> ViewHeader {
        self.live.header().clone()
    }
    fn step(&mut self) -> LiveFrame {
        self.live.step()
    }
    fn after_frame(&mut self) {
        self.live.judge_last()
    }
    fn grab(&mut self, point: Vec3) -> Result<u32, String> {
        self.live.grab(point).map_err(|e| e.to_string())
    }
    fn drag(&mut self, target: Vec3) {
        self.live.drag(target)
    }
    fn release(&mut self) {
        self.live.release()
    }
    fn fold(&mut self, line: &tryon_view::live::FoldLine) -> Result<ViewHeader, String> {
        let drawn: Vec<Vec3> = line.points.iter().map(|p| Vec3::from(*p)).collect();
        // Points drawn close together land on one vertex: each kept once.
        let mut start: Vec<Vec3> = Vec::new();
        for p in self.live.to_start(&drawn) {
            if start.last().is_none_or(|q| (p - q).norm() > 0.002) {
                start.push(p);
            }
        }
        let points: Vec<String> = (start.iter())
            .map(|p| format!("[{}, {}, {}]", p.x, p.y, p.z))
            .collect();
        let table = format!(
            "[[fold]]\nshape = \"{}\"\nheight = {}\npoints = [{}]\n",
            line.shape,
            line.height,
            points.join(", ")
        );
        let folds = format!("{}{table}", self.folds);
        let drawn_error = |e: String| format!("the drawn fold: {e}");
        let scene = self.source.scene(&folds).map_err(drawn_error)?;
        let pipeline = build(scene, &self.source.file, self.limits).map_err(drawn_error)?;
        self.live = Live::new(pipeline);
        self.folds = folds;
        Ok(self.live.header().clone())
    }
}

fn build(
    scene: Scene,
    file: &std::path::Path,
    limits: tryon_pipeline::budget::Limits,
) -> Result<Pipeline, String> {
    let options = Options {
        limits,
        ..Options::default()
    };
    Pipeline::with_options(scene, &options).map_err(|e| match e {
        e @ tryon_pipeline::build::AssembleError::At { .. } => e.to_string(),
        e => format!("{}: {e}", file.display()),
    })
}

/// Runs the scene `source` gives live and serves it until the process is stopped.
pub(crate) fn serve(source: Source, budget: &BudgetFlags, port: u16) -> Result<(), Failure> {
    let scene = source.scene("").map_err(Failure::BadInput)?;
    let name = scene.scene.name.clone();
    let file = source.file.display().to_string();
    let pipeline = crate::assemble(scene, &file, false, budget, None)?;
    let live = Box::new(LiveScene {
        live: Live::new(pipeline),
        source,
        limits: budget.limits(),
        folds: String::new(),
    });
    tryon_view::serve_live(live, port, |addr| {
        println!(
            "tryon view: {name}, live: http://{addr}/ (press on the cloth to drag it; Ctrl-C stops)"
        );
    })
    .map_err(|e| match e {
        e @ tryon_view::ViewError::Listen { .. } => Failure::BadInput(e.to_string()),
        e => Failure::Internal(e.to_string()),
    })
}
