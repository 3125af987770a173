//! The scene schema as data (every key of every table and kind, with its type, default, range and
//! description, read from the types' JSON schema) and the reference generated from it,
//! docs/scenes.md. The range checks read the same list, so the reference cannot go stale against
//! them; `cargo xtask tidy` checks the committed file against [`markdown`].

use super::Scene;
use schemars::JsonSchema;
use serde_json::Value;

/// One key of the schema.
#[derive(Clone, Debug, PartialEq)]
pub struct Key {
    /// The table (`body`, `effects`, ...).
    pub table: String,
    /// The `kind` that owns the key, for tables with kinds.
    pub kind: Option<String>,
    pub name: String,
    /// What it holds, in words ("number", "bool", "one of ...").
    pub ty: String,
    /// Its default as TOML would spell it; `None` when required, "none" when optional.
    pub default: Option<String>,
    pub min: Option<f64>,
    pub max: Option<f64>,
    /// Exact length of an array value.
    pub len: Option<usize>,
    /// Whether the range applies to each element of an array.
    pub per_item: bool,
    pub description: String,
}

impl Key {
    /// What the key allows, in words.
    pub fn allowed(&self) -> String {
        let range = match (self.min, self.max) {
            (Some(a), Some(b)) => format!("{a}..={b}"),
            (Some(a), None) => format!(">= {a}"),
            (None, Some(b)) => format!("<= {b}"),
            (None, None) => String::new(),
        };
        match (self.len, range.is_empty()) {
            (Some(n), false) => format!("{n} numbers in {range}"),
            (Some(n), true) => format!("{n} values"),
            (None, false) => range,
            (None, true) if self.ty.starts_with("one of") => self.ty.clone(),
            (None, true) if self.ty == "number" => "see what it does".into(),
            (None, true) => "any".into(),
        }
    }
}

fn root() -> Value {
    schemars::schema_for!(Scene).as_value().clone()
}

/// `v` with a `$ref` followed into `defs`.
fn resolve<'a>(v: &'a Value, defs: &'a Value) -> &'a Value {
    match v["$ref"].as_str().and_then(|r| r.strip_prefix("#/$defs/")) {
        Some(name) => &defs[name],
        None => v,
    }
}

/// The names of an externally tagged enum's variants, in declaration order.
pub fn variant_names<T: JsonSchema>() -> Vec<String> {
    let s = schemars::schema_for!(T);
    let v = s.as_value();
    v["oneOf"]
        .as_array()
        .into_iter()
        .flatten()
        .flat_map(|e| {
            let named = e["required"].as_array().into_iter().flatten();
            let unit = e["enum"].as_array().into_iter().flatten();
            named.chain(unit).chain(std::iter::once(&e["const"]))
        })
        .filter_map(|n| n.as_str().map(str::to_string))
        .collect()
}

/// A type in words: "number", "integer", "bool", "string", "array", or "one of ..." for enums.
fn type_words(p: &Value, defs: &Value) -> String {
    if let Some(any) = p["anyOf"].as_array() {
        // Option<T>: the non-null alternative.
        if let Some(t) = any.iter().find(|a| a["type"] != "null") {
            return type_words(resolve(t, defs), defs);
        }
    }
    let p = resolve(p, defs);
    let alts = p["oneOf"].as_array().into_iter().flatten();
    let names: Vec<String> = alts
        .flat_map(|a| {
            let one = a["const"].as_str().into_iter();
            one.chain(
                a["enum"]
                    .as_array()
                    .into_iter()
                    .flatten()
                    .filter_map(Value::as_str),
            )
        })
        .chain(
            p["enum"]
                .as_array()
                .into_iter()
                .flatten()
                .filter_map(Value::as_str),
        )
        .map(|c| format!("\"{c}\""))
        .collect();
    if !names.is_empty() {
        return format!("one of {}", names.join(", "));
    }
    let t = match &p["type"] {
        Value::Array(a) => a.iter().find(|x| *x != "null").cloned().unwrap_or_default(),
        t => t.clone(),
    };
    match t.as_str().unwrap_or("") {
        "number" => "number".into(),
        "integer" => "integer".into(),
        "boolean" => "bool".into(),
        "string" => "string".into(),
        "array" => "array".into(),
        _ => "value".into(),
    }
}

/// A default value as TOML spells it.
fn toml_words(v: &Value) -> String {
    match v {
        Value::Null => "none".into(),
        Value::String(s) => format!("\"{s}\""),
        Value::Array(a) => format!(
            "[{}]",
            a.iter().map(toml_words).collect::<Vec<_>>().join(", ")
        ),
        v => v.to_string(),
    }
}

/// The keys of one struct schema.
fn keys_of(table: &str, kind: Option<&str>, s: &Value, defs: &Value) -> Vec<Key> {
    let s = resolve(s, defs);
    let required: Vec<&str> = s["required"]
        .as_array()
        .into_iter()
        .flatten()
        .filter_map(Value::as_str)
        .collect();
    let (mut out, mut nested) = (Vec::new(), Vec::new());
    for (name, p) in s["properties"].as_object().into_iter().flatten() {
        // A table inside the table (`[cloth.vbd]`): its keys follow the table's own.
        let sub = resolve(p, defs);
        if kind.is_none() && sub["properties"].is_object() {
            nested.extend(keys_of(&format!("{table}.{name}"), None, sub, defs));
            continue;
        }
        let items = &p["items"];
        let per_item =
            items.is_object() && (items.get("minimum").is_some() || items.get("maximum").is_some());
        let bound = |k: &str| {
            let direct = p[k].as_f64();
            let opt = p["anyOf"]
                .as_array()
                .and_then(|a| a.iter().find_map(|x| x[k].as_f64()));
            direct
                .or(opt)
                .or(if per_item { items[k].as_f64() } else { None })
        };
        let len = match (p["minItems"].as_u64(), p["maxItems"].as_u64()) {
            (Some(a), Some(b)) if a == b => Some(a as usize),
            _ => None,
        };
        let default = if required.contains(&name.as_str()) {
            None
        } else {
            Some(p.get("default").map_or("none".into(), toml_words))
        };
        out.push(Key {
            table: table.into(),
            kind: kind.map(str::to_string),
            name: name.clone(),
            ty: type_words(p, defs),
            default,
            min: bound("minimum"),
            max: bound("maximum"),
            len,
            per_item,
            description: p["description"].as_str().unwrap_or("").replace('\n', " "),
        });
    }
    out.extend(nested);
    out
}

/// Every key of the scene schema, table by table (kinds in declaration order).
pub fn keys() -> Vec<Key> {
    let r = root();
    let defs = &r["$defs"];
    let mut out = Vec::new();
    for table in [
        "scene", "body", "garment", "motion", "cloth", "effects", "output", "folding",
    ] {
        let t = resolve(&r["properties"][table], defs);
        if table == "folding" {
            let w = schemars::schema_for!(super::FoldSpec).as_value().clone();
            out.extend(keys_of("fold", None, &w, &w["$defs"]));
        }
        if table == "garment" {
            let w = schemars::schema_for!(super::WearSpec).as_value().clone();
            out.extend(keys_of(table, None, &w, &w["$defs"]));
        }
        match t["oneOf"].as_array() {
            Some(kinds) => {
                for k in kinds {
                    let Some(kind) = k["required"][0].as_str() else {
                        continue;
                    };
                    out.extend(keys_of(table, Some(kind), &k["properties"][kind], defs));
                }
            }
            None => out.extend(keys_of(table, None, t, defs)),
        }
    }
    out
}

/// The description of a table, or of one kind of it.
fn describe(table: &str, kind: Option<&str>) -> String {
    if table == "fold" {
        let f = schemars::schema_for!(super::FoldSpec).as_value().clone();
        return f["description"].as_str().unwrap_or("").replace('\n', " ");
    }
    let r = root();
    let defs = &r["$defs"];
    let mut t = &r;
    for part in table.split('.') {
        t = resolve(&t["properties"][part], defs);
    }
    let d = match kind {
        None => &t["description"],
        Some(k) => t["oneOf"]
            .as_array()
            .and_then(|a| a.iter().find(|e| e["required"][0] == k))
            .map_or(&Value::Null, |e| &e["description"]),
    };
    d.as_str().unwrap_or("").replace('\n', " ")
}

/// docs/scenes.md: every key of every table and kind.
pub fn markdown() -> String {
    let mut s = String::from(
        "# Scene files: every key\n\n\
         Generated from the schema by `cargo xtask docs` (do not edit; `cargo xtask tidy` checks it).\n\
         A scene is TOML with the tables below; `[body]` and `[garment]` are required. A table with\n\
         kinds takes `kind = \"...\"` and only that kind's keys. Several garments are worn as\n\
         `[[garment]]` tables, each with its kind, its kind's keys and the keys every kind takes. Unknown keys and values outside the\n\
         allowed range are errors naming the file, line and key. Any key can be set on the command\n\
         line with `--set table.key=value`.\n",
    );
    let keys = keys();
    let mut last: Option<(String, Option<String>)> = None;
    for k in &keys {
        let here = (k.table.clone(), k.kind.clone());
        if last.as_ref() != Some(&here) {
            if last.as_ref().is_none_or(|l| l.0 != k.table) {
                // Tables given as arrays (`[[fold]]`) are headed as such.
                let header = match k.table.as_str() {
                    "fold" => "[[fold]]".to_string(),
                    t => format!("[{t}]"),
                };
                s.push_str(&format!("\n## {header}\n\n{}\n", describe(&k.table, None)));
            }
            if let Some(kind) = &k.kind {
                let d = describe(&k.table, Some(kind));
                s.push_str(&format!("\n### kind = \"{kind}\"\n\n{d}\n"));
            }
            s.push_str(
                "\n| key | type | default | allowed | what it does |\n|---|---|---|---|---|\n",
            );
            last = Some(here);
        }
        let default = k.default.clone().unwrap_or_else(|| "required".into());
        let ty = if k.ty.starts_with("one of") {
            "string"
        } else {
            &k.ty
        };
        s.push_str(&format!(
            "| `{}` | {} | `{}` | {} | {} |\n",
            k.name,
            ty,
            default,
            k.allowed(),
            k.description
        ));
    }
    s.push_str(&crate::fixes::markdown());
    s
}
