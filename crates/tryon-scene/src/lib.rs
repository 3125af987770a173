//! The scene file: TOML read with every key's position kept, the tables `[body]`, `[garment]` and
//! `[motion]` read as the variant their `kind` names (each owning its keys), then every value
//! checked against what it allows. Errors name the file, the line, the key and what is allowed.
//! The schema is in `schema.rs`, `sections.rs` and `patterns.rs`; `docs.rs` writes its reference,
//! `fixes.rs` lists the keys that each fix one symptom. The defaults are the path the project
//! recommends and measures (docs/decisions, *default path*): a scene file names what differs.

use std::path::{Path, PathBuf};
use thiserror::Error;

mod check;
pub mod docs;
pub mod fixes;
mod folds;
mod patterns;
mod read;
mod schema;
mod sections;

pub use folds::{FoldShape, FoldSpec, FoldingSection, SmoothName};
pub use schema::{
    ArmRaiseSpec, BodySection, BvhSpec, DressSpec, GarmentSection, IntegratorName, KimonoSpec,
    MakeHumanSpec, MannequinBody, MaterialName, MhcloSpec, MotionSection, ObjectBody, RigName,
    SceneSection, ShirtSpec, SkirtSpec, SphereBody, SquareSpec, StillSpec, WalkSpec, WearSpec,
};
pub use sections::{
    BroadPhaseName, ClothSection, CollisionMethod, EffectsSection, OutputSection, P1Section,
    SolverName,
};

/// Why a scene file was rejected.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum SceneError {
    #[error("{}: cannot read: {source}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{}:{line}:{column}: {message}", file.display())]
    Syntax {
        file: PathBuf,
        line: usize,
        column: usize,
        message: String,
    },
    #[error("{}{}: `{key}` = {value}: expected {expected}", file.display(), line.map_or(String::new(), |l| format!(":{l}")))]
    Invalid {
        file: PathBuf,
        /// Line of the key, or of its table when the key was left out.
        line: Option<usize>,
        key: String,
        value: String,
        expected: String,
    },
}

/// A scene as written in its file.
#[derive(Clone, Debug, PartialEq, serde::Serialize, schemars::JsonSchema)]
pub struct Scene {
    /// How fast and how long the scene runs.
    pub scene: SceneSection,
    /// The body; required.
    pub body: BodySection,
    /// The garment; required. With several (`[[garment]]`), the first listed.
    pub garment: GarmentSection,
    /// The garments listed after the first (`[[garment]]`), in order.
    #[serde(skip)]
    #[schemars(skip)]
    pub more_garments: Vec<GarmentSection>,
    /// How each garment is worn (layer, material), one per garment, the first's first.
    #[serde(skip)]
    #[schemars(skip)]
    pub wear: Vec<WearSpec>,
    /// The motion; the body holds still when absent.
    pub motion: MotionSection,
    /// Material and solver settings.
    pub cloth: ClothSection,
    /// Which effects act.
    pub effects: EffectsSection,
    /// What to write.
    pub output: OutputSection,
    /// How the folds are shaped and held.
    pub folding: FoldingSection,
    /// Folds drawn on the garment (`[[fold]]`, P3), in order.
    #[serde(skip)]
    #[schemars(skip)]
    pub fold: Vec<FoldSpec>,
    /// The file the scene was read from (asset paths are resolved beside it).
    #[serde(skip)]
    #[schemars(skip)]
    pub source: Option<PathBuf>,
}

/// Farthest a body vertex may move between two collider updates unless a scene says otherwise
/// (m). Only the body near the cloth counts. A walk at 30 fps is left at one update; 131_01's
/// lunges and arm swings (up to 30 cm a frame) get up to four. Smaller steps were tried: 4 cm
/// splits the demo's walk too and doubles its cloth time (every sub-frame pays the strap's
/// stretch-guard retries: 49 -> 333) with no gain in penetration.
pub const BODY_STEP: tryon_core::math::Real = 0.08;

/// The embedded default scene (`tryon demo`): the mannequin in the dress, walking.
pub const DEMO_SCENE: &str = include_str!("../../../data/scenes/demo-dress-walk.toml");

/// Line (1-based) and column of a byte offset.
pub(crate) fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let col = before.len() - before.rfind('\n').map_or(0, |i| i + 1) + 1;
    (line, col)
}

/// Line of `key` inside `[table]` (or of the table header when the key is absent).
pub fn line_of(text: &str, table: &str, key: &str) -> Option<usize> {
    line_of_nth(text, table, 0, key)
}

/// Line of a key as errors name it (`table.key`, or `table[n].key` in an array of tables).
fn line_in(text: &str, key: &str) -> Option<usize> {
    let (table, name) = key.rsplit_once('.')?;
    match table.split_once('[') {
        Some((t, n)) => line_of_nth(text, t, n.trim_end_matches(']').parse().ok()?, name),
        None => line_of(text, table, name),
    }
}

/// Line of `key` inside the `nth` (from 0) `[[table]]` of an array of tables, or inside
/// `[table]` (`nth` = 0); the table header's line when the key is absent.
pub fn line_of_nth(text: &str, table: &str, nth: usize, key: &str) -> Option<usize> {
    let mut current = String::new();
    let mut header = None;
    let mut seen = 0;
    for (i, raw) in text.lines().enumerate() {
        let l = raw.trim();
        if let Some(name) = l.strip_prefix('[').and_then(|s| s.strip_suffix(']')) {
            let name = name.trim();
            let array = name.strip_prefix('[').and_then(|s| s.strip_suffix(']'));
            current = array.unwrap_or(name).trim().to_string();
            if current == table {
                if array.is_some() {
                    seen += 1;
                }
                if seen.max(1) - 1 == nth && header.is_none() {
                    header = Some(i + 1);
                } else {
                    current.clear();
                }
            }
            continue;
        }
        if current == table
            && let Some((k, _)) = l.split_once('=')
            && k.trim() == key
        {
            return Some(i + 1);
        }
    }
    header
}

/// One garment of a scene and how it is worn.
#[derive(Clone, Copy, Debug)]
pub struct Worn<'a> {
    /// Its place in the scene's list of garments.
    pub index: usize,
    pub garment: &'a GarmentSection,
    pub wear: &'a WearSpec,
    /// Its layer: `wear.layer`, else its index.
    pub layer: u32,
}

impl Scene {
    /// The scene's name made a folder name (the default output folder is `out/` and this): every
    /// character but letters, digits, `-`, `_` and `.` becomes `_`, leading dots are dropped and
    /// it is cut at 100 characters, so a name is never a path (`"/abs/dir"`, `"../../x"`); an
    /// empty result is `"scene"`.
    pub fn folder_name(&self) -> String {
        let kept: String = self
            .scene
            .name
            .chars()
            .map(
                |c| match c.is_alphanumeric() || matches!(c, '-' | '_' | '.') {
                    true => c,
                    false => '_',
                },
            )
            .skip_while(|&c| c == '.')
            .take(100)
            .collect();
        match kept.is_empty() {
            true => "scene".into(),
            false => kept,
        }
    }

    /// Every garment in the order listed, with how it is worn.
    pub fn garments(&self) -> Vec<Worn<'_>> {
        static PLAIN: std::sync::OnceLock<WearSpec> = std::sync::OnceLock::new();
        let plain = PLAIN.get_or_init(WearSpec::default);
        std::iter::once(&self.garment)
            .chain(&self.more_garments)
            .enumerate()
            .map(|(index, garment)| {
                let wear = self.wear.get(index).unwrap_or(plain);
                Worn {
                    index,
                    garment,
                    wear,
                    layer: wear.layer.unwrap_or(index as u32),
                }
            })
            .collect()
    }

    /// Parses and checks a scene; `file` names it in errors.
    pub fn parse(text: &str, file: &Path) -> Result<Scene, SceneError> {
        let scene = read::scene(text, file)?;
        scene.check(text, file)?;
        Ok(scene)
    }

    /// Reads, parses and checks a scene file.
    pub fn load(path: &Path) -> Result<Scene, SceneError> {
        let text = std::fs::read_to_string(path).map_err(|source| SceneError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        let mut scene = Scene::parse(&text, path)?;
        scene.source = Some(path.to_path_buf());
        Ok(scene)
    }

    /// Parses a scene with `table.key=value` overrides applied first (the value in TOML syntax; a
    /// bare word is taken as a string), as `tryon run --set` does. Errors name the override.
    pub fn parse_with_overrides(
        text: &str,
        file: &Path,
        sets: &[String],
    ) -> Result<Scene, SceneError> {
        if sets.is_empty() {
            return Scene::parse(text, file);
        }
        let mut table: toml::Table = toml::from_str(text).map_err(|e| {
            let (line, column) = e.span().map_or((0, 0), |s| line_col(text, s.start));
            SceneError::Syntax {
                file: file.to_path_buf(),
                line,
                column,
                message: e.message().to_string(),
            }
        })?;
        for set in sets {
            let bad = |expected: &str| SceneError::Invalid {
                file: file.to_path_buf(),
                line: None,
                key: "--set".into(),
                value: set.clone(),
                expected: expected.into(),
            };
            let (key, value) = set.split_once('=').ok_or_else(|| bad("table.key=value"))?;
            let (t, k) = key
                .trim()
                .split_once('.')
                .ok_or_else(|| bad("table.key=value (for example effects.refine=2)"))?;
            let value = value.trim();
            let parsed = toml::from_str::<toml::Table>(&format!("v = {value}"))
                .ok()
                .and_then(|mut v| v.remove("v"))
                .unwrap_or_else(|| toml::Value::String(value.to_string()));
            // `cloth.vbd.substep`: every part but the last names a table, made if absent.
            let mut path: Vec<&str> = k.split('.').map(str::trim).collect();
            let last = path.pop().unwrap_or_default();
            let mut section = &mut table;
            for (depth, part) in std::iter::once(t).chain(path).enumerate() {
                let entry = section
                    .entry(part.to_string())
                    .or_insert_with(|| toml::Value::Table(toml::Table::new()));
                section = match entry {
                    toml::Value::Table(s) => s,
                    toml::Value::Array(_) if depth == 0 => {
                        return Err(bad(&format!(
                            "a key of a single table: the [[{t}]] list is set in the scene file"
                        )));
                    }
                    _ => return Err(bad("a key inside a [table]")),
                };
            }
            section.insert(last.to_string(), parsed);
        }
        let merged = toml::to_string(&table).map_err(|e| SceneError::Syntax {
            file: file.to_path_buf(),
            line: 0,
            column: 0,
            message: e.to_string(),
        })?;
        let named = PathBuf::from(format!(
            "{} (with --set {})",
            file.display(),
            sets.join(" ")
        ));
        // The merged text is the table written anew: its lines are not the file's. Name the
        // file's own line of a key, and none for a key an override set.
        Scene::parse(&merged, &named).map_err(|e| match e {
            SceneError::Invalid {
                file,
                key,
                value,
                expected,
                ..
            } => {
                let overridden = sets
                    .iter()
                    .any(|s| s.split_once('=').is_some_and(|(k, _)| k.trim() == key));
                let line = match overridden {
                    true => None,
                    false => line_in(text, &key),
                };
                SceneError::Invalid {
                    file,
                    line,
                    key,
                    value,
                    expected,
                }
            }
            other => other,
        })
    }

    /// Reads a scene file and applies `table.key=value` overrides.
    pub fn load_with_overrides(path: &Path, sets: &[String]) -> Result<Scene, SceneError> {
        let text = std::fs::read_to_string(path).map_err(|source| SceneError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        let mut scene = Scene::parse_with_overrides(&text, path, sets)?;
        scene.source = Some(path.to_path_buf());
        Ok(scene)
    }

    /// The embedded demo scene.
    pub fn demo() -> Scene {
        Scene::parse(DEMO_SCENE, Path::new("<embedded demo-dress-walk.toml>"))
            .unwrap_or_else(|e| unreachable!("the embedded demo scene is checked by tests: {e}"))
    }
}

#[cfg(test)]
mod tests;
