//! `tryon view SCENE` and `tryon view --demo`: the scene runs live (tryon-pipeline's `Live`) and
//! tryon-view serves it to the page, which grabs and drags the cloth.

use crate::Failure;
use tryon_core::math::Vec3;
use tryon_io::{LiveFrame, ViewHeader};
use tryon_pipeline::live::Live;
use tryon_pipeline::pipeline::Pipeline;

/// The live scene as the server drives it.
struct Scene(Live);

impl tryon_view::live::LiveSim for Scene {
    fn header(&self) -> ViewHeader {
        self.0.header().clone()
    }
    fn step(&mut self) -> LiveFrame {
        self.0.step()
    }
    fn after_frame(&mut self) {
        self.0.judge_last()
    }
    fn grab(&mut self, point: Vec3) -> Result<u32, String> {
        self.0.grab(point).map_err(|e| e.to_string())
    }
    fn drag(&mut self, target: Vec3) {
        self.0.drag(target)
    }
    fn release(&mut self) {
        self.0.release()
    }
}

/// Runs `pipeline` live and serves it until the process is stopped.
pub(crate) fn serve(pipeline: Pipeline, port: u16) -> Result<(), Failure> {
    let name = pipeline.scene.scene.name.clone();
    let live = Box::new(Scene(Live::new(pipeline)));
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
