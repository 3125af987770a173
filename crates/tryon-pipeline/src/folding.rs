//! The scene's `[[fold]]` lines made into folds on the dressed garment (P3, the `fold` stage)
//! before the cloth is built: the mesh subdivided along them and shaped, and the bend springs
//! across each line changed once the solver's model exists. Their height is measured again
//! after the run: stats.json's `fold_retention`.

use crate::build::AssembleError;
use crate::scene::Scene;
use crate::wardrobe::Dressed;
use cloth_dyn::bends::BendChange;
use tryon_core::math::{Real, Vec3};
use tryon_core::mesh::PolyMesh;

/// The folds made, as the run measures them.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Folds {
    pub folds: Vec<fold::Fold>,
    /// Edges from a line at which the surrounding surface is taken (`fold::fold_height`).
    pub reach: u32,
    /// The bend springs to change.
    pub bends: Vec<BendChange>,
    /// Each fold's height as shaped, before the simulation (m; `None` when not measurable).
    pub shaped: Vec<Option<Real>>,
    /// Where the cloth starts when the folds were drawn on the draped garment (`[folding]
    /// drape`): the draped shape, folded; the garment mesh is then its modelled shape, folded.
    pub start: Option<Vec<Vec3>>,
}

impl Folds {
    /// Each fold's height in `x` (the garment's vertices) over its drawn height; NaN where
    /// the fold cannot be measured.
    pub fn retention(&self, x: &[Vec3], triangles: &[[u32; 3]]) -> Vec<Real> {
        self.folds
            .iter()
            .map(|f| {
                fold::fold_height(x, triangles, &f.ridge, self.reach, f.drawn)
                    .map_or(Real::NAN, |h| fold::fold_retention(h, f.drawn))
            })
            .collect()
    }
}

/// The fold stage's bend-spring edits as the cloth model's changes.
pub fn bend_changes(edits: &[fold::BendEdit]) -> Vec<BendChange> {
    edits
        .iter()
        .map(|e| BendChange {
            a: e.a,
            b: e.b,
            rest_scale: e.rest_scale,
            stiffness_scale: e.stiffness_scale,
        })
        .collect()
}

/// `dressed` with the scene's folds made; unchanged, with no folds, when it has none.
pub(crate) fn apply(
    scene: &Scene,
    body: &PolyMesh,
    mut dressed: Dressed,
) -> Result<(Dressed, Folds), AssembleError> {
    if scene.fold.is_empty() {
        return Ok((dressed, Folds::default()));
    }
    if dressed.wear.len() > 1 {
        return Err(AssembleError::FoldGarments(dressed.wear.len()));
    }
    let (draped, body) = crate::canvas::drape(scene, body, &dressed)?;
    // The folds are drawn on the garment as it hangs, and carried onto its modelled shape for
    // the rest lengths (the draped garment is stretched where it hangs from).
    let mut on = dressed.mesh.clone();
    if let Some(x) = &draped {
        on.positions.clone_from(x);
    }
    let p = scene.folding.params();
    let placed = |e: AssembleError| e.at_fold(scene);
    let lines = crate::canvas::fold_lines(scene, &body, &on).map_err(placed)?;
    let mut folded = fold::build(&on, &lines, &p).map_err(|e| placed(e.into()))?;
    let bends = bend_changes(&fold::bend_edits(&folded, &p));
    let reach = p.rings + 2;
    let (tris, _) = folded.mesh.triangulate();
    let shaped = folded
        .folds
        .iter()
        .map(|f| fold::fold_height(&folded.mesh.positions, &tris, &f.ridge, reach, f.drawn))
        .collect();
    let n = folded.mesh.positions.len() as u32;
    if let Some(w) = dressed.wear.first_mut() {
        w.particles.end = n;
    }
    let start = draped.map(|_| folded.mesh.positions.clone());
    if let Some(rest) = folded.carried(&on.positions, &dressed.mesh.positions) {
        folded.mesh.positions = rest;
    }
    dressed.mesh = folded.mesh;
    Ok((
        dressed,
        Folds {
            folds: folded.folds,
            reach,
            bends,
            shaped,
            start,
        },
    ))
}
