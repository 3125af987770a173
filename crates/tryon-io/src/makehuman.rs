//! MakeHuman readers: skeletons (.mhskel), skin weights (.mhw), morph targets (.target) and garment
//! or proxy bindings (.mhclo, .proxy). MakeHuman works in decimetres; everything is converted to
//! metres here. Vertex indices refer to base.obj's own vertex order (read it with [`crate::read_obj`]).

use crate::read::{At, ReadError, json_error, read_text, short};
use serde::Deserialize;
use std::collections::{BTreeMap, HashMap};
use std::path::Path;
use tryon_core::assets::{
    ClothBinding, MakeHumanAssets, MhBone, MhSkeleton, MhWeights, MorphTarget, ScaleRef,
};
use tryon_core::math::{Real, Vec3};

/// Metres per MakeHuman unit (decimetres).
pub const MH_UNIT: Real = 0.1;
/// Most entries (bones, weights, offsets, bound vertices) one MakeHuman file may hold.
pub const MAX_MH_ENTRIES: usize = 10_000_000;

#[derive(Deserialize)]
struct SkelFile {
    #[serde(default)]
    name: String,
    bones: BTreeMap<String, BoneFile>,
    joints: BTreeMap<String, Vec<u32>>,
}

#[derive(Deserialize)]
struct BoneFile {
    head: String,
    tail: String,
    parent: Option<String>,
    #[serde(default)]
    reference: Option<Vec<String>>,
    #[serde(default)]
    weights_reference: Option<Vec<String>>,
}

/// 1-based line of the first occurrence of `"key"` in `text` (1 when absent).
fn line_of(text: &str, key: &str) -> usize {
    let quoted = format!("\"{key}\"");
    text.find(&quoted)
        .map_or(1, |i| text[..i].matches('\n').count() + 1)
}

/// Reads a .mhskel skeleton; bones come out parents first.
pub fn read_mhskel(path: &Path) -> Result<MhSkeleton, ReadError> {
    parse_mhskel(&read_text(path)?, path)
}

/// Parses .mhskel JSON; `file` names the source in errors.
pub fn parse_mhskel(text: &str, file: &Path) -> Result<MhSkeleton, ReadError> {
    let s: SkelFile = serde_json::from_str(text).map_err(|e| json_error(file, e))?;
    let at = |key: &str| At {
        file,
        line: line_of(text, key),
    };
    if s.bones.len() > MAX_MH_ENTRIES {
        return Err(at("bones").limit("bone count", MAX_MH_ENTRIES));
    }
    let joint = |name: &str, bone: &str| -> Result<Vec<u32>, ReadError> {
        s.joints.get(name).cloned().ok_or_else(|| {
            at(bone).err(format!(
                "bone `{bone}` refers to joint `{name}`, which `joints` does not define"
            ))
        })
    };
    // Order parents first: the order of repeated passes over the alphabetical map, each placing
    // every bone whose parent is already placed, computed in one walk up each parent chain.
    let names: Vec<&String> = s.bones.keys().collect();
    let index: HashMap<&str, usize> = names
        .iter()
        .enumerate()
        .map(|(i, n)| (n.as_str(), i))
        .collect();
    let mut parent = Vec::with_capacity(names.len());
    for n in &names {
        parent.push(match &s.bones[*n].parent {
            None => None,
            Some(p) => Some(*index.get(p.as_str()).ok_or_else(|| {
                at(n).err(format!(
                    "bone `{n}` has parent `{p}`, which is not a bone of this skeleton"
                ))
            })?),
        });
    }
    let pass = passes(&parent).map_err(|stuck| {
        let stuck = names[stuck];
        at(stuck).err(format!("bone `{stuck}` is part of a parent cycle"))
    })?;
    let mut order: Vec<usize> = (0..names.len()).collect();
    order.sort_by_key(|&i| (pass[i], i));
    let mut bones: Vec<MhBone> = Vec::with_capacity(order.len());
    for &i in &order {
        let name = names[i];
        let b = &s.bones[name];
        let parent = match &b.parent {
            Some(p) => bones.iter().position(|x| &x.name == p),
            None => None,
        };
        bones.push(MhBone {
            name: name.clone(),
            parent,
            head: joint(&b.head, name)?,
            tail: joint(&b.tail, name)?,
            reference: b.reference.clone().unwrap_or_default(),
            weights_reference: b.weights_reference.clone().unwrap_or_default(),
        });
    }
    Ok(MhSkeleton {
        name: s.name,
        bones,
    })
}

/// The pass of repeated in-order sweeps in which each bone is placed (roots in pass 0; a bone in
/// its parent's pass when the parent comes before it, else in the next), or a bone on a cycle.
fn passes(parent: &[Option<usize>]) -> Result<Vec<usize>, usize> {
    const UNKNOWN: usize = usize::MAX;
    let mut pass = vec![UNKNOWN; parent.len()];
    let mut chain = Vec::new();
    for start in 0..parent.len() {
        // Walk up to a bone whose pass is known (or a root), then fill the chain back down.
        let mut b = start;
        while pass[b] == UNKNOWN {
            if chain.len() > parent.len() {
                // Past as many steps as there are bones, the walk is going round a cycle.
                return Err(b);
            }
            chain.push(b);
            match parent[b] {
                Some(p) => b = p,
                None => break,
            }
        }
        while let Some(c) = chain.pop() {
            pass[c] = match parent[c] {
                None => 0,
                Some(p) if pass[p] == UNKNOWN => return Err(c),
                Some(p) if p < c => pass[p],
                Some(p) => pass[p] + 1,
            };
        }
    }
    Ok(pass)
}

#[derive(Deserialize)]
struct WeightsFile {
    weights: BTreeMap<String, Vec<(u32, f64)>>,
}

/// Reads .mhw skin weights as listed (normalising and keeping the strongest four is the skinning
/// stage's job: `body_model::SkinWeights::from_influences`).
pub fn read_mhw(path: &Path) -> Result<MhWeights, ReadError> {
    parse_mhw(&read_text(path)?, path)
}

/// Parses .mhw JSON; `file` names the source in errors.
pub fn parse_mhw(text: &str, file: &Path) -> Result<MhWeights, ReadError> {
    let w: WeightsFile = serde_json::from_str(text).map_err(|e| json_error(file, e))?;
    let total: usize = w.weights.values().map(Vec::len).sum();
    if total > MAX_MH_ENTRIES {
        return Err(At { file, line: 1 }.limit("weight count", MAX_MH_ENTRIES));
    }
    for (bone, list) in &w.weights {
        if let Some((v, x)) = list.iter().find(|(_, x)| !(x.is_finite() && *x >= 0.0)) {
            return Err(At {
                file,
                line: line_of(text, bone),
            }
            .err(format!(
                "bone `{bone}`: weight {x} of vertex {v} is not a finite non-negative number"
            )));
        }
    }
    Ok(MhWeights {
        bones: w.weights.into_iter().collect(),
    })
}

/// Reads a .target morph target (offsets converted to metres).
pub fn read_target(path: &Path) -> Result<MorphTarget, ReadError> {
    let name = path
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("")
        .to_string();
    let mut t = parse_target(&read_text(path)?, path)?;
    t.name = name;
    Ok(t)
}

/// Parses .target text (`vertex dx dy dz` lines, `#` comments).
pub fn parse_target(text: &str, file: &Path) -> Result<MorphTarget, ReadError> {
    let mut offsets = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let at = At { file, line: i + 1 };
        let line = line.split('#').next().unwrap_or("");
        let mut tok = line.split_whitespace();
        let Some(first) = tok.next() else { continue };
        if offsets.len() >= MAX_MH_ENTRIES {
            return Err(at.limit("offset count", MAX_MH_ENTRIES));
        }
        let v = at.index(Some(first), "a vertex index")?;
        let d = Vec3::new(
            at.real(tok.next(), "dx")?,
            at.real(tok.next(), "dy")?,
            at.real(tok.next(), "dz")?,
        );
        if let Some(extra) = tok.next() {
            return Err(at.err(format!("expected `vertex dx dy dz`, found extra `{extra}`")));
        }
        offsets.push((v, d * MH_UNIT));
    }
    Ok(MorphTarget {
        name: String::new(),
        offsets,
    })
}

/// Reads a .mhclo garment binding or a .proxy body binding (same format).
pub fn read_binding(path: &Path) -> Result<ClothBinding, ReadError> {
    parse_binding(&read_text(path)?, path)
}

/// Parses .mhclo/.proxy text; `file` names the source in errors.
pub fn parse_binding(text: &str, file: &Path) -> Result<ClothBinding, ReadError> {
    #[derive(PartialEq)]
    enum Section {
        Header,
        Verts,
        Delete,
    }
    let mut b = ClothBinding::default();
    let mut section = Section::Header;
    for (i, line) in text.lines().enumerate() {
        let at = At { file, line: i + 1 };
        let line = line.split('#').next().unwrap_or("");
        let toks: Vec<&str> = line.split_whitespace().collect();
        let Some(&first) = toks.first() else { continue };
        let numeric = first.parse::<f64>().is_ok();
        if numeric && section == Section::Verts {
            if b.refs.len() >= MAX_MH_ENTRIES {
                return Err(at.limit("bound vertex count", MAX_MH_ENTRIES));
            }
            binding_line(&at, &toks, &mut b)?;
            continue;
        }
        if numeric && section == Section::Delete {
            delete_line(&at, &toks, &mut b.delete_verts)?;
            continue;
        }
        section = Section::Header;
        match first {
            "name" => b.name = toks[1..].join(" "),
            "obj_file" => b.obj_file = toks[1..].join(" "),
            "x_scale" | "y_scale" | "z_scale" => {
                let axis = (first.as_bytes()[0] - b'x') as usize;
                let a = at.index(toks.get(1).copied(), "the first scale vertex")?;
                let c = at.index(toks.get(2).copied(), "the second scale vertex")?;
                let rest = at.real(toks.get(3).copied(), "the rest distance")?;
                if !(rest > 0.0) {
                    return Err(at.err(format!(
                        "{first}: the rest distance must be positive, found {rest}"
                    )));
                }
                b.scales[axis] = Some(ScaleRef {
                    a,
                    b: c,
                    rest: rest * MH_UNIT,
                });
            }
            "verts" => section = Section::Verts,
            "delete_verts" => section = Section::Delete,
            _ if numeric => {
                return Err(at.err("numbers outside a `verts` or `delete_verts` section"));
            }
            _ => {}
        }
    }
    if b.refs.is_empty() {
        return Err(At {
            file,
            line: text.lines().count().max(1),
        }
        .err("no bound vertices: expected a `verts` section"));
    }
    Ok(b)
}

/// One `verts` line: `v` (exactly a base vertex) or `v0 v1 v2 w0 w1 w2 dx dy dz`.
fn binding_line(at: &At, toks: &[&str], b: &mut ClothBinding) -> Result<(), ReadError> {
    match toks.len() {
        1 => {
            let v = at.index(Some(toks[0]), "a base vertex")?;
            b.refs.push([v; 3]);
            b.weights.push([1.0, 0.0, 0.0]);
            b.offsets.push(Vec3::zeros());
        }
        9 => {
            let mut r = [0u32; 3];
            let mut w = [0.0; 3];
            let mut d = Vec3::zeros();
            for k in 0..3 {
                r[k] = at.index(Some(toks[k]), "a reference vertex")?;
                w[k] = at.real(Some(toks[3 + k]), "a weight")?;
                d[k] = at.real(Some(toks[6 + k]), "an offset")? * MH_UNIT;
            }
            check_bound(at, w, d)?;
            b.refs.push(r);
            b.weights.push(w);
            b.offsets.push(d);
        }
        n => {
            return Err(at.err(format!(
                "a bound vertex needs 1 or 9 numbers (3 vertices, 3 weights, 3 offsets), found {n}"
            )));
        }
    }
    Ok(())
}

/// A bound vertex's weights mix its three body vertices (they sum to 1: MakeHuman writes them to
/// five decimals) and its offset is a garment's distance from the body, not kilometres.
fn check_bound(at: &At, w: [f64; 3], d: Vec3) -> Result<(), ReadError> {
    let sum = w[0] + w[1] + w[2];
    if (sum - 1.0).abs() > MAX_WEIGHT_SUM_ERROR {
        return Err(at.err(format!(
            "the weights {} {} {} sum to {}; a bound vertex's weights sum to 1 (within {MAX_WEIGHT_SUM_ERROR})",
            short(w[0]),
            short(w[1]),
            short(w[2]),
            short((sum * 1e5).round() / 1e5)
        )));
    }
    if let Some(x) = w.iter().find(|x| x.abs() > MAX_WEIGHT) {
        return Err(at.err(format!(
            "a weight of {} is out of range (-{MAX_WEIGHT}..={MAX_WEIGHT})",
            short(*x)
        )));
    }
    if d.amax() > MAX_OFFSET_M {
        return Err(at.err(format!(
            "an offset of {:.3e} m is out of range (at most {MAX_OFFSET_M} m from the body)",
            d.amax()
        )));
    }
    Ok(())
}

/// How far a bound vertex's weights may sum from 1.
const MAX_WEIGHT_SUM_ERROR: f64 = 0.01;
/// The largest weight accepted (MakeHuman's garments use -0.9 to 2.7).
const MAX_WEIGHT: f64 = 100.0;
/// The largest offset from the body accepted, m (MakeHuman's garments use up to 0.22).
const MAX_OFFSET_M: f64 = 10.0;

/// One `delete_verts` line: indices and `a - b` ranges.
fn delete_line(at: &At, toks: &[&str], out: &mut Vec<u32>) -> Result<(), ReadError> {
    let mut k = 0;
    while k < toks.len() {
        let a = at.index(Some(toks[k]), "a vertex to delete")?;
        if toks.get(k + 1) == Some(&"-") {
            let b = at.index(toks.get(k + 2).copied(), "the end of a vertex range")?;
            if b < a || (b - a) as usize > MAX_MH_ENTRIES {
                return Err(at.err(format!("bad vertex range {a} - {b}")));
            }
            if out.len() + (b - a) as usize >= MAX_MH_ENTRIES {
                return Err(at.limit("deleted vertex count", MAX_MH_ENTRIES));
            }
            out.extend(a..=b);
            k += 3;
        } else {
            if out.len() >= MAX_MH_ENTRIES {
                return Err(at.limit("deleted vertex count", MAX_MH_ENTRIES));
            }
            out.push(a);
            k += 1;
        }
    }
    Ok(())
}

/// Which rig skins a MakeHuman body.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MhRig {
    /// The 163-bone default rig and its weights.
    Default,
    /// The 31-bone cmu_mb rig (CMU joint names), weighted through `weights_reference`.
    CmuMb,
}

/// Every .target file of a folder, sorted by name.
pub fn read_targets(dir: &Path) -> Result<Vec<MorphTarget>, ReadError> {
    let entries = std::fs::read_dir(dir).map_err(|source| ReadError::Io {
        file: dir.to_path_buf(),
        source,
    })?;
    let mut paths: Vec<_> = entries.filter_map(|e| e.ok().map(|e| e.path())).collect();
    paths.sort();
    paths
        .iter()
        .filter(|p| p.extension().is_some_and(|e| e == "target"))
        .map(|p| read_target(p))
        .collect()
}

/// Loads base.obj (metres), the default rig and weights, the chosen rig and every measurement
/// and macro target from a MakeHuman data folder laid out as ../shared/data is.
pub fn load_makehuman(data: &Path, rig: MhRig) -> Result<MakeHumanAssets, ReadError> {
    let mh = data.join("makehuman");
    let mut base = crate::read_obj(&mh.join("base.obj"))?;
    for p in &mut base.positions {
        *p *= MH_UNIT;
    }
    let rig = match rig {
        MhRig::Default => None,
        MhRig::CmuMb => Some(read_mhskel(
            &data.join("makehuman-assets/rigs/cmu_mb.mhskel"),
        )?),
    };
    let targets = read_targets(&mh.join("targets/measure"))?;
    let macros = read_targets(&mh.join("targets/macrodetails"))?;
    Ok(MakeHumanAssets {
        base,
        default_rig: read_mhskel(&mh.join("default.mhskel"))?,
        weights: read_mhw(&mh.join("default_weights.mhw"))?,
        rig,
        targets,
        macros,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p() -> &'static Path {
        Path::new("t")
    }

    #[test]
    fn skeleton_orders_parents_first_and_resolves_joints() {
        let text = r#"{"name":"s","bones":{
            "a":{"head":"a_h","tail":"a_t","parent":"b","reference":null},
            "b":{"head":"b_h","tail":"a_h","parent":null,"reference":["x"],"weights_reference":["y","z"]}},
          "joints":{"a_h":[1,2],"a_t":[3],"b_h":[0]}}"#;
        let s = parse_mhskel(text, p()).unwrap();
        assert_eq!(s.bones[0].name, "b");
        assert_eq!(s.bones[1].parent, Some(0));
        assert_eq!(s.bones[1].head, vec![1, 2]);
        assert_eq!(s.bones[0].weights_reference, vec!["y", "z"]);
        let bad = text.replace(r#""parent":"b""#, r#""parent":"q""#);
        let e = parse_mhskel(&bad, p()).unwrap_err();
        assert!(e.to_string().contains("parent `q`"), "{e}");
        assert_eq!(e.line(), Some(2));
        let e = parse_mhskel(&text.replace("\"a_t\":[3],", ""), p()).unwrap_err();
        assert!(e.to_string().contains("joint `a_t`"), "{e}");
        let e = parse_mhskel("{\"bones\": [}", p()).unwrap_err();
        assert!(matches!(e, ReadError::Json { line: 1, .. }), "{e}");
    }

    #[test]
    fn weights_and_targets() {
        let w = parse_mhw(r#"{"weights":{"a":[[0,0.5],[3,1.0]]}}"#, p()).unwrap();
        assert_eq!(w.bones[0].1, vec![(0, 0.5), (3, 1.0)]);
        let e = parse_mhw("{\"weights\":{\n\"a\":[[0,-1]]}}", p()).unwrap_err();
        assert_eq!(e.line(), Some(2), "{e}");
        let t = parse_target("# c\n4 0.1 0 -1\n\n7 0 0 2\n", p()).unwrap();
        assert_eq!(t.offsets[1], (7, Vec3::new(0.0, 0.0, 0.2)));
        let e = parse_target("4 0.1 0 -1\n7 0 zz 2\n", p()).unwrap_err();
        assert_eq!(e.line(), Some(2));
        assert!(e.to_string().contains("dy"), "{e}");
    }

    #[test]
    fn bindings() {
        let text = "name g\nobj_file g.obj\nx_scale 1 2 1.5\nverts 0\n5\n1 2 3 0.2 0.3 0.5 0.1 0 -0.1\ndelete_verts\n4 - 6 9\n";
        let b = parse_binding(text, p()).unwrap();
        assert_eq!(b.refs, vec![[5; 3], [1, 2, 3]]);
        assert_eq!(b.weights[0], [1.0, 0.0, 0.0]);
        assert!((b.offsets[1] - Vec3::new(0.01, 0.0, -0.01)).norm() < 1e-15);
        assert_eq!(b.scales[0].map(|s| s.rest), Some(0.15000000000000002));
        assert!(b.scales[1].is_none());
        assert_eq!(b.delete_verts, vec![4, 5, 6, 9]);
        let e = parse_binding(&text.replace("0.1 0 -0.1", "0.1 0"), p()).unwrap_err();
        assert_eq!(e.line(), Some(6));
        assert!(e.to_string().contains("1 or 9 numbers"), "{e}");
        let e = parse_binding("name g\n", p()).unwrap_err();
        assert!(e.to_string().contains("no bound vertices"), "{e}");
    }

    #[test]
    fn bindings_with_weights_that_do_not_mix_or_offsets_far_away_are_refused_at_their_line() {
        let head = "name g\nverts 0\n";
        for (line, says) in [
            ("1 2 3 0 0 0 0 0 0", "sum to 0;"),
            ("1 2 3 0.5 0.2 0.2 0 0 0", "sum to 0.9"),
            ("1 2 3 1e30 0 0 0 0 0", "the weights 1e30 0 0 sum to 1e30"),
            (
                "1 2 3 -200 100.5 100.5 0 0 0",
                "a weight of -200 is out of range",
            ),
            (
                "1 2 3 0.2 0.3 0.5 0 0 1e6",
                "an offset of 1.000e5 m is out of range",
            ),
        ] {
            let e = parse_binding(&format!("{head}{line}\n"), p()).unwrap_err();
            assert_eq!(e.line(), Some(3), "{e}");
            assert!(e.to_string().contains(says), "{line}: {e}");
        }
        // MakeHuman's own rounding (five decimals) passes.
        parse_binding(&format!("{head}1 2 3 0.33333 0.33333 0.33333 0 0 0\n"), p()).unwrap();
        let e = parse_binding(
            "name g\nverts 0\n5\ndelete_verts\n0 - 9000000 0 - 9000000\n",
            p(),
        )
        .unwrap_err();
        assert!(e.to_string().contains("deleted vertex count"), "{e}");
    }

    /// The passes as the loop over the bones computed them before (the oracle).
    fn passes_by_sweeps(parent: &[Option<usize>]) -> Option<Vec<usize>> {
        let mut pass = vec![usize::MAX; parent.len()];
        let mut placed = 0;
        for k in 0.. {
            let before = placed;
            for i in 0..parent.len() {
                let ready = match parent[i] {
                    None => true,
                    Some(p) => pass[p] != usize::MAX,
                };
                if pass[i] == usize::MAX && ready {
                    pass[i] = k;
                    placed += 1;
                }
            }
            if placed == parent.len() {
                return Some(pass);
            }
            if placed == before {
                return None;
            }
        }
        None
    }

    #[test]
    fn bones_are_ordered_as_repeated_sweeps_order_them_in_one_walk() {
        let mut state = 12345u64;
        let mut next = |n: usize| {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 33) as usize % n
        };
        for case in 0..500 {
            let n = 1 + next(12);
            let parent: Vec<Option<usize>> = (0..n)
                .map(|_| if next(4) == 0 { None } else { Some(next(n)) })
                .collect();
            match (passes(&parent), passes_by_sweeps(&parent)) {
                (Ok(a), Some(b)) => assert_eq!(a, b, "case {case}: {parent:?}"),
                (Err(c), None) => {
                    // The bone named is on a cycle: its parents lead back to it.
                    let mut b = parent[c];
                    let mut steps = 0;
                    while b != Some(c) && steps <= n {
                        b = b.and_then(|x| parent[x]);
                        steps += 1;
                    }
                    assert_eq!(
                        b,
                        Some(c),
                        "case {case}: {c} is not on a cycle in {parent:?}"
                    );
                }
                (a, b) => panic!("case {case}: {a:?} vs {b:?} for {parent:?}"),
            }
        }
        // A chain of 100,000 bones listed against its order: the sweeps took one pass a bone.
        let n = 100_000;
        let chain: Vec<Option<usize>> = (0..n).map(|i| (i + 1 < n).then_some(i + 1)).collect();
        let pass = passes(&chain).unwrap();
        assert_eq!((pass[n - 1], pass[0]), (0, n - 1));
    }
}
