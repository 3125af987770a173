//! The scene's checks: every value against the range its schema gives (the same list
//! docs/scenes.md is written from), then what one key's value asks of another (a sheet material
//! needs a square garment, an object body holds still, ...). Errors name the file, the line, the
//! key and what is allowed.

use super::*;
use tryon_core::math::Real;
use tryon_core::measure::MeasureError;

/// An error at `table.key` of `text`.
fn bad(
    text: &str,
    file: &Path,
    table: &str,
    key: &str,
    value: String,
    expected: &str,
) -> SceneError {
    SceneError::Invalid {
        file: file.to_path_buf(),
        line: line_of(text, table, key),
        key: format!("{table}.{key}"),
        value,
        expected: expected.to_string(),
    }
}

/// Every key `keys` holds that `which` takes, against its range in `v` (a scene as TOML), errors
/// naming the `nth` `[[garment]]`'s line for garment keys.
fn within_ranges(
    keys: &[docs::Key],
    v: &toml::Value,
    which: impl Fn(&docs::Key) -> bool,
    (text, file, nth): (&str, &Path, usize),
) -> Result<(), SceneError> {
    for k in keys.iter().filter(|k| which(k)) {
        let Some(table) = k.table.split('.').try_fold(v, |v, part| v.get(part)) else {
            continue;
        };
        let holder = match &k.kind {
            Some(kind) => table.get(kind.as_str()),
            None => Some(table),
        };
        let Some(value) = holder.and_then(|h| h.get(k.name.as_str())) else {
            continue;
        };
        let ok = match value {
            toml::Value::Array(items) => {
                k.len.is_none_or(|n| items.len() == n)
                    && (!k.per_item
                        || items
                            .iter()
                            .all(|x| number(x).is_some_and(|x| within(k, x))))
            }
            v => number(v).is_none_or(|x| within(k, x)),
        };
        if !ok {
            let shown = match value {
                toml::Value::Array(_) => value.to_string(),
                v => number(v).map_or(v.to_string(), |x| x.to_string()),
            };
            let expected = if k.len.is_some() {
                k.allowed()
            } else if k.min.is_none() && k.max.is_none() {
                // Its own rule (checked after) says more; a non-finite value fails here first.
                "a finite number".to_string()
            } else {
                format!("a number in {}", k.allowed())
            };
            return Err(SceneError::Invalid {
                file: file.to_path_buf(),
                line: line_of_nth(text, &k.table, nth, &k.name),
                key: match nth {
                    0 => format!("{}.{}", k.table, k.name),
                    n => format!("{}[{n}].{}", k.table, k.name),
                },
                value: shown,
                expected,
            });
        }
    }
    Ok(())
}

/// Every key but the garments' wear keys (read per garment) and the folds' (read per fold).
fn true_key(k: &docs::Key) -> bool {
    !(k.table == "garment" && k.kind.is_none()) && k.table != "fold"
}

/// Whether `x` lies in the key's range.
fn within(k: &docs::Key, x: f64) -> bool {
    x.is_finite() && k.min.is_none_or(|a| x >= a) && k.max.is_none_or(|b| x <= b)
}

fn number(v: &toml::Value) -> Option<f64> {
    v.as_float().or_else(|| v.as_integer().map(|i| i as f64))
}

impl Scene {
    pub(super) fn check(&self, text: &str, file: &Path) -> Result<(), SceneError> {
        self.check_ranges(text, file)?;
        self.check_values(text, file)?;
        self.check_fold_lines(text, file)?;
        self.check_combinations(text, file)
    }

    /// Every key against the range and length its schema gives, every garment's too.
    fn check_ranges(&self, text: &str, file: &Path) -> Result<(), SceneError> {
        let syntax = |e: toml::ser::Error| SceneError::Syntax {
            file: file.to_path_buf(),
            line: 0,
            column: 0,
            message: e.to_string(),
        };
        let v = toml::Value::try_from(self).map_err(syntax)?;
        let keys = docs::keys();
        within_ranges(&keys, &v, true_key, (text, file, 0))?;
        for (n, g) in self.more_garments.iter().enumerate() {
            let mut t = toml::Table::new();
            t.insert("garment".into(), toml::Value::try_from(g).map_err(syntax)?);
            let garment = |k: &docs::Key| k.table == "garment" && k.kind.is_some();
            within_ranges(&keys, &toml::Value::Table(t), garment, (text, file, n + 1))?;
        }
        for (n, f) in self.fold.iter().enumerate() {
            let mut t = toml::Table::new();
            t.insert("fold".into(), toml::Value::try_from(f).map_err(syntax)?);
            let fold = |k: &docs::Key| k.table == "fold";
            within_ranges(&keys, &toml::Value::Table(t), fold, (text, file, n))?;
        }
        for (n, w) in self.wear.iter().enumerate() {
            let mut t = toml::Table::new();
            t.insert("garment".into(), toml::Value::try_from(w).map_err(syntax)?);
            let wear = |k: &docs::Key| k.table == "garment" && k.kind.is_none();
            within_ranges(&keys, &toml::Value::Table(t), wear, (text, file, n))?;
        }
        Ok(())
    }

    /// Each `[[fold]]` line given one way (points or pixels), its pixels inside the canvas.
    fn check_fold_lines(&self, text: &str, file: &Path) -> Result<(), SceneError> {
        let (w, h) = (self.output.preview_width, self.output.preview_height);
        for (n, f) in self.fold.iter().enumerate() {
            let err = |key: &str, value: String, expected: String| SceneError::Invalid {
                file: file.to_path_buf(),
                line: line_of_nth(text, "fold", n, key),
                key: format!("fold[{n}].{key}"),
                value,
                expected,
            };
            let one_way =
                "a line as `points` (m) or as `screen` (pixels of `tryon canvas`), not both";
            match (f.points.is_empty(), f.screen.is_empty()) {
                (true, true) => return Err(err("points", "none".into(), one_way.into())),
                (false, false) => {
                    return Err(err("screen", "beside points".into(), one_way.into()));
                }
                _ => {}
            }
            let inside = |p: &[Real; 2]| {
                p.iter().all(|x| x.is_finite())
                    && (0.0..=w as Real).contains(&p[0])
                    && (0.0..=h as Real).contains(&p[1])
            };
            if let Some(p) = f.screen.iter().find(|p| !inside(p)) {
                let expected = format!(
                    "pixels inside the {w} x {h} canvas ([output] preview_width x preview_height)"
                );
                return Err(err("screen", format!("{p:?}"), expected));
            }
        }
        Ok(())
    }

    /// Values whose allowed set a range cannot say.
    fn check_values(&self, text: &str, file: &Path) -> Result<(), SceneError> {
        if let BodySection::Mannequin(b) = &self.body {
            match b.measurements().validate() {
                Ok(()) => {}
                Err(MeasureError::OutOfRange {
                    name,
                    value,
                    min,
                    max,
                }) => {
                    let expected = format!("{min:.3}..={max:.3} m for this height");
                    return Err(bad(text, file, "body", name, value.to_string(), &expected));
                }
                Err(e) => {
                    return Err(bad(
                        text,
                        file,
                        "body",
                        "waist",
                        b.waist.to_string(),
                        &e.to_string(),
                    ));
                }
            }
        }
        for (n, g) in self.more_garments.iter().enumerate() {
            if let GarmentSection::Square(SquareSpec { grab: Some(_), .. }) = g {
                return Err(SceneError::Invalid {
                    file: file.to_path_buf(),
                    line: line_of_nth(text, "garment", n + 1, "grab"),
                    key: format!("garment[{}].grab", n + 1),
                    value: "a path".into(),
                    expected: "no grab: only the first garment is grabbed".into(),
                });
            }
        }
        if let GarmentSection::Square(g) = &self.garment
            && let Some(path) = &g.grab
        {
            let ok = !path.is_empty()
                && path
                    .iter()
                    .all(|p| p.len() == 4 && p.iter().all(|x| x.is_finite()))
                && path.windows(2).all(|w| w[1][0] > w[0][0])
                && path[0][0] >= 0.0;
            if !ok {
                let expected = "[[t, x, y, z], ...] with finite numbers and times rising from >= 0";
                return Err(bad(
                    text,
                    file,
                    "garment",
                    "grab",
                    format!("{path:?}"),
                    expected,
                ));
            }
        }
        let c = &self.cloth;
        if let Some(x) = c.p1.max_strain
            && !(x == 0.0 || (x.is_finite() && (1.0..=2.0).contains(&x)))
        {
            return Err(bad(
                text,
                file,
                "cloth.p1",
                "max_strain",
                x.to_string(),
                "0 (off) or a ratio in [1, 2]",
            ));
        }
        let x = c.vbd.limit;
        if !(x == 0.0 || (x.is_finite() && (1.0..=2.0).contains(&x))) {
            return Err(bad(
                text,
                file,
                "cloth.vbd",
                "limit",
                x.to_string(),
                "0 (off) or a ratio in [1, 2]",
            ));
        }
        if let Some(x) = c.p1.stretch_guard
            && !(x == 0.0 || (x.is_finite() && x > 1.0 && x <= 10.0))
        {
            return Err(bad(
                text,
                file,
                "cloth.p1",
                "stretch_guard",
                x.to_string(),
                "0 (off) or a ratio in (1, 10]",
            ));
        }
        let e = &self.effects;
        if e.fine_collider == Some(CollisionMethod::None) {
            let expected = "\"nearest_vertex\", \"sdf\", \"depth_maps\" or \"exact\" (set fine_collision = false to turn it off)";
            return Err(bad(
                text,
                file,
                "effects",
                "fine_collider",
                "\"none\"".into(),
                expected,
            ));
        }
        if !(e.fine_margin >= e.fine_skin) {
            let expected = format!("a number in {}..=0.2 (at least fine_skin)", e.fine_skin);
            return Err(bad(
                text,
                file,
                "effects",
                "fine_margin",
                e.fine_margin.to_string(),
                &expected,
            ));
        }
        Ok(())
    }

    /// What one table's kind asks of the others.
    fn check_combinations(&self, text: &str, file: &Path) -> Result<(), SceneError> {
        let (sc, cc) = (self.effects.self_collision, self.effects.cloth_collision);
        for (on, key) in [(sc, "self_collision"), (cc, "cloth_collision")] {
            if on && self.cloth.solver != SolverName::Vbd {
                let expected = "false, or cloth.solver = \"vbd\" (only the vbd solver has contact between layers of cloth)";
                return Err(bad(text, file, "effects", key, "true".into(), expected));
            }
        }
        for worn in self.garments() {
            self.check_garment(worn.garment, worn.index, text, file)?;
        }
        let kind = |v: &dyn erased::Kind| v.kind().to_string();
        let (body, motion) = (kind(&self.body), kind(&self.motion));
        match body.as_str() {
            "object" | "sphere" if motion != "still" => Err(bad(
                text,
                file,
                "motion",
                "kind",
                format!("\"{motion}\""),
                &format!("\"still\" for {body} body (it has no skeleton)"),
            )),
            "makehuman" if matches!(motion.as_str(), "walk" | "arm_raise") => Err(bad(
                text,
                file,
                "motion",
                "kind",
                format!("\"{motion}\""),
                "\"still\" or \"bvh\" on a MakeHuman body (the built-in clips drive the mannequin's joints)",
            )),
            _ => Ok(()),
        }
    }

    /// What garment `nth`'s kind asks of the body and the material.
    fn check_garment(
        &self,
        g: &GarmentSection,
        nth: usize,
        text: &str,
        file: &Path,
    ) -> Result<(), SceneError> {
        let garment = erased::Kind::kind(g);
        let body = erased::Kind::kind(&self.body);
        let wrong = |table: &str, key: &str, value: String, expected: &str| {
            Err(SceneError::Invalid {
                file: file.to_path_buf(),
                line: line_of_nth(text, table, if table == "garment" { nth } else { 0 }, key),
                key: match (table, nth) {
                    ("garment", n) if n > 0 => format!("garment[{n}].{key}"),
                    _ => format!("{table}.{key}"),
                },
                value,
                expected: expected.to_string(),
            })
        };
        let quoted = format!("\"{garment}\"");
        if self.cloth.material == MaterialName::Sheet && garment != "square" {
            let expected = "\"garment\": the sheet material assumes a flat rest shape (garment kind = \"square\")";
            return wrong("cloth", "material", "\"sheet\"".into(), expected);
        }
        match body {
            "object" | "sphere" if garment != "square" => wrong(
                "garment",
                "kind",
                quoted,
                &format!("\"square\" on {body} body"),
            ),
            b if b != "mannequin" && garment == "kimono" => wrong(
                "garment",
                "kind",
                quoted,
                "a mannequin ([body] kind = \"mannequin\"): the kimono is fitted to its measurements",
            ),
            "makehuman" if matches!(garment, "dress" | "skirt" | "shirt") => wrong(
                "garment",
                "kind",
                quoted,
                "\"mhclo\" or \"square\" on a MakeHuman body (patterns are cut for the mannequin)",
            ),
            b if b != "makehuman" && garment == "mhclo" => wrong(
                "garment",
                "kind",
                quoted,
                "a MakeHuman body ([body] kind = \"makehuman\") to bind the garment to",
            ),
            _ => Ok(()),
        }
    }
}

/// The `kind` each tagged table was read as.
mod erased {
    use super::*;

    pub trait Kind {
        fn kind(&self) -> &'static str;
    }

    impl Kind for BodySection {
        fn kind(&self) -> &'static str {
            match self {
                BodySection::Mannequin(_) => "mannequin",
                BodySection::Sphere(_) => "sphere",
                BodySection::Makehuman(_) => "makehuman",
                BodySection::Object(_) => "object",
            }
        }
    }

    impl Kind for GarmentSection {
        fn kind(&self) -> &'static str {
            match self {
                GarmentSection::Dress(_) => "dress",
                GarmentSection::Skirt(_) => "skirt",
                GarmentSection::Shirt(_) => "shirt",
                GarmentSection::Square(_) => "square",
                GarmentSection::Mhclo(_) => "mhclo",
                GarmentSection::Kimono(_) => "kimono",
            }
        }
    }

    impl Kind for MotionSection {
        fn kind(&self) -> &'static str {
            match self {
                MotionSection::Still(_) => "still",
                MotionSection::Walk(_) => "walk",
                MotionSection::ArmRaise(_) => "arm_raise",
                MotionSection::Bvh(_) => "bvh",
            }
        }
    }
}
