//! Tests of the scene schema: every key of every kind in the generated reference is checked
//! against the range the reference gives, keys belong to their kind only, and the tagged tables
//! read the values they are given.

use super::*;
use std::path::Path;

/// A minimal scene whose `table` has kind `kind` (the other tables made to fit it), with `extra`
/// lines added to that table.
fn minimal(table: &str, kind: Option<&str>, extra: &str) -> String {
    // A table inside a table (`cloth.vbd`) goes under its parent.
    if let Some((parent, _)) = table.split_once('.') {
        return minimal(parent, kind, &format!("\n[{table}]\n{extra}"));
    }
    let (mut body, mut garment, mut motion) = (
        "kind = \"mannequin\"\n".to_string(),
        "kind = \"dress\"\n".to_string(),
        "kind = \"still\"\n".to_string(),
    );
    let file = |k: &str| match k {
        "object" => "file = \"x.obj\"\n",
        "mhclo" => "file = \"x.mhclo\"\n",
        "bvh" => "file = \"x.bvh\"\n",
        _ => "",
    };
    match (table, kind) {
        ("body", Some(k)) => {
            body = format!("kind = \"{k}\"\n{}", file(k));
            if k != "mannequin" {
                garment = "kind = \"square\"\n".into();
            }
        }
        ("garment", Some(k)) => {
            garment = format!("kind = \"{k}\"\n{}", file(k));
            match k {
                "square" => body = "kind = \"sphere\"\n".into(),
                "mhclo" => body = "kind = \"makehuman\"\n".into(),
                _ => {}
            }
        }
        ("motion", Some(k)) => motion = format!("kind = \"{k}\"\n{}", file(k)),
        _ => {}
    }
    let mut tables = vec![
        ("scene", String::new()),
        ("body", body),
        ("garment", garment),
        ("motion", motion),
        ("cloth", String::new()),
        ("effects", String::new()),
        ("output", String::new()),
        ("folding", String::new()),
    ];
    for (name, text) in &mut tables {
        if *name == table {
            text.push_str(extra);
        }
    }
    let mut out: String = tables.iter().map(|(n, t)| format!("[{n}]\n{t}")).collect();
    if table == "fold" {
        // A fold needs its line; the dress's front at the waist.
        out.push_str(&format!(
            "[[fold]]\npoints = [[0.0, 1.0, 0.1], [0.0, 0.9, 0.1]]\n{}",
            if extra.contains("height") {
                extra.to_string()
            } else {
                format!("height = 0.02\n{extra}")
            }
        ));
    }
    out
}

#[test]
fn every_minimal_scene_of_every_kind_parses() {
    for k in docs::keys() {
        let text = minimal(&k.table, k.kind.as_deref(), "");
        if let Err(e) = Scene::parse(&text, Path::new("m.toml")) {
            panic!("{}/{:?}: {e}\n{text}", k.table, k.kind);
        }
    }
}

#[test]
fn every_ranged_key_refuses_values_past_its_range_and_names_itself() {
    let mut checked = 0;
    for k in docs::keys() {
        let (Some(lo), Some(hi)) = (k.min, k.max) else {
            continue;
        };
        let integer = k.ty == "integer";
        let spell = |x: f64| {
            let one = if integer {
                format!("{}", x as i64)
            } else {
                format!("{x:?}")
            };
            match k.len {
                Some(n) => format!("[{}]", vec![one; n].join(", ")),
                None => one,
            }
        };
        for (x, ok) in [(lo, true), (hi, true), (hi + 1.0, false), (lo - 1.0, false)] {
            if integer && x < 0.0 {
                continue; // an unsigned key cannot even be written below 0
            }
            let text = minimal(
                &k.table,
                k.kind.as_deref(),
                &format!("{} = {}\n", k.name, spell(x)),
            );
            let got = Scene::parse(&text, Path::new("m.toml"));
            let name = format!("{}.{}", k.table, k.name);
            match (ok, got) {
                (true, Err(e)) if e.to_string().contains(&name) => {
                    // A value at the edge of its own range may still break a rule between keys
                    // (measurements for the height, fine_margin >= fine_skin): only those.
                    assert!(
                        ["body.", "effects.fine_"]
                            .iter()
                            .any(|p| name.starts_with(p)),
                        "{name} = {x} refused: {e}"
                    );
                }
                (false, Ok(_)) => panic!("{name} = {x} accepted (allowed {})", k.allowed()),
                (false, Err(e)) => {
                    let e = e.to_string();
                    assert!(
                        e.contains(&name) && e.contains("m.toml:"),
                        "{name} = {x}: {e}"
                    );
                    checked += 1;
                }
                _ => {}
            }
        }
    }
    assert!(checked > 60, "only {checked} out-of-range values checked");
}

#[test]
fn a_key_of_another_kind_is_refused_and_the_kind_that_takes_it_is_named() {
    let text = minimal("body", Some("mannequin"), "rig = \"cmu_mb\"\n");
    let e = Scene::parse(&text, Path::new("m.toml"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("body.rig") && e.contains("kind = \"makehuman\""),
        "{e}"
    );
    let text = minimal("garment", Some("dress"), "particles = 8\n");
    let e = Scene::parse(&text, Path::new("m.toml"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("garment.particles") && e.contains("\"square\""),
        "{e}"
    );
}

#[test]
fn tagged_tables_read_their_values_and_defaults_come_from_the_stages() {
    let text = minimal("motion", Some("walk"), "period = 0.9\n");
    let s = Scene::parse(&text, Path::new("m.toml")).unwrap();
    let MotionSection::Walk(w) = &s.motion else {
        panic!("{:?}", s.motion)
    };
    assert_eq!(w.period, 0.9);
    assert_eq!(w.hip_deg, mocap_retarget::WalkParams::default().hip_deg);
    let BodySection::Mannequin(b) = &s.body else {
        panic!("{:?}", s.body)
    };
    assert_eq!(
        b.measurements(),
        tryon_core::measure::Measurements::default()
    );
    assert_eq!(s.cloth.thickness, cloth_dyn::presets::THICKNESS);
    assert_eq!(
        s.effects.h_normal,
        wrinkle::DetailParams::default().h_normal
    );
}

#[test]
fn the_reference_lists_every_kind_and_its_keys() {
    let md = docs::markdown();
    for kind in [
        "mannequin",
        "sphere",
        "makehuman",
        "object",
        "dress",
        "skirt",
        "square",
        "mhclo",
    ] {
        assert!(md.contains(&format!("### kind = \"{kind}\"")), "{kind}");
    }
    for kind in ["still", "walk", "arm_raise", "bvh"] {
        assert!(md.contains(&format!("### kind = \"{kind}\"")), "{kind}");
    }
    assert!(
        md.contains("| `raise_deg` | number | `100.0` | 0..=150 |"),
        "{md}"
    );
    assert_eq!(
        docs::variant_names::<MotionSection>(),
        ["still", "walk", "arm_raise", "bvh"]
    );
}

/// `[cloth]` with a solver's table under it holding `keys`.
fn solver_table(solver: &str, keys: &str) -> String {
    minimal(&format!("cloth.{solver}"), None, keys)
}

#[test]
fn a_ratio_with_an_off_value_refuses_what_lies_between_and_says_what_is_allowed() {
    for (table, key, bad) in [
        ("vbd", "limit", "0.5"),
        ("vbd", "limit", "2.5"),
        ("p1", "max_strain", "0.9"),
    ] {
        let text = solver_table(table, &format!("{key} = {bad}\n"));
        let e = Scene::parse(&text, Path::new("m.toml"))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains(&format!("cloth.{table}.{key}"))
                && e.contains("0 (off) or a ratio in [1, 2]"),
            "{key} = {bad}: {e}"
        );
    }
    // A non-finite value is refused before the key's own rule, as not a finite number.
    let text = solver_table("vbd", "limit = nan\n");
    let e = Scene::parse(&text, Path::new("m.toml"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("cloth.vbd.limit") && e.contains("a finite number"),
        "{e}"
    );
    for good in ["0", "1.0", "1.1"] {
        let text = solver_table("vbd", &format!("limit = {good}\n"));
        let s = Scene::parse(&text, Path::new("m.toml")).unwrap();
        assert_eq!(s.cloth.vbd.limit, good.parse::<f64>().unwrap());
    }
}

#[test]
fn the_vbd_bending_keys_refuse_what_is_out_of_range_and_name_the_key() {
    for (key, bad, allowed) in [
        ("dihedral", "-1e-4", "0..=1"),
        ("dihedral", "2", "0..=1"),
        ("dihedral", "nan", "0..=1"),
        ("flexion", "-5", "0..=1000000"),
    ] {
        let text = solver_table("vbd", &format!("{key} = {bad}\n"));
        let e = Scene::parse(&text, Path::new("m.toml"))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains(&format!("cloth.vbd.{key}")) && e.contains(allowed),
            "{key} = {bad}: {e}"
        );
    }
    let text = solver_table("vbd", "dihedral = 1e-4\nflexion = 0\n");
    let s = Scene::parse(&text, Path::new("m.toml")).unwrap();
    assert_eq!((s.cloth.vbd.dihedral, s.cloth.vbd.bend), (1e-4, 0.0));
}

#[test]
fn an_unknown_key_of_a_solver_table_is_named_with_its_whole_path() {
    let text = solver_table("xpbd", "substep = 0.001\nsweeps = 3\n");
    let e = Scene::parse(&text, Path::new("m.toml"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("`cloth.xpbd.sweeps`") && e.contains("unknown field"),
        "{e}"
    );
}

#[test]
fn an_old_flat_solver_key_is_refused_naming_its_new_table() {
    for (table, old, new) in [
        ("cloth", "vbd_substep = 0.01", "[cloth.vbd]"),
        ("cloth", "xpbd_iterations = 2", "[cloth.xpbd]"),
        ("cloth", "integrator = \"rk4\"", "[cloth.p1]"),
        ("effects", "sdf_resolution = 64", "[effects.sdf]"),
    ] {
        let text = minimal(table, None, &format!("{old}\n"));
        let e = Scene::parse(&text, Path::new("m.toml"))
            .unwrap_err()
            .to_string();
        let key = old.split(" =").next().unwrap();
        assert!(
            e.contains(&format!("{table}.{key}")) && e.contains(new),
            "{old}: {e}"
        );
    }
    // The same through --set, and the new place takes the value.
    let text = minimal("cloth", None, "");
    let set = |s: &str| Scene::parse_with_overrides(&text, Path::new("m.toml"), &[s.to_string()]);
    let e = set("cloth.vbd_limit=1.0").unwrap_err().to_string();
    assert!(
        e.contains("cloth.vbd_limit") && e.contains("[cloth.vbd]"),
        "{e}"
    );
    assert_eq!(set("cloth.vbd.limit=1.0").unwrap().cloth.vbd.limit, 1.0);
    let s = set("effects.depth_maps.resolution=64").unwrap();
    assert_eq!(s.effects.depth_maps.resolution, 64);
}

#[test]
fn self_collision_asks_for_the_vbd_solver_and_a_thickness_in_range() {
    // VBD is the default solver; another is refused.
    let text = minimal("effects", None, "self_collision = true\n");
    let p1 = text.replace("[cloth]\n", "[cloth]\nsolver = \"p1\"\n");
    let e = Scene::parse(&p1, Path::new("m.toml"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("effects.self_collision") && e.contains("vbd"),
        "{e}"
    );
    assert!(Scene::parse(&text, Path::new("m.toml")).is_ok());
    let text = text.replace("[cloth]\n", "[cloth]\nself_thickness = 0.05\n");
    let e = Scene::parse(&text, Path::new("m.toml"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("cloth.self_thickness") && e.contains("0.02"),
        "{e}"
    );
    let ok = text.replace("0.05", "0.003");
    let s = Scene::parse(&ok, Path::new("m.toml")).unwrap();
    assert!(s.effects.self_collision && s.cloth.self_thickness == 0.003);
}

/// A mannequin scene wearing `garments` (the text of each `[[garment]]` table).
fn wearing(garments: &[&str], effects: &str) -> String {
    let mut s = String::from("[body]\nkind = \"mannequin\"\n");
    for g in garments {
        s.push_str(&format!("[[garment]]\n{g}"));
    }
    s.push_str(&format!("[cloth]\nsolver = \"vbd\"\n[effects]\n{effects}"));
    s
}

#[test]
fn several_garments_are_read_in_order_with_their_layers_and_materials() {
    let text = wearing(
        &[
            "kind = \"skirt\"\ndensity = 0.1\nstiffness = 0.5\n",
            "kind = \"dress\"\nlayer = 3\n",
            "kind = \"skirt\"\n",
        ],
        "cloth_collision = true\n",
    );
    let s = Scene::parse(&text, Path::new("m.toml")).unwrap_or_else(|e| panic!("{e}"));
    let worn = s.garments();
    let kinds: Vec<_> = worn
        .iter()
        .map(|w| matches!(w.garment, GarmentSection::Dress(_)))
        .collect();
    assert_eq!(kinds, [false, true, false]);
    // Layers: the given one, else the place in the list.
    let layers: Vec<u32> = worn.iter().map(|w| w.layer).collect();
    assert_eq!(layers, [0, 3, 2]);
    assert_eq!(worn[0].wear.density, Some(0.1));
    assert_eq!(worn[0].wear.stiffness, 0.5);
    assert_eq!(worn[1].wear.density, None);
    assert_eq!(worn[2].wear.stiffness, 1.0);
    // One `[garment]` table is one garment, as it always was.
    let one = Scene::parse(&minimal("garment", Some("dress"), ""), Path::new("m.toml")).unwrap();
    assert_eq!(one.garments().len(), 1);
    assert_eq!(one.garments()[0].layer, 0);
}

#[test]
fn a_bad_value_of_a_later_garment_names_that_garment_and_its_line() {
    let text = wearing(
        &[
            "kind = \"skirt\"\n",
            "kind = \"dress\"\nstiffness = 500.0\n",
        ],
        "",
    );
    let e = Scene::parse(&text, Path::new("m.toml"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("garment[1].stiffness") && e.contains("m.toml:7"),
        "{e}"
    );
    let text = wearing(
        &["kind = \"skirt\"\n", "kind = \"dress\"\nflare = 9.0\n"],
        "",
    );
    let e = Scene::parse(&text, Path::new("m.toml"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("garment[1].flare") && e.contains("m.toml:7"),
        "{e}"
    );
    // A MakeHuman garment on the mannequin, second in the list.
    let text = wearing(
        &[
            "kind = \"skirt\"\n",
            "kind = \"mhclo\"\nfile = \"x.mhclo\"\n",
        ],
        "",
    );
    let e = Scene::parse(&text, Path::new("m.toml"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("garment[1].kind") && e.contains("MakeHuman body"),
        "{e}"
    );
}

#[test]
fn garment_lists_and_contact_between_garments_are_checked() {
    let e = Scene::parse(
        "garment = []\n[body]\nkind = \"mannequin\"\n",
        Path::new("m.toml"),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("garment") && e.contains("one or more"), "{e}");
    let nine = vec!["kind = \"skirt\"\n"; 9];
    let e = Scene::parse(&wearing(&nine, ""), Path::new("m.toml"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("at most 8"), "{e}");
    let text = wearing(&["kind = \"skirt\"\n"], "cloth_collision = true\n")
        .replace("solver = \"vbd\"", "solver = \"p1\"");
    let e = Scene::parse(&text, Path::new("m.toml"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("effects.cloth_collision") && e.contains("vbd"),
        "{e}"
    );
}

#[test]
fn a_scenes_name_is_a_folder_name_never_a_path() {
    let folder = |name: &str| {
        let mut s = Scene::demo();
        s.scene.name = name.into();
        s.folder_name()
    };
    assert_eq!(folder("demo-dress-walk"), "demo-dress-walk");
    assert_eq!(folder("/abs/dir"), "_abs_dir");
    assert_eq!(folder("../../x"), "_.._x");
    assert_eq!(folder(".."), "scene");
    assert_eq!(folder(""), "scene");
    assert_eq!(folder("a b\\c:d"), "a_b_c_d");
    assert_eq!(folder("着物 walk"), "着物_walk");
    assert_eq!(folder(&"x".repeat(300)).len(), 100);
    for name in ["/abs/dir", "../../x", "..", "a/../../b", "C:\\x"] {
        let f = folder(name);
        let p = std::path::Path::new("out").join(&f);
        assert_eq!(p.components().count(), 2, "{name} -> {f}");
        assert!(
            !f.contains('/') && !f.contains('\\') && f != "..",
            "{name} -> {f}"
        );
    }
}

#[test]
fn an_error_under_overrides_names_the_files_own_line_or_the_override() {
    let text = "# a scene\n\n[scene]\nfps = 30\n\n[body]\nkind = \"mannequin\"\nheight = 9.0\n\n[garment]\nkind = \"dress\"\n\n[motion]\nkind = \"still\"\n";
    let file = Path::new("s.toml");
    let sets = ["effects.refine=1".to_string()];
    let e = Scene::parse_with_overrides(text, file, &sets).unwrap_err();
    let SceneError::Invalid { line, key, .. } = &e else {
        panic!("{e}");
    };
    assert_eq!((key.as_str(), *line), ("body.height", Some(8)), "{e}");
    let sets = ["effects.refine=9".to_string()];
    let fixed = text.replace("height = 9.0", "height = 1.6");
    let e = Scene::parse_with_overrides(&fixed, file, &sets).unwrap_err();
    let SceneError::Invalid { line, key, .. } = &e else {
        panic!("{e}");
    };
    assert_eq!((key.as_str(), *line), ("effects.refine", None), "{e}");
    assert!(e.to_string().contains("--set effects.refine=9"), "{e}");
}

#[test]
fn a_retired_key_is_refused_saying_what_does_its_job_now() {
    let text = minimal("cloth.vbd", None, "pokes = true\n");
    let e = Scene::parse(&text, Path::new("m.toml"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("cloth.vbd.pokes") && e.contains("retired") && e.contains("fine_pokes"),
        "{e}"
    );
    let flat = minimal("cloth", None, "vbd_pokes = true\n");
    let e = Scene::parse(&flat, Path::new("m.toml"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("cloth.vbd_pokes") && e.contains("retired"),
        "{e}"
    );
    let plain = minimal("cloth", None, "");
    let sets = ["cloth.vbd.pokes=true".to_string()];
    let e = Scene::parse_with_overrides(&plain, Path::new("m.toml"), &sets)
        .unwrap_err()
        .to_string();
    assert!(e.contains("retired"), "{e}");
    // A key beside it is still read.
    let ok = minimal("cloth.vbd", None, "swept = false\n");
    assert!(
        !Scene::parse(&ok, Path::new("m.toml"))
            .unwrap()
            .cloth
            .vbd
            .swept
    );
}
