//! Reading a scene document with every key's position kept: each table is deserialized from the
//! parsed document itself, so an error points at the offending key or value; a table with a
//! `kind` is read as the variant the kind names, which owns its keys.

use super::{FoldSpec, Scene, SceneError, line_col};
use serde::Deserialize;
use serde::de::DeserializeOwned;
use std::path::Path;
use toml::Spanned;
use toml::de::{DeString, DeTable, DeValue, Deserializer};

/// The tables a scene may have.
const TABLES: [&str; 9] = [
    "scene", "body", "garment", "motion", "cloth", "effects", "output", "folding", "fold",
];

/// A deserialization error at its place in `text`, with the key named when the message does not.
fn located(e: toml::de::Error, text: &str, file: &Path, table: &str) -> SceneError {
    let (line, column) = e.span().map_or((0, 0), |s| line_col(text, s.start));
    let mut message = e.message().to_string();
    // A table inside the table (`[cloth.vbd]`) names its keys by its whole path.
    let header = text
        .lines()
        .take(line)
        .filter_map(|l| {
            let l = l.split('#').next().unwrap_or("").trim();
            l.strip_prefix('[').and_then(|s| s.strip_suffix(']'))
        })
        .last()
        .map(|h| h.trim_matches(['[', ']']).trim().to_string());
    let table = match header {
        Some(h) if h.starts_with(&format!("{table}.")) => h,
        _ => table.to_string(),
    };
    let table = table.as_str();
    let key = text
        .lines()
        .nth(line.wrapping_sub(1))
        .and_then(|l| l.split_once('='))
        .map(|(k, _)| k.trim().to_string())
        .filter(|k| !k.is_empty() && !k.starts_with('['));
    if let Some(k) = key {
        message = format!("`{table}.{k}`: {message}");
        // A key of another kind of this table: say which kinds take it.
        let owners: Vec<String> = super::docs::keys()
            .into_iter()
            .filter(|x| x.table == table && x.name == k)
            .filter_map(|x| x.kind.map(|kind| format!("kind = \"{kind}\"")))
            .collect();
        if message.contains("unknown field") && !owners.is_empty() {
            message = format!("{message} (only {} takes it)", owners.join(" or "));
        }
    }
    SceneError::Syntax {
        file: file.to_path_buf(),
        line,
        column,
        message,
    }
}

fn invalid(
    text: &str,
    file: &Path,
    at: usize,
    key: &str,
    value: String,
    expected: String,
) -> SceneError {
    SceneError::Invalid {
        file: file.to_path_buf(),
        line: Some(line_col(text, at).0),
        key: key.to_string(),
        value,
        expected,
    }
}

/// The table `value` holds, with its span, or an error naming `name`.
fn table_of<'i>(
    text: &str,
    file: &Path,
    name: &str,
    value: Spanned<DeValue<'i>>,
) -> Result<(std::ops::Range<usize>, DeTable<'i>), SceneError> {
    let span = value.span();
    match value.into_inner() {
        DeValue::Table(t) => Ok((span, t)),
        _ => Err(invalid(
            text,
            file,
            span.start,
            name,
            "a value".into(),
            format!("a [{name}] table"),
        )),
    }
}

/// Keys that moved into a table of their own: (table, old key, new table, new key).
pub(super) const MOVED: [(&str, &str, &str, &str); 22] = [
    ("cloth", "integrator", "cloth.p1", "integrator"),
    ("cloth", "substep", "cloth.p1", "substep"),
    ("cloth", "max_strain", "cloth.p1", "max_strain"),
    (
        "cloth",
        "strain_iterations",
        "cloth.p1",
        "strain_iterations",
    ),
    ("cloth", "stretch_guard", "cloth.p1", "stretch_guard"),
    ("cloth", "xpbd_substep", "cloth.xpbd", "substep"),
    ("cloth", "xpbd_iterations", "cloth.xpbd", "iterations"),
    (
        "cloth",
        "stretch_compliance",
        "cloth.xpbd",
        "stretch_compliance",
    ),
    ("cloth", "bend_compliance", "cloth.xpbd", "bend_compliance"),
    ("cloth", "static_friction", "cloth.xpbd", "static_friction"),
    ("cloth", "xpbd_bending", "cloth.xpbd", "bending"),
    ("cloth", "vbd_substep", "cloth.vbd", "substep"),
    ("cloth", "vbd_iterations", "cloth.vbd", "iterations"),
    ("cloth", "vbd_stretch", "cloth.vbd", "stretch"),
    ("cloth", "vbd_flexion", "cloth.vbd", "flexion"),
    ("cloth", "vbd_dihedral", "cloth.vbd", "dihedral"),
    ("cloth", "vbd_contact", "cloth.vbd", "contact"),
    ("cloth", "vbd_swept", "cloth.vbd", "swept"),
    ("cloth", "vbd_limit", "cloth.vbd", "limit"),
    ("cloth", "vbd_limit_passes", "cloth.vbd", "limit_passes"),
    ("effects", "sdf_resolution", "effects.sdf", "resolution"),
    (
        "effects",
        "depth_resolution",
        "effects.depth_maps",
        "resolution",
    ),
];

/// What a retired key did, and what does its job now.
const POKES_RETIRED: &str = "nothing: the coarse cloth's pokes were retired (off everywhere); \
    `[effects] fine_pokes` lifts the output surface over narrow body features \
    (docs/decisions, *fine pokes*)";

/// Keys that were retired: (table, the key's path inside it, what is allowed instead).
pub(super) const RETIRED: [(&str, &[&str], &str); 2] = [
    ("cloth", &["vbd", "pokes"], POKES_RETIRED),
    ("cloth", &["vbd_pokes"], POKES_RETIRED),
];

/// An error for a retired key of `table` (the scene's table `name`).
fn retired(text: &str, file: &Path, name: &str, table: &DeTable<'_>) -> Result<(), SceneError> {
    for (_, path, instead) in RETIRED.iter().filter(|r| r.0 == name) {
        let mut at = table;
        for (depth, part) in path.iter().enumerate() {
            let Some((key, value)) = at.iter().find(|(k, _)| k.get_ref().as_ref() == *part) else {
                break;
            };
            if depth + 1 == path.len() {
                return Err(invalid(
                    text,
                    file,
                    key.span().start,
                    &format!("{name}.{}", path.join(".")),
                    "a retired key".into(),
                    instead.to_string(),
                ));
            }
            match value.get_ref() {
                DeValue::Table(t) => at = t,
                _ => break,
            }
        }
    }
    Ok(())
}

/// An error naming the new place of a key that moved into a table of its own.
fn moved(text: &str, file: &Path, name: &str, table: &DeTable<'_>) -> Result<(), SceneError> {
    retired(text, file, name, table)?;
    for key in table.keys() {
        let k: &str = key.get_ref().as_ref();
        if let Some((_, _, to, new)) = MOVED.iter().find(|m| m.0 == name && m.1 == k) {
            return Err(invalid(
                text,
                file,
                key.span().start,
                &format!("{name}.{k}"),
                "a key of the old flat table".into(),
                format!("`{new}` in the [{to}] table (`--set {to}.{new}=...`)"),
            ));
        }
    }
    Ok(())
}

/// A plain table.
fn plain<T: DeserializeOwned>(
    text: &str,
    file: &Path,
    name: &str,
    value: Spanned<DeValue<'_>>,
) -> Result<T, SceneError> {
    let (span, table) = table_of(text, file, name, value)?;
    moved(text, file, name, &table)?;
    T::deserialize(Deserializer::from(Spanned::new(span, table)))
        .map_err(|e| located(e, text, file, name))
}

/// A table whose `kind` names the variant of `T` that reads the rest of it.
fn tagged<T: DeserializeOwned + schemars::JsonSchema>(
    text: &str,
    file: &Path,
    name: &str,
    value: Spanned<DeValue<'_>>,
) -> Result<T, SceneError> {
    let kinds = super::docs::variant_names::<T>()
        .iter()
        .map(|k| format!("\"{k}\""))
        .collect::<Vec<_>>()
        .join(", ");
    let (span, mut table) = table_of(text, file, name, value)?;
    let key = table.keys().find(|k| k.get_ref() == "kind").cloned();
    let Some(kind) = key.and_then(|k| table.remove(&k)) else {
        return Err(invalid(
            text,
            file,
            span.start,
            &format!("{name}.kind"),
            "nothing".into(),
            format!("one of {kinds}"),
        ));
    };
    let kind_span = kind.span();
    let DeValue::String(kind) = kind.into_inner() else {
        return Err(invalid(
            text,
            file,
            kind_span.start,
            &format!("{name}.kind"),
            "a value".into(),
            format!("one of {kinds}"),
        ));
    };
    let mut outer = DeTable::default();
    outer.insert(
        Spanned::new(kind_span, kind),
        Spanned::new(span.clone(), DeValue::Table(table)),
    );
    T::deserialize(Deserializer::from(Spanned::new(span, outer)))
        .map_err(|e| located(e, text, file, name))
}

/// One garment's table: its wear keys (`WearSpec`) taken out and read, the rest read as the kind
/// it names.
fn worn(
    text: &str,
    file: &Path,
    value: Spanned<DeValue<'_>>,
) -> Result<(super::GarmentSection, super::WearSpec), SceneError> {
    let (span, mut table) = table_of(text, file, "garment", value)?;
    let mut wear = DeTable::default();
    let keys: Vec<_> = table
        .keys()
        .filter(|k| super::WearSpec::KEYS.contains(&k.get_ref().as_ref()))
        .cloned()
        .collect();
    for k in keys {
        if let Some(v) = table.remove(&k) {
            wear.insert(k, v);
        }
    }
    let spec = super::WearSpec::deserialize(Deserializer::from(Spanned::new(span.clone(), wear)))
        .map_err(|e| located(e, text, file, "garment"))?;
    let garment = tagged(
        text,
        file,
        "garment",
        Spanned::new(span, DeValue::Table(table)),
    )?;
    Ok((garment, spec))
}

/// The garments of `[garment]` (one) or `[[garment]]` (one or more), in order.
fn garments(
    text: &str,
    file: &Path,
    value: Spanned<DeValue<'_>>,
) -> Result<Vec<(super::GarmentSection, super::WearSpec)>, SceneError> {
    let span = value.span();
    match value.into_inner() {
        DeValue::Array(items) if items.is_empty() => Err(invalid(
            text,
            file,
            span.start,
            "garment",
            "an empty list".into(),
            "one or more [[garment]] tables".into(),
        )),
        DeValue::Array(items) if items.len() > MAX_GARMENTS => Err(invalid(
            text,
            file,
            span.start,
            "garment",
            format!("{} garments", items.len()),
            format!("at most {MAX_GARMENTS} [[garment]] tables"),
        )),
        DeValue::Array(items) => items.into_iter().map(|v| worn(text, file, v)).collect(),
        other => Ok(vec![worn(text, file, Spanned::new(span, other))?]),
    }
}

/// Most garments one scene wears.
pub const MAX_GARMENTS: usize = 8;

/// Reads a scene (not yet checked).
pub(super) fn scene(text: &str, file: &Path) -> Result<Scene, SceneError> {
    let doc = DeTable::parse(text).map_err(|e| located(e, text, file, ""))?;
    let mut s = Scene {
        scene: Default::default(),
        body: super::BodySection::Sphere(Default::default()),
        garment: super::GarmentSection::Square(Default::default()),
        more_garments: Vec::new(),
        wear: Vec::new(),
        motion: Default::default(),
        cloth: Default::default(),
        effects: Default::default(),
        output: Default::default(),
        folding: Default::default(),
        fold: Vec::new(),
        source: None,
    };
    let (mut body, mut garment) = (false, false);
    for (key, value) in doc.into_inner() {
        let name: &DeString = key.get_ref();
        match name.as_ref() {
            "scene" => s.scene = plain(text, file, "scene", value)?,
            "body" => (s.body, body) = (tagged(text, file, "body", value)?, true),
            "garment" => {
                let (worn, wear): (Vec<_>, Vec<_>) =
                    garments(text, file, value)?.into_iter().unzip();
                let mut worn = worn.into_iter();
                if let Some(first) = worn.next() {
                    (s.garment, garment) = (first, true);
                }
                (s.more_garments, s.wear) = (worn.collect(), wear);
            }
            "motion" => s.motion = tagged(text, file, "motion", value)?,
            "cloth" => s.cloth = plain(text, file, "cloth", value)?,
            "effects" => s.effects = plain(text, file, "effects", value)?,
            "output" => s.output = plain(text, file, "output", value)?,
            "folding" => s.folding = plain(text, file, "folding", value)?,
            "fold" => {
                let span = value.span();
                // Each fold remembers its line, for the errors only assembling can find.
                let fold = |v: Spanned<DeValue<'_>>| {
                    let line = line_col(text, v.span().start).0;
                    plain(text, file, "fold", v).map(|f: FoldSpec| FoldSpec {
                        line: Some(line),
                        ..f
                    })
                };
                s.fold = match value.into_inner() {
                    DeValue::Array(items) => {
                        items.into_iter().map(fold).collect::<Result<_, _>>()?
                    }
                    other => vec![fold(Spanned::new(span, other))?],
                };
            }
            other => {
                let tables = TABLES.map(|t| format!("[{t}]")).join(", ");
                return Err(invalid(
                    text,
                    file,
                    key.span().start,
                    other,
                    "a table".into(),
                    format!("one of the tables {tables}"),
                ));
            }
        }
    }
    for (given, name) in [(body, "body"), (garment, "garment")] {
        if !given {
            return Err(SceneError::Invalid {
                file: file.to_path_buf(),
                line: None,
                key: name.into(),
                value: "nothing".into(),
                expected: format!("a [{name}] table with a kind"),
            });
        }
    }
    Ok(s)
}
