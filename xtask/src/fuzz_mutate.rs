//! The fuzzer's corpus and mutations: real files of the data folder cut to a few kilobytes (so a
//! case parses in microseconds), and structure-aware changes to them: numbers swapped for
//! boundary values, tokens and lines deleted, repeated, swapped or spliced from elsewhere in the
//! file, the text cut short, structural characters of the format inserted.

use std::path::Path;

/// A small, fast, reproducible generator (splitmix64): case `i` of reader `r` is the same on
/// every machine.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Rng {
        Rng(seed)
    }

    pub fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// A number in `0..n` (0 when `n` is 0).
    pub fn below(&mut self, n: usize) -> usize {
        if n == 0 {
            0
        } else {
            (self.next() % n as u64) as usize
        }
    }

    fn pick<'a>(&mut self, list: &[&'a str]) -> &'a str {
        list[self.below(list.len())]
    }
}

/// Values at the edges of what a reader may meet.
const BOUNDARY: &[&str] = &[
    "0",
    "-0",
    "1",
    "-1",
    "2",
    "0.5",
    "-5",
    "7",
    "1e6",
    "1e9",
    "1e300",
    "1e308",
    "-1e308",
    "1e-320",
    "nan",
    "NaN",
    "inf",
    "-inf",
    "4294967295",
    "4294967296",
    "-4294967296",
    "18446744073709551616",
    "99999999999",
    "0x10",
    "1.",
    ".5",
    "+3",
    "--1",
    "1e",
    "",
    "x",
    "é",
    "\u{0}",
    "9223372036854775807",
];

/// Characters that open, close or separate things in the formats read.
const STRUCTURE: &[&str] = &[
    "{", "}", "[", "]", ",", ":", "\"", "=", "/", "//", "-", " - ", "\n", "\t", "#", "'", "\\",
];

/// One mutated copy of `seed`: one change in most cases (so most of the file stays readable and
/// the reader gets deep), up to four stacked.
pub fn mutate(seed: &str, rng: &mut Rng) -> String {
    let mut text = seed.to_string();
    let changes = [1, 1, 1, 1, 1, 2, 2, 3, 4][rng.below(9)];
    for _ in 0..changes {
        text = match rng.below(9) {
            0..=2 => replace_token(&text, rng, None),
            3 => replace_token(&text, rng, Some(&text.clone())),
            4 => edit_lines(&text, rng),
            5 => insert_structure(&text, rng),
            6 => delete_span(&text, rng),
            7 => truncate(&text, rng),
            _ => scale_number(&text, rng),
        };
    }
    text
}

/// Byte offsets of the whitespace-separated tokens of `text`.
fn tokens(text: &str) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut start = None;
    for (i, c) in text.char_indices() {
        match (c.is_whitespace(), start) {
            (true, Some(s)) => {
                out.push((s, i));
                start = None;
            }
            (false, None) => start = Some(i),
            _ => {}
        }
    }
    if let Some(s) = start {
        out.push((s, text.len()));
    }
    out
}

/// A token replaced by a boundary value, or by another token of `splice` when given.
fn replace_token(text: &str, rng: &mut Rng, splice: Option<&str>) -> String {
    let toks = tokens(text);
    if toks.is_empty() {
        return rng.pick(BOUNDARY).to_string();
    }
    let (a, b) = toks[rng.below(toks.len())];
    let with = match splice {
        Some(s) => {
            let other = tokens(s);
            let (c, d) = other[rng.below(other.len())];
            s[c..d].to_string()
        }
        None => rng.pick(BOUNDARY).to_string(),
    };
    format!("{}{}{}", &text[..a], with, &text[b..])
}

/// A number multiplied or shifted in place (keeps the file's shape, moves values across ranges).
fn scale_number(text: &str, rng: &mut Rng) -> String {
    let toks: Vec<(usize, usize)> = tokens(text)
        .into_iter()
        .filter(|&(a, b)| {
            text[a..b]
                .trim_matches(|c| c == ',' || c == ']')
                .parse::<f64>()
                .is_ok()
        })
        .collect();
    if toks.is_empty() {
        return replace_token(text, rng, None);
    }
    let (a, b) = toks[rng.below(toks.len())];
    let raw = text[a..b].trim_end_matches([',', ']']);
    let tail = &text[a + raw.len()..b];
    let v: f64 = raw.parse().unwrap_or(0.0);
    let new = match rng.below(5) {
        0 => v * 1e6,
        1 => -v,
        2 => v + 1.0,
        3 => (v as i64).wrapping_mul(1 << 20) as f64,
        _ => v / 1e6,
    };
    let new = if raw.contains('.') || raw.contains('e') {
        format!("{new}")
    } else {
        format!("{}", new as i64)
    };
    format!("{}{}{}{}", &text[..a], new, tail, &text[b..])
}

/// A line deleted, repeated, swapped with another or copied elsewhere.
fn edit_lines(text: &str, rng: &mut Rng) -> String {
    let mut lines: Vec<&str> = text.lines().collect();
    if lines.is_empty() {
        return text.to_string();
    }
    let i = rng.below(lines.len());
    let j = rng.below(lines.len());
    match rng.below(4) {
        0 => {
            lines.remove(i);
        }
        1 => {
            let l = lines[i];
            for _ in 0..1 + rng.below(3) {
                lines.insert(i, l);
            }
        }
        2 => lines.swap(i, j),
        _ => {
            let l = lines[i];
            lines.insert(j, l);
        }
    }
    let mut out = lines.join("\n");
    out.push('\n');
    out
}

fn char_boundary(text: &str, mut at: usize) -> usize {
    at = at.min(text.len());
    while !text.is_char_boundary(at) {
        at -= 1;
    }
    at
}

fn insert_structure(text: &str, rng: &mut Rng) -> String {
    let at = char_boundary(text, rng.below(text.len() + 1));
    format!("{}{}{}", &text[..at], rng.pick(STRUCTURE), &text[at..])
}

fn delete_span(text: &str, rng: &mut Rng) -> String {
    let a = char_boundary(text, rng.below(text.len() + 1));
    let b = char_boundary(text, a + 1 + rng.below(40));
    format!("{}{}", &text[..a], &text[b.max(a)..])
}

fn truncate(text: &str, rng: &mut Rng) -> String {
    text[..char_boundary(text, rng.below(text.len() + 1))].to_string()
}

/// The seeds of one reader: real files, cut down.
pub struct Seeds {
    pub texts: Vec<String>,
}

fn read(data: &Path, rel: &str) -> Result<String, String> {
    let p = data.join(rel);
    std::fs::read_to_string(&p).map_err(|e| {
        format!(
            "{}: {e} (the fuzz corpus is the data folder's files)",
            p.display()
        )
    })
}

/// The first `n` lines of `text` that `keep` accepts, with every line `always` accepts.
fn cut(text: &str, n: usize, always: impl Fn(&str) -> bool) -> String {
    let mut kept = 0;
    let mut out = String::new();
    for l in text.lines() {
        if always(l) || kept < n {
            if !always(l) {
                kept += 1;
            }
            out.push_str(l);
            out.push('\n');
        }
    }
    out
}

/// An OBJ cut to its first `n` vertices (and texture coordinates) and the faces among them.
fn small_obj(text: &str, n: usize) -> String {
    let mut out = String::new();
    let (mut v, mut vt) = (0, 0);
    for l in text.lines() {
        let t = l.split_whitespace().next().unwrap_or("");
        let keep = match t {
            "v" => {
                v += 1;
                v <= n
            }
            "vt" => {
                vt += 1;
                vt <= n
            }
            "f" => l.split_whitespace().skip(1).all(|c| {
                c.split('/')
                    .all(|i| i.is_empty() || i.parse::<usize>().is_ok_and(|i| i <= n))
            }),
            _ => true,
        };
        if keep {
            out.push_str(l);
            out.push('\n');
        }
    }
    out
}

/// A BVH with its hierarchy and the first `frames` frames.
fn small_bvh(text: &str, frames: usize) -> String {
    let Some(m) = text.find("MOTION") else {
        return text.to_string();
    };
    let mut out = text[..m].to_string();
    let mut lines = text[m..].lines();
    out.push_str("MOTION\n");
    lines.next();
    lines.next();
    out.push_str(&format!("Frames: {frames}\n"));
    for l in lines.take(frames + 1) {
        out.push_str(l);
        out.push('\n');
    }
    out
}

/// Skin weights JSON cut to `bones` bones of `entries` entries each.
fn small_mhw(text: &str, bones: usize, entries: usize) -> Result<String, String> {
    let mut v: serde_json::Value = serde_json::from_str(text).map_err(|e| e.to_string())?;
    if let Some(w) = v.get_mut("weights").and_then(|w| w.as_object_mut()) {
        let keys: Vec<String> = w.keys().skip(bones).cloned().collect();
        for k in keys {
            w.remove(&k);
        }
        for list in w.values_mut() {
            if let Some(a) = list.as_array_mut() {
                a.truncate(entries);
            }
        }
    }
    serde_json::to_string_pretty(&v).map_err(|e| e.to_string())
}

/// The seeds of `reader` from the data folder `data` and the repository `root`.
pub fn seeds(reader: &str, data: &Path, root: &Path) -> Result<Seeds, String> {
    let mhclo_head = |l: &str| !l.trim_start().starts_with(|c: char| c.is_ascii_digit());
    let texts = match reader {
        "obj" => vec![
            read(data, "keenan-crane-spot/spot_control_mesh.obj")?,
            small_obj(
                &read(
                    data,
                    "makehuman-assets/clothes/female_elegantsuit01/female_elegantsuit01.obj",
                )?,
                60,
            ),
            small_obj(
                &read(data, "makehuman-assets/proxymeshes/proxy741/proxy741.obj")?,
                60,
            ),
        ],
        "bvh" | "retarget" => vec![
            small_bvh(&read(data, "cmu-mocap-bvh/10_04.bvh")?, 3),
            small_bvh(&read(data, "cmu-mocap-bvh/131_01.bvh")?, 2),
        ],
        "mhskel" => vec![read(data, "makehuman-assets/rigs/cmu_mb.mhskel")?],
        "mhw" => vec![small_mhw(
            &read(data, "makehuman/default_weights.mhw")?,
            4,
            12,
        )?],
        "target" => vec![
            cut(
                &read(
                    data,
                    "makehuman/targets/measure/measure-waist-circ-incr.target",
                )?,
                40,
                |_| false,
            ),
            cut(
                &read(
                    data,
                    "makehuman/targets/macrodetails/asian-female-young.target",
                )?,
                40,
                |_| false,
            ),
        ],
        "mhclo" => vec![
            cut(
                &read(
                    data,
                    "makehuman-assets/clothes/female_elegantsuit01/female_elegantsuit01.mhclo",
                )?,
                40,
                mhclo_head,
            ),
            cut(
                &read(data, "makehuman-assets/proxymeshes/proxy741/proxy741.proxy")?,
                40,
                mhclo_head,
            ),
        ],
        "scene" => {
            let dir = root.join("data/scenes");
            let mut paths: Vec<_> = std::fs::read_dir(&dir)
                .map_err(|e| format!("{}: {e}", dir.display()))?
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.extension().is_some_and(|x| x == "toml"))
                .collect();
            paths.sort();
            let mut t: Vec<String> = paths
                .iter()
                .filter_map(|p| std::fs::read_to_string(p).ok())
                .collect();
            t.push(tryon_pipeline::DEMO_SCENE.to_string());
            t
        }
        other => return Err(format!("unknown reader `{other}`")),
    };
    Ok(Seeds { texts })
}

/// `--set` overrides for a scene case: keys of the seed's own tables, values at the edges.
pub fn overrides(seed: &str, rng: &mut Rng) -> Vec<String> {
    let mut keys = Vec::new();
    let mut table = String::new();
    for l in seed.lines() {
        let l = l.trim();
        if l.starts_with('[') {
            table = l.trim_matches(|c| c == '[' || c == ']').to_string();
        } else if let Some((k, _)) = l.split_once('=')
            && !l.starts_with('#')
        {
            keys.push(format!("{table}.{}", k.trim()));
        }
    }
    keys.extend(
        [
            "scene.fps",
            "effects.refine",
            "cloth.solver",
            "body.kind",
            "garment.kind",
            "nope.x",
            "scene",
        ]
        .map(String::from),
    );
    const VALUES: &[&str] = &[
        "0",
        "-1",
        "1e300",
        "nan",
        "inf",
        "\"\"",
        "\"x\"",
        "[1,2,3,99]",
        "[]",
        "true",
        "{a=1}",
        "\"../../x\"",
        "1e-300",
        "4294967296",
        "=",
        "[[1,2]]",
        "'",
        "\"p1\"",
        "\"vbd\"",
        "3",
    ];
    (0..rng.below(4))
        .map(|_| {
            let k = &keys[rng.below(keys.len())];
            format!("{k}={}", VALUES[rng.below(VALUES.len())])
        })
        .collect()
}
