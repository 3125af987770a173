//! Wavefront OBJ reader that keeps the file's vertex order exactly: MakeHuman's weights, targets,
//! bindings and skeletons refer to vertices by their index in the file, so nothing is regrouped,
//! welded or renumbered. Reads `v`, `vt`, `f` (triangles and quads; larger polygons become fans),
//! `g`/`o` groups; other statements (normals, materials, smoothing) are skipped.

use crate::read::{At, ReadError, read_text};
use std::path::Path;
use tryon_core::assets::ObjMesh;
use tryon_core::math::Vec3;
use tryon_core::mesh::Face;

/// Most vertices (and faces) an OBJ may have.
pub const MAX_OBJ_ELEMENTS: usize = 20_000_000;

/// Reads an OBJ file in its own units.
pub fn read_obj(path: &Path) -> Result<ObjMesh, ReadError> {
    parse_obj(&read_text(path)?, path)
}

/// Parses OBJ text; `file` names the source in errors.
pub fn parse_obj(text: &str, file: &Path) -> Result<ObjMesh, ReadError> {
    let mut m = ObjMesh::default();
    let mut uv_faces: Vec<Option<Face>> = Vec::new();
    let mut group: Option<(String, usize)> = None;
    for (i, raw) in text.lines().enumerate() {
        let at = At { file, line: i + 1 };
        let line = raw.split('#').next().unwrap_or("");
        let mut tok = line.split_whitespace();
        let Some(key) = tok.next() else { continue };
        match key {
            "v" => {
                if m.positions.len() >= MAX_OBJ_ELEMENTS {
                    return Err(at.limit("vertex count", MAX_OBJ_ELEMENTS));
                }
                let x = at.coordinate(tok.next(), "vertex x")?;
                let y = at.coordinate(tok.next(), "vertex y")?;
                let z = at.coordinate(tok.next(), "vertex z")?;
                m.positions.push(Vec3::new(x, y, z));
            }
            "vt" => {
                let u = at.real(tok.next(), "texture u")?;
                let v = at.real(tok.next(), "texture v").unwrap_or(0.0);
                m.uvs.push([u, v]);
            }
            "f" => {
                if m.faces.len() >= MAX_OBJ_ELEMENTS {
                    return Err(at.limit("face count", MAX_OBJ_ELEMENTS));
                }
                let mut vs = Vec::with_capacity(4);
                let mut ts = Vec::with_capacity(4);
                for t in tok {
                    let mut parts = t.split('/');
                    let v = resolve(&at, parts.next(), m.positions.len(), VERTEX)?
                        .ok_or_else(|| at.err("face corner without a vertex index"))?;
                    vs.push(v);
                    ts.push(resolve(&at, parts.next(), m.uvs.len(), TEXTURE)?);
                }
                if vs.len() < 3 {
                    return Err(at.err(format!(
                        "a face needs at least 3 vertices, this one has {}",
                        vs.len()
                    )));
                }
                for a in 0..vs.len() {
                    if vs[a + 1..].contains(&vs[a]) {
                        return Err(
                            at.err(format!("face lists vertex {} more than once", vs[a] + 1))
                        );
                    }
                }
                let uv = if ts.iter().all(Option::is_some) {
                    Some(ts.iter().map(|t| t.unwrap_or(0)).collect::<Vec<_>>())
                } else {
                    None
                };
                for (f, t) in polygon(&vs, uv.as_deref()) {
                    m.faces.push(f);
                    uv_faces.push(t);
                }
            }
            "g" | "o" => {
                let name = tok.collect::<Vec<_>>().join(" ");
                close_group(&mut m, group.take());
                group = Some((name, m.faces.len()));
            }
            _ => {}
        }
    }
    close_group(&mut m, group);
    if !uv_faces.is_empty() && uv_faces.iter().all(Option::is_some) {
        m.face_uvs = uv_faces.into_iter().flatten().collect();
    }
    Ok(m)
}

fn close_group(m: &mut ObjMesh, group: Option<(String, usize)>) {
    if let Some((name, start)) = group {
        m.groups.push((name, start..m.faces.len()));
    }
}

/// What an index counts, in the singular and the plural.
const VERTEX: [&str; 2] = ["vertex", "vertices"];
const TEXTURE: [&str; 2] = ["texture coordinate", "texture coordinates"];

/// A 1-based (or negative, relative) OBJ index into `count` elements; `Ok(None)` when absent.
fn resolve(
    at: &At,
    tok: Option<&str>,
    count: usize,
    [what, many]: [&str; 2],
) -> Result<Option<u32>, ReadError> {
    let Some(tok) = tok.filter(|t| !t.is_empty()) else {
        return Ok(None);
    };
    let i: i64 = tok
        .parse()
        .map_err(|_| at.err(format!("expected a {what} index, found `{tok}`")))?;
    let idx = if i > 0 { i - 1 } else { count as i64 + i };
    if i == 0 || idx < 0 || idx >= count as i64 {
        return Err(at.err(format!(
            "{what} index {i} is out of range: {count} {} defined before this line",
            match count {
                1 => format!("{what} is"),
                _ => format!("{many} are"),
            }
        )));
    }
    Ok(Some(idx as u32))
}

/// A polygon as one face (triangle or quad) or a fan of triangles, with matching UV faces.
fn polygon(vs: &[u32], uv: Option<&[u32]>) -> Vec<(Face, Option<Face>)> {
    let face = |idx: &[u32]| match idx.len() {
        3 => Face::Tri([idx[0], idx[1], idx[2]]),
        _ => Face::Quad([idx[0], idx[1], idx[2], idx[3]]),
    };
    if vs.len() <= 4 {
        return vec![(face(vs), uv.map(face))];
    }
    (1..vs.len() - 1)
        .map(|k| {
            let tri = |i: &[u32]| Face::Tri([i[0], i[k], i[k + 1]]);
            (tri(vs), uv.map(tri))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(s: &str) -> Result<ObjMesh, ReadError> {
        parse_obj(s, Path::new("t.obj"))
    }

    #[test]
    fn keeps_vertex_order_groups_quads_and_uvs() {
        let m = parse(
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\r\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n\
             g a\nf 1/1 2/2 3/3 4/4\ng b\nf 2/2 5/1 3/3\n",
        )
        .unwrap();
        assert_eq!(m.positions[4], Vec3::new(2.0, 0.0, 0.0));
        assert_eq!(
            m.faces,
            vec![Face::Quad([0, 1, 2, 3]), Face::Tri([1, 4, 2])]
        );
        assert_eq!(m.face_uvs[1], Face::Tri([1, 0, 2]));
        assert_eq!(m.group_faces("b"), vec![1]);
        assert_eq!(m.group_vertices("b"), vec![1, 2, 4]);
    }

    #[test]
    fn negative_indices_and_fans() {
        let m = parse("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv -1 1 0\nf -5 -4 -3 -2 -1\n").unwrap();
        assert_eq!(m.faces.len(), 3);
        assert_eq!(m.faces[2], Face::Tri([0, 3, 4]));
        assert!(m.face_uvs.is_empty());
    }

    #[test]
    fn malformed_files_name_the_line() {
        for (text, line, needle) in [
            ("v 0 0 0\nv 1 x 0\n", 2, "vertex y"),
            (
                "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n",
                4,
                "3 vertices are defined",
            ),
            ("v 0 0 0\nf 1 2 3\n", 2, "1 vertex is defined"),
            (
                "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/2 3/1\n",
                5,
                "1 texture coordinate is",
            ),
            ("v 0 0 0\nv 1 0 0\nf 1 2\n", 3, "at least 3"),
            ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 2\n", 4, "more than once"),
            ("v 0 0 nan\n", 1, "finite"),
            ("v 0 0 0\nv 1e300 0 0\n", 2, "vertex x 1e300 is beyond"),
            (
                "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/9 2 3\n",
                4,
                "texture coordinate index",
            ),
            ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", 4, "out of range"),
        ] {
            let e = parse(text).unwrap_err();
            assert_eq!(e.line(), Some(line), "{text:?}: {e}");
            assert!(e.to_string().contains(needle), "{e}");
            assert!(e.to_string().starts_with("t.obj:"), "{e}");
        }
    }
}
