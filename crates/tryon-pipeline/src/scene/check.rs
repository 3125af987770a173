//! The scene's range checks: every value against what it allows, and the combinations of body,
//! garment and motion that make sense. Errors name the file, the line, the key and what is allowed.

use super::*;

impl Scene {
    pub(super) fn check(&self, text: &str, file: &Path) -> Result<(), SceneError> {
        let bad = |table: &str, key: &str, value: String, expected: &str| SceneError::Invalid {
            file: file.to_path_buf(),
            line: line_of(text, table, key),
            key: format!("{table}.{key}"),
            value,
            expected: expected.to_string(),
        };
        let range = |table: &str, key: &str, v: Option<Real>, lo: Real, hi: Real| match v {
            Some(x) if !(x.is_finite() && x >= lo && x <= hi) => Err(bad(
                table,
                key,
                x.to_string(),
                &format!("a number in {lo}..={hi}"),
            )),
            _ => Ok(()),
        };
        let s = &self.scene;
        range("scene", "fps", Some(s.fps), 1.0, 1000.0)?;
        range("scene", "duration", s.duration, 0.0, 3600.0)?;
        range("scene", "settle", Some(s.settle), 0.0, 60.0)?;
        let b = &self.body;
        for (k, v, lo, hi) in [
            ("height", b.height, 1.2, 2.2),
            ("bust", b.bust, 0.5, 1.8),
            ("waist", b.waist, 0.4, 1.6),
            ("hip", b.hip, 0.5, 1.8),
            ("shoulder_width", b.shoulder_width, 0.25, 0.6),
            ("arm_length", b.arm_length, 0.35, 0.85),
            ("inseam", b.inseam, 0.5, 1.1),
            ("radius", b.radius, 0.01, 5.0),
        ] {
            range("body", k, v, lo, hi)?;
        }
        if b.kind == BodyKind::Mannequin {
            match self.measurements().validate() {
                Ok(()) => {}
                Err(tryon_core::measure::MeasureError::OutOfRange {
                    name,
                    value,
                    min,
                    max,
                }) => {
                    return Err(bad(
                        "body",
                        name,
                        value.to_string(),
                        &format!("{min:.3}..={max:.3} m for this height"),
                    ));
                }
                Err(e) => {
                    return Err(bad(
                        "body",
                        "waist",
                        b.waist.map_or("default".into(), |w| w.to_string()),
                        &e.to_string(),
                    ));
                }
            }
        }
        let g = &self.garment;
        range("body", "scale", b.scale, 1e-4, 1e4)?;
        range("body", "table", b.table, 0.0, 20.0)?;
        if b.kind == BodyKind::Object && b.file.is_none() {
            return Err(bad(
                "body",
                "file",
                "nothing".into(),
                "an .obj file for kind = \"object\"",
            ));
        }
        if b.kind != BodyKind::Object {
            for (k, given) in [
                ("file", b.file.is_some()),
                ("scale", b.scale.is_some()),
                ("table", b.table.is_some()),
            ] {
                if given {
                    return Err(bad(
                        "body",
                        k,
                        "a value".into(),
                        "nothing: only kind = \"object\" takes it",
                    ));
                }
            }
        }
        if let Some(path) = &g.grab {
            let ok = !path.is_empty()
                && path.iter().all(|p| p.iter().all(|x| x.is_finite()))
                && path.windows(2).all(|w| w[1][0] > w[0][0])
                && path[0][0] >= 0.0;
            if !ok {
                return Err(bad(
                    "garment",
                    "grab",
                    format!("{path:?}"),
                    "[[t, x, y, z], ...] with finite numbers and times rising from >= 0",
                ));
            }
            if g.kind != GarmentKind::Square {
                return Err(bad(
                    "garment",
                    "grab",
                    format!("{path:?}"),
                    "nothing: only kind = \"square\" can be grabbed",
                ));
            }
        }
        if let Some(n) = b.subdivisions
            && n > 6
        {
            return Err(bad("body", "subdivisions", n.to_string(), "0..=6"));
        }
        if let Some(e) = &g.ease {
            let want = if g.kind == GarmentKind::Skirt { 2 } else { 3 };
            if e.len() != want || e.iter().any(|x| !(x.is_finite() && *x >= 0.0 && *x <= 0.5)) {
                return Err(bad(
                    "garment",
                    "ease",
                    format!("{e:?}"),
                    &format!("{want} numbers in 0..=0.5 (m)"),
                ));
            }
        }
        range("garment", "flare", g.flare, 0.0, 2.0)?;
        range("garment", "hem_above_knee", g.hem_above_knee, -0.3, 0.3)?;
        range("garment", "row_spacing", g.row_spacing, 0.01, 0.2)?;
        range("garment", "size", g.size, 0.05, 10.0)?;
        range("garment", "drop_height", g.drop_height, -10.0, 10.0)?;
        range("garment", "band_gap", g.band_gap, 0.0, 0.05)?;
        if let Some(c) = g.columns
            && !(16..=96).contains(&c)
        {
            return Err(bad("garment", "columns", c.to_string(), "16..=96"));
        }
        if let Some(n) = g.particles
            && !(2..=256).contains(&n)
        {
            return Err(bad(
                "garment",
                "particles",
                n.to_string(),
                "2..=256 per side",
            ));
        }
        let m = &self.motion;
        range("motion", "duration", m.duration, 0.0, 3600.0)?;
        range("motion", "period", m.period, 0.3, 5.0)?;
        range("motion", "hip_deg", m.hip_deg, 0.0, 60.0)?;
        range("motion", "knee_deg", m.knee_deg, 0.0, 120.0)?;
        range("motion", "arm_deg", m.arm_deg, 0.0, 60.0)?;
        range("motion", "raise_deg", m.raise_deg, 0.0, 150.0)?;
        range("body", "gender", b.gender, 0.0, 1.0)?;
        range("motion", "start", m.start, 0.0, 3600.0)?;
        range("motion", "ease_in", m.ease_in, 0.0, 10.0)?;
        range("motion", "unit", m.unit, 1e-4, 10.0)?;
        if m.kind == MotionKind::Bvh && m.file.is_none() {
            return Err(bad(
                "motion",
                "file",
                "nothing".into(),
                "a .bvh file for kind = \"bvh\"",
            ));
        }
        if g.kind == GarmentKind::Mhclo && g.file.is_none() {
            return Err(bad(
                "garment",
                "file",
                "nothing".into(),
                "a .mhclo file for kind = \"mhclo\"",
            ));
        }
        if g.kind == GarmentKind::Mhclo && b.kind != BodyKind::Makehuman {
            return Err(bad(
                "garment",
                "kind",
                "\"mhclo\"".into(),
                "a MakeHuman body ([body] kind = \"makehuman\") to bind the garment to",
            ));
        }
        if b.kind != BodyKind::Makehuman {
            if b.rig.is_some() {
                return Err(bad(
                    "body",
                    "rig",
                    format!("{:?}", b.rig),
                    "no rig: only MakeHuman bodies take one",
                ));
            }
            if let Some(x) = b.gender {
                return Err(bad(
                    "body",
                    "gender",
                    x.to_string(),
                    "no gender: only MakeHuman bodies take one",
                ));
            }
        }
        let c = &self.cloth;
        range("cloth", "substep", c.substep, 1e-5, 0.1)?;
        range("cloth", "density", c.density, 1e-3, 10.0)?;
        for (k, v) in [
            ("k_stretch", c.k_stretch),
            ("k_compress", c.k_compress),
            ("k_shear", c.k_shear),
            ("k_bend", c.k_bend),
            ("spring_damping", c.spring_damping),
        ] {
            range("cloth", k, v, 0.0, 1e9)?;
        }
        if let Some(x) = c.max_strain
            && !(x == 0.0 || (x.is_finite() && (1.0..=2.0).contains(&x)))
        {
            return Err(bad(
                "cloth",
                "max_strain",
                x.to_string(),
                "0 (off) or a ratio in [1, 2]",
            ));
        }
        if let Some(x) = c.stretch_guard
            && !(x == 0.0 || (x.is_finite() && x > 1.0 && x <= 10.0))
        {
            return Err(bad(
                "cloth",
                "stretch_guard",
                x.to_string(),
                "0 (off) or a ratio in (1, 10]",
            ));
        }
        if c.material == Some(MaterialName::Sheet) && self.garment.kind != GarmentKind::Square {
            return Err(bad(
                "cloth",
                "material",
                "\"sheet\"".to_string(),
                "\"garment\": the sheet material assumes a flat rest shape (garment kind = \"square\")",
            ));
        }
        if let Some(n) = c.strain_iterations
            && n > 100
        {
            return Err(bad("cloth", "strain_iterations", n.to_string(), "0..=100"));
        }
        range("cloth", "thickness", c.thickness, 0.0, 0.05)?;
        let e = &self.effects;
        range("effects", "air_drag", Some(e.air_drag), 0.0, 100.0)?;
        range("effects", "friction", Some(e.friction), 0.0, 5.0)?;
        if e.refine > 4 {
            return Err(bad("effects", "refine", e.refine.to_string(), "0..=4"));
        }
        if !(8..=512).contains(&e.sdf_resolution) {
            return Err(bad(
                "effects",
                "sdf_resolution",
                e.sdf_resolution.to_string(),
                "8..=512 cells along the body's longest side",
            ));
        }
        if !(16..=4096).contains(&e.depth_resolution) {
            return Err(bad(
                "effects",
                "depth_resolution",
                e.depth_resolution.to_string(),
                "16..=4096 pixels along the body's longest side",
            ));
        }
        if e.fine_collider == Some(CollisionMethod::None) {
            return Err(bad(
                "effects",
                "fine_collider",
                "\"none\"".into(),
                "\"nearest_vertex\", \"sdf\", \"depth_maps\" or \"exact\" (set fine_collision = false to turn it off)",
            ));
        }
        range("effects", "k_out_plane", Some(e.k_out_plane), 0.0, 100.0)?;
        range("effects", "h_normal", Some(e.h_normal), 1e-5, 1.0)?;
        range("effects", "fine_skin", Some(e.fine_skin), 0.0, 0.05)?;
        range(
            "effects",
            "fine_margin",
            Some(e.fine_margin),
            e.fine_skin,
            0.2,
        )?;
        range(
            "effects",
            "max_fine_stretch",
            Some(e.max_fine_stretch),
            1.0,
            3.0,
        )?;
        range(
            "effects",
            "velocity_damping",
            Some(e.velocity_damping),
            0.0,
            100.0,
        )?;
        if e.wind.iter().any(|w| !(w.is_finite() && w.abs() <= 100.0)) {
            return Err(bad(
                "effects",
                "wind",
                format!("{:?}", e.wind),
                "three numbers in -100..=100 (m/s)",
            ));
        }
        let o = &self.output;
        for (k, v) in [
            ("preview_width", o.preview_width),
            ("preview_height", o.preview_height),
        ] {
            if !(16..=8192).contains(&v) {
                return Err(bad("output", k, v.to_string(), "16..=8192 pixels"));
            }
        }
        // Combinations.
        if self.body.kind == BodyKind::Object && self.motion.kind != MotionKind::Still {
            return Err(bad(
                "motion",
                "kind",
                format!("{:?}", self.motion.kind).to_lowercase(),
                "\"still\" for an object body (it has no skeleton)",
            ));
        }
        if self.body.kind == BodyKind::Object && g.kind != GarmentKind::Square {
            return Err(bad(
                "garment",
                "kind",
                format!("{:?}", g.kind).to_lowercase(),
                "\"square\" on an object body",
            ));
        }
        if self.body.kind == BodyKind::Sphere && self.motion.kind != MotionKind::Still {
            return Err(bad(
                "motion",
                "kind",
                format!("{:?}", self.motion.kind).to_lowercase(),
                "\"still\" for a sphere body (it has no skeleton)",
            ));
        }
        if self.body.kind == BodyKind::Makehuman
            && matches!(g.kind, GarmentKind::Dress | GarmentKind::Skirt)
        {
            return Err(bad(
                "garment",
                "kind",
                format!("{:?}", g.kind).to_lowercase(),
                "\"mhclo\" or \"square\" on a MakeHuman body (patterns are cut for the mannequin)",
            ));
        }
        if self.body.kind == BodyKind::Makehuman
            && matches!(self.motion.kind, MotionKind::Walk | MotionKind::ArmRaise)
        {
            return Err(bad(
                "motion",
                "kind",
                format!("{:?}", self.motion.kind).to_lowercase(),
                "\"still\" or \"bvh\" on a MakeHuman body (the built-in clips drive the mannequin's joints)",
            ));
        }
        if self.body.kind == BodyKind::Sphere && g.kind != GarmentKind::Square {
            return Err(bad(
                "garment",
                "kind",
                format!("{:?}", g.kind).to_lowercase(),
                "\"square\" on a sphere body (patterns need the mannequin's measurements)",
            ));
        }
        Ok(())
    }
}
