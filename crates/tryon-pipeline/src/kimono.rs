//! The kimono job (P2, `tryon kimono`): tailoring dimensions from the wearer's measurements, the
//! kimono family built, the blend fit (eq. 1), the print correction (eq. 2), and the outputs: the
//! fitted kimono as GLB with the bolt's print, pictures before and after the print correction,
//! and fit.json with P2's Table 1 (target, initial, fitted, relative error per dimension).

use crate::kimono_wear::store::{ShapeError, worn_family};
pub use kimono::Wearer;
use kimono::family::{Family, flat_family};
use kimono::{Dimensions, FitParams, PrintAspect, PrintParams};
use serde::Serialize;
use std::path::Path;
use std::time::Instant;
use thiserror::Error;
use tryon_core::math::{Real, Vec3};
use tryon_io::preview::{Camera, PreviewMesh, write_png};
use tryon_io::textured::{Texture, TexturedMesh, render_textured, write_textured_glb};

/// Why the kimono job failed: bad measurements (the user's) or an output not written.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum KimonoError {
    #[error(transparent)]
    Measurements(#[from] kimono::TailorError),
    #[error("the kimono family: {0}")]
    Family(#[from] kimono::family::FamilyError),
    #[error("the fit: {0}")]
    Fit(#[from] kimono::FitError),
    #[error("the print correction: {0}")]
    Print(#[from] kimono::PrintError),
    #[error("the worn target shapes: {0}")]
    Shapes(#[from] ShapeError),
    #[error("{0}")]
    Output(String),
}

/// One row of Table 1.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct DimensionRow {
    pub name: &'static str,
    pub target_m: Real,
    pub initial_m: Real,
    pub fitted_m: Real,
    pub rel_error: Real,
    pub initial_rel_error: Real,
}

/// How square the print's squares are (mean aspect, at least 1) and its scale, on the initial
/// kimono, on the fitted one before the print correction and after it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct PrintFigures {
    pub initial: [Real; 2],
    pub before: [Real; 2],
    pub after: [Real; 2],
}

/// What fit.json holds.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FitReport {
    pub wearer: [Real; 6],
    pub dimensions: Vec<DimensionRow>,
    pub mean_rel_error: Real,
    pub max_rel_error: Real,
    pub initial_mean_rel_error: Real,
    /// Per sub-mesh (right sleeve, left sleeve, back, left front, right front, collar), one
    /// weight per target shape.
    pub weights: Vec<Vec<Real>>,
    /// `[mean aspect, scale]` each.
    pub print: PrintFigures,
    pub fit_ms: Real,
    pub print_ms: Real,
    pub vertices: usize,
    pub triangles: usize,
    /// What the targets are: "worn" (the tailored kimonos put on the mannequins of their sizes,
    /// data/kimono) or "flat" (laid flat).
    pub targets: &'static str,
}

/// The fitted kimono and what was measured on it.
#[derive(Clone, Debug)]
pub struct KimonoFit {
    pub dims: Dimensions,
    pub family: Family,
    pub positions: Vec<Vec3>,
    pub uvs: Vec<[Real; 2]>,
    pub report: FitReport,
}

fn aspect(a: PrintAspect) -> [Real; 2] {
    [a.mean, a.scale]
}

/// The target shapes the fit blends.
#[derive(Clone, Copy)]
pub enum Targets<'a> {
    /// The kimonos worn (data/kimono): `text(file name)` gives a shape's OBJ text (the CLI
    /// builds them in; [`crate::kimono_wear::store::dir_shapes`] reads a folder).
    Worn(&'a dyn Fn(&str) -> Option<String>),
    /// The kimonos laid flat.
    Flat,
}

impl std::fmt::Debug for Targets<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl Targets<'_> {
    pub fn name(self) -> &'static str {
        match self {
            Targets::Worn(_) => "worn",
            Targets::Flat => "flat",
        }
    }

    /// The family: the initial shape and the ten targets.
    pub fn family(self) -> Result<Family, KimonoError> {
        let flat = flat_family()?;
        Ok(match self {
            Targets::Flat => flat,
            Targets::Worn(text) => worn_family(flat, text)?,
        })
    }
}

/// Tailors, fits and corrects the print for `w`, blending `targets`.
pub fn fit_kimono(w: &Wearer, targets: Targets) -> Result<KimonoFit, KimonoError> {
    let dims = kimono::tailor(w)?;
    let family = targets.family()?;
    let base = &family.base;
    let t0 = Instant::now();
    let fit = kimono::fit(
        base,
        &base.positions,
        &family.targets,
        &dims,
        &FitParams::default(),
    )?;
    let fit_ms = t0.elapsed().as_secs_f64() * 1e3;
    let t1 = Instant::now();
    let uvs = kimono::correct_print(
        base,
        &base.positions,
        &fit.positions,
        &PrintParams::default(),
    )?;
    let print_ms = t1.elapsed().as_secs_f64() * 1e3;
    let table = dims.table();
    let rows: Vec<DimensionRow> = base
        .dimensions
        .iter()
        .enumerate()
        .filter(|(_, s)| s.in_table)
        .map(|(k, s)| {
            let target = table[s.table_index].1;
            let initial = base.measure(k, &base.positions);
            DimensionRow {
                name: s.name,
                target_m: target,
                initial_m: initial,
                fitted_m: fit.measured[k],
                rel_error: (fit.measured[k] - target).abs() / target,
                initial_rel_error: (initial - target).abs() / target,
            }
        })
        .collect();
    let n = rows.len() as Real;
    let print = PrintFigures {
        initial: aspect(kimono::print_aspect(base, &base.positions, &base.uvs)?),
        before: aspect(kimono::print_aspect(base, &fit.positions, &base.uvs)?),
        after: aspect(kimono::print_aspect(base, &fit.positions, &uvs)?),
    };
    let report = FitReport {
        wearer: [
            w.height,
            w.bust,
            w.waist,
            w.hip,
            dims.yuki,
            dims.sleeve_length,
        ],
        mean_rel_error: rows.iter().map(|r| r.rel_error).sum::<Real>() / n,
        max_rel_error: rows.iter().map(|r| r.rel_error).fold(0.0, Real::max),
        initial_mean_rel_error: rows.iter().map(|r| r.initial_rel_error).sum::<Real>() / n,
        dimensions: rows,
        weights: fit.weights.clone(),
        print,
        fit_ms,
        print_ms,
        vertices: base.positions.len(),
        triangles: base.triangles.len(),
        targets: targets.name(),
    };
    Ok(KimonoFit {
        dims,
        positions: fit.positions,
        uvs,
        family,
        report,
    })
}

/// The print's texture at `px` x `px` texels a tile.
pub fn print_texture(px: usize) -> Texture {
    Texture {
        width: px as u32,
        height: px as u32,
        rgb: kimono::bolt::print_tile(px),
        tile: kimono::bolt::TILE,
    }
}

/// Writes kimono.glb (the fitted kimono with its corrected print), before.png and after.png (the
/// fitted kimono with the print before and after the correction) and fit.json into `dir`.
pub fn write_kimono(dir: &Path, k: &KimonoFit, picture: (u32, u32)) -> Result<(), KimonoError> {
    let out = |e: String| KimonoError::Output(e);
    std::fs::create_dir_all(dir)
        .map_err(|e| out(format!("cannot create {}: {e}", dir.display())))?;
    let base = &k.family.base;
    let tex = print_texture(256);
    // One vertex per UV vertex: the texture's seams split the mesh.
    let at = |x: &[Vec3]| -> Vec<Vec3> { base.uv_vertex.iter().map(|&v| x[v as usize]).collect() };
    let split = at(&k.positions);
    fn mesh<'a>(
        positions: &'a [Vec3],
        uvs: &'a [[Real; 2]],
        tris: &'a [[u32; 3]],
    ) -> TexturedMesh<'a> {
        TexturedMesh {
            positions,
            uvs,
            triangles: tris,
        }
    }
    write_textured_glb(
        &dir.join("kimono.glb"),
        &mesh(&split, &k.uvs, &base.uv_triangles),
        &tex,
        "kimono",
    )
    .map_err(|e| out(e.to_string()))?;
    let camera = Camera::framing(&[PreviewMesh {
        positions: &split,
        triangles: &base.uv_triangles,
        color: [0; 3],
    }]);
    for (name, uvs) in [("before.png", &base.uvs), ("after.png", &k.uvs)] {
        let img = render_textured(
            &mesh(&split, uvs, &base.uv_triangles),
            &tex,
            &camera,
            picture.0,
            picture.1,
        );
        write_png(&dir.join(name), &img).map_err(|e| out(e.to_string()))?;
    }
    let path = dir.join("fit.json");
    tryon_io::write_json(&path, &k.report).map_err(|e| out(format!("{}: {e}", path.display())))?;
    Ok(())
}
