//! The worn shapes on disk (data/kimono, made by `cargo xtask kimono-targets`): one OBJ per
//! wearer, named by the wearer's measurements in centimetres (`158-84-66-92.obj`: height, bust,
//! waist, hip), each with the initial kimono's vertices in order and its triangles; and
//! targets.json, what each dressing reached. Reading checks the topology against the initial
//! kimono's, so a shape made for another layout is an error, not a wrong fit.

use kimono::family::{BASE, Family, TARGETS};
use kimono::{KimonoMesh, Wearer};
use serde::Serialize;
use std::fmt::Write as _;
use std::path::Path;
use thiserror::Error;
use tryon_core::math::{Vec3, is_finite};
use tryon_core::mesh::Face;

/// The file name of `w`'s worn shape.
pub fn shape_name(w: &Wearer) -> String {
    let cm = |x: f64| (x * 100.0).round() as i64;
    format!(
        "{}-{}-{}-{}.obj",
        cm(w.height),
        cm(w.bust),
        cm(w.waist),
        cm(w.hip)
    )
}

/// The wearers of the family, the initial shape's first.
pub fn family_wearers() -> Vec<Wearer> {
    std::iter::once(BASE).chain(TARGETS).collect()
}

/// `positions` over `triangles` as OBJ text, 0.01 mm resolution, with a comment naming the wearer.
pub fn shape_obj(w: &Wearer, positions: &[Vec3], triangles: &[[u32; 3]]) -> String {
    let mut s = format!(
        "# tryon worn kimono (P2 target shape): height {} m, bust {} m, waist {} m, hip {} m\n# made by `cargo xtask kimono-targets`; vertices in the initial kimono's order\n",
        w.height, w.bust, w.waist, w.hip
    );
    for p in positions {
        let _ = writeln!(s, "v {:.5} {:.5} {:.5}", p.x, p.y, p.z);
    }
    for t in triangles {
        let _ = writeln!(s, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    s
}

/// What one dressing reached (a row of targets.json).
#[derive(Clone, Debug, Serialize)]
pub struct ShapeRecord {
    pub file: String,
    /// "initial" or "target".
    pub role: &'static str,
    /// Height, bust, waist, hip (m).
    pub wearer: [f64; 4],
    /// Crossing triangle pairs: folded flat start, inflated, tied.
    pub crossings: [usize; 3],
    pub row_lag_m: [f64; 3],
    pub hem_above_ankle_m: f64,
    pub ms_per_frame: f64,
}

/// Why the worn family could not be read.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum ShapeError {
    #[error("{file}: {source}")]
    Read {
        file: String,
        #[source]
        source: tryon_io::ReadError,
    },
    #[error("{file}: missing; make the worn shapes with `cargo xtask kimono-targets`")]
    Missing { file: String },
    #[error(
        "{file}: {found} vertices and {faces} triangles, not the initial kimono's {expected} and {expected_faces}; remake the worn shapes with `cargo xtask kimono-targets`"
    )]
    Count {
        file: String,
        found: usize,
        expected: usize,
        faces: usize,
        expected_faces: usize,
    },
    #[error(
        "{file}: face {face} is not the initial kimono's; remake the worn shapes with `cargo xtask kimono-targets`"
    )]
    Topology { file: String, face: usize },
    #[error("{file}: vertex {vertex} is not finite")]
    NonFinite { file: String, vertex: usize },
}

/// A shape file's text from folder `dir` (for [`worn_family`]); `None` when it cannot be read.
pub fn dir_shapes(dir: &Path) -> impl Fn(&str) -> Option<String> + '_ {
    move |name| std::fs::read_to_string(dir.join(name)).ok()
}

/// Reads one shape (`text` of `file`) and checks it against `base`.
pub fn parse_shape(text: &str, file: &str, base: &KimonoMesh) -> Result<Vec<Vec3>, ShapeError> {
    let m = tryon_io::obj::parse_obj(text, Path::new(file)).map_err(|source| ShapeError::Read {
        file: file.into(),
        source,
    })?;
    if m.positions.len() != base.positions.len() || m.faces.len() != base.triangles.len() {
        return Err(ShapeError::Count {
            file: file.into(),
            found: m.positions.len(),
            expected: base.positions.len(),
            faces: m.faces.len(),
            expected_faces: base.triangles.len(),
        });
    }
    if let Some(face) = m
        .faces
        .iter()
        .zip(&base.triangles)
        .position(|(f, t)| *f != Face::Tri(*t))
    {
        return Err(ShapeError::Topology {
            file: file.into(),
            face,
        });
    }
    if let Some(vertex) = m.positions.iter().position(|p| !is_finite(p)) {
        return Err(ShapeError::NonFinite {
            file: file.into(),
            vertex,
        });
    }
    Ok(m.positions)
}

/// The worn family: the flat family's mesh and layout with the worn shapes as initial and target
/// positions. `text(name)` gives a shape file's text, or `None` when it is missing.
pub fn worn_family(
    flat: Family,
    text: &dyn Fn(&str) -> Option<String>,
) -> Result<Family, ShapeError> {
    let read = |w: &Wearer| {
        let file = shape_name(w);
        let t = text(&file).ok_or_else(|| ShapeError::Missing { file: file.clone() })?;
        parse_shape(&t, &file, &flat.base)
    };
    let base_positions = read(&BASE)?;
    let targets = TARGETS.iter().map(read).collect::<Result<Vec<_>, _>>()?;
    let mut base = flat.base;
    base.positions = base_positions;
    Ok(Family {
        base,
        targets,
        ..flat
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn small() -> KimonoMesh {
        kimono::family::flat_family().unwrap().base
    }

    #[test]
    fn a_shape_round_trips_through_its_obj_text() {
        let base = small();
        let moved: Vec<Vec3> = base
            .positions
            .iter()
            .map(|p| p + Vec3::new(0.1, -0.2, 0.3))
            .collect();
        let text = shape_obj(&BASE, &moved, &base.triangles);
        let back = parse_shape(&text, "x.obj", &base).unwrap();
        let worst = back
            .iter()
            .zip(&moved)
            .map(|(a, b)| (a - b).norm())
            .fold(0.0, f64::max);
        assert!(worst < 1e-5, "{worst}");
        assert_eq!(shape_name(&BASE), "158-84-66-92.obj");
    }

    #[test]
    fn a_shape_of_another_topology_is_an_error_naming_the_file() {
        let base = small();
        let mut tris = base.triangles.clone();
        tris.swap(0, 1);
        let text = shape_obj(&BASE, &base.positions, &tris);
        let e = parse_shape(&text, "w.obj", &base).unwrap_err();
        assert!(matches!(e, ShapeError::Topology { face: 0, .. }), "{e}");
        let short = shape_obj(&BASE, &base.positions[..10], &[]);
        let e = parse_shape(&short, "w.obj", &base).unwrap_err();
        assert!(
            e.to_string()
                .starts_with("w.obj: 10 vertices and 0 triangles"),
            "{e}"
        );
        let e = worn_family(kimono::family::flat_family().unwrap(), &|_| None).unwrap_err();
        assert_eq!(
            e.to_string(),
            "158-84-66-92.obj: missing; make the worn shapes with `cargo xtask kimono-targets`"
        );
    }
}
