//! P4's object body: a user's OBJ, mended where it can be (faces turned outward, duplicate
//! vertices welded, slivers dropped, each said in a warning) and stood on a table.

use crate::build::AssembleError;
use crate::real;
use crate::scene::{ObjectBody, Scene};
use tryon_core::math::{Real, Vec3};
use tryon_core::mesh::{Face, PolyMesh};
use tryon_core::shapes::table_slab;

/// P4's scene body: the scene's OBJ scaled to metres, welded (duplicate vertices merged, sliver
/// faces dropped: the warning says how many), centred over the origin and standing on a closed
/// table slab whose top is y = 0.
pub(crate) fn object_on_table(
    scene: &Scene,
    b: &ObjectBody,
) -> Result<(PolyMesh, Vec<String>), AssembleError> {
    let path = real::resolve(scene, "body.file", &b.file)?;
    let obj = tryon_io::read_obj(&path).map_err(real::AssetError::from)?;
    let scale = b.scale;
    let mut mesh = PolyMesh {
        positions: obj.positions.iter().map(|p| p * scale).collect(),
        faces: obj.faces,
    };
    if mesh.faces.is_empty() {
        return Err(AssembleError::EmptyObject {
            file: path.display().to_string(),
        });
    }
    let mut warnings = Vec::new();
    // Faces wound inward would put the cloth inside the object: turn them out.
    let volume = mesh.signed_volume();
    if volume < 0.0 {
        mesh = mesh.flipped();
        warnings.push(format!(
            "{}: the faces point inward (enclosed volume {volume:.3e} m^3): turned outward",
            path.display()
        ));
    }
    let (mut lo, mut hi) = (
        Vec3::repeat(Real::INFINITY),
        Vec3::repeat(Real::NEG_INFINITY),
    );
    for p in &mesh.positions {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    let shift = Vec3::new(-(lo.x + hi.x) / 2.0, -lo.y, -(lo.z + hi.z) / 2.0);
    for p in &mut mesh.positions {
        *p += shift;
    }
    let side = b.table;
    if side > 0.0 {
        let cells = ((side / 0.03).ceil() as usize).clamp(2, 200);
        let slab = table_slab(side, 0.04, cells);
        let base = mesh.positions.len() as u32;
        mesh.positions.extend_from_slice(&slab.positions);
        mesh.faces.extend(slab.faces.iter().map(|f| match f {
            Face::Tri(t) => Face::Tri(t.map(|v| v + base)),
            Face::Quad(q) => Face::Quad(q.map(|v| v + base)),
        }));
    }
    // Welded after the table joins: an object touching the table at a vertex of its top shares it.
    let (mesh, welding) = mesh.welded();
    if welding.changed() {
        warnings.push(format!(
            "{}: welded: {} duplicate vertices merged, {} sliver faces dropped",
            path.display(),
            welding.merged_vertices,
            welding.dropped_faces
        ));
    }
    Ok((mesh, warnings))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    /// An octahedron of radius 0.1 m, each face with its own three vertices (a triangle soup,
    /// as exporters write seams), wound `outward` or not.
    fn soup(outward: bool) -> String {
        let c = [
            [0.1, 0.0, 0.0],
            [-0.1, 0.0, 0.0],
            [0.0, 0.1, 0.0],
            [0.0, -0.1, 0.0],
            [0.0, 0.0, 0.1],
            [0.0, 0.0, -0.1],
        ];
        let mut text = String::new();
        let mut f = 0;
        for x in [0, 1] {
            for y in [2, 3] {
                for z in [4, 5] {
                    // Outward when the corners' x, y, z signs make a right-handed turn.
                    let odd = (x + (y - 2) + (z - 4)) % 2 == 1;
                    let tri = if odd == outward { [x, z, y] } else { [x, y, z] };
                    for v in tri {
                        let p = c[v];
                        text += &format!("v {} {} {}\n", p[0], p[1], p[2]);
                    }
                    text += &format!("f {} {} {}\n", 3 * f + 1, 3 * f + 2, 3 * f + 3);
                    f += 1;
                }
            }
        }
        text
    }

    fn scene_with(dir: &Path, name: &str, obj: &str) -> Scene {
        std::fs::create_dir_all(dir).unwrap();
        std::fs::write(dir.join(name), obj).unwrap();
        let file = dir.join(name);
        let text = format!(
            "[body]\nkind = \"object\"\nfile = \"{}\"\n[garment]\nkind = \"square\"\n",
            file.display()
        );
        Scene::parse(&text, &dir.join("s.toml")).unwrap()
    }

    fn object(s: &Scene) -> &ObjectBody {
        match &s.body {
            crate::scene::BodySection::Object(o) => o,
            _ => unreachable!("the scene's body is an object"),
        }
    }

    fn scratch(name: &str) -> std::path::PathBuf {
        std::env::temp_dir().join(format!("tryon-object-{}-{name}", std::process::id()))
    }

    #[test]
    fn an_objects_seams_are_welded_with_a_warning_and_inward_faces_turned_out() {
        let dir = scratch("weld");
        for outward in [true, false] {
            let s = scene_with(&dir, "soup.obj", &soup(outward));
            let (mesh, warnings) = object_on_table(&s, object(&s)).unwrap();
            mesh.validate().unwrap();
            let text = warnings.join("\n");
            // 24 corners of 8 faces on 6 points: 18 merged, and the lowest point onto the
            // table top's centre vertex it stands on: 19.
            assert!(
                text.contains("19 duplicate vertices merged, 0 sliver"),
                "{text}"
            );
            assert_eq!(text.contains("point inward"), !outward, "{text}");
            // The object (its 6 vertices first) encloses the octahedron's volume, facing out.
            let object = PolyMesh {
                positions: mesh.positions.clone(),
                faces: mesh.faces[..8].to_vec(),
            };
            let v = object.signed_volume();
            assert!((v - 4.0 / 3.0 * 1e-3).abs() < 1e-9, "{v}");
        }
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn an_object_without_faces_is_an_error_naming_the_file() {
        let dir = scratch("empty");
        for (name, obj) in [
            ("empty.obj", ""),
            ("points.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n"),
        ] {
            let s = scene_with(&dir, name, obj);
            let e = object_on_table(&s, object(&s)).unwrap_err();
            let text = e.to_string();
            assert!(text.contains(name) && text.contains("no faces"), "{text}");
        }
        std::fs::remove_dir_all(&dir).ok();
    }
}
