//! MakeHuman garment bindings (.mhclo) refitted onto a (morphed) body: every garment vertex is the
//! weighted mix of three body vertices plus its offset scaled, axis by axis, by how the body's size
//! between two reference vertices compares with the size the garment was made for.

use thiserror::Error;
use tryon_core::assets::{ClothBinding, ObjMesh};
use tryon_core::math::{Real, Vec3};
use tryon_core::mesh::{MeshError, PolyMesh};
use tryon_core::stages::Collider;

/// Why a binding cannot be fitted.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum FitError {
    #[error("binding `{name}` has {bound} vertices but its mesh has {mesh}")]
    CountMismatch {
        name: String,
        bound: usize,
        mesh: usize,
    },
    #[error(
        "binding `{name}`: garment vertex {vertex} refers to body vertex {body_vertex}, beyond the body's {count}"
    )]
    ReferenceOutOfRange {
        name: String,
        vertex: usize,
        body_vertex: u32,
        count: usize,
    },
    #[error(
        "binding `{name}`: {key} names body vertex {body_vertex}, beyond the body's {count} (0..={last})",
        last = count.saturating_sub(1)
    )]
    KeyOutOfRange {
        name: String,
        key: &'static str,
        body_vertex: u32,
        count: usize,
    },
    #[error("binding `{name}`: the fitted garment is not a valid mesh: {source}")]
    Mesh {
        name: String,
        #[source]
        source: MeshError,
    },
    #[error("binding `{name}`: the fitted garment's borders cannot be traced: {source}")]
    Topology {
        name: String,
        #[source]
        source: tryon_core::topology::TopologyError,
    },
}

/// Per-axis scale of the binding's offsets on `body`.
pub fn binding_scales(b: &ClothBinding, body: &[Vec3]) -> [Real; 3] {
    let mut s = [1.0; 3];
    for (axis, r) in b.scales.iter().enumerate() {
        if let Some(r) = r
            && let (Some(pa), Some(pb)) = (body.get(r.a as usize), body.get(r.b as usize))
        {
            s[axis] = (pa[axis] - pb[axis]).abs() / r.rest;
        }
    }
    s
}

/// The garment's vertex positions on `body` (all base vertices, helpers included).
pub fn fit_positions(b: &ClothBinding, body: &[Vec3]) -> Result<Vec<Vec3>, FitError> {
    check_keys(b, body.len())?;
    let s = binding_scales(b, body);
    let mut out = Vec::with_capacity(b.refs.len());
    for (i, (r, w)) in b.refs.iter().zip(&b.weights).enumerate() {
        let mut p = Vec3::zeros();
        for k in 0..3 {
            let q = body
                .get(r[k] as usize)
                .ok_or_else(|| FitError::ReferenceOutOfRange {
                    name: b.name.clone(),
                    vertex: i,
                    body_vertex: r[k],
                    count: body.len(),
                })?;
            p += q * w[k];
        }
        let d = b.offsets[i];
        out.push(p + Vec3::new(d.x * s[0], d.y * s[1], d.z * s[2]));
    }
    Ok(out)
}

/// The body vertices the binding names outside `verts` (the scale references, `delete_verts`)
/// exist on a body of `count` vertices.
fn check_keys(b: &ClothBinding, count: usize) -> Result<(), FitError> {
    let scales = b.scales.iter().zip(["x_scale", "y_scale", "z_scale"]);
    let scale_vertices =
        scales.flat_map(|(r, key)| r.iter().flat_map(move |r| [(key, r.a), (key, r.b)]));
    let deleted = b.delete_verts.iter().map(|&v| ("delete_verts", v));
    match scale_vertices
        .chain(deleted)
        .find(|&(_, v)| v as usize >= count)
    {
        Some((key, body_vertex)) => Err(FitError::KeyOutOfRange {
            name: b.name.clone(),
            key,
            body_vertex,
            count,
        }),
        None => Ok(()),
    }
}

/// The garment mesh (faces of `obj`, positions fitted on `body`).
pub fn fit_garment(b: &ClothBinding, obj: &ObjMesh, body: &[Vec3]) -> Result<PolyMesh, FitError> {
    if obj.positions.len() != b.refs.len() {
        return Err(FitError::CountMismatch {
            name: b.name.clone(),
            bound: b.refs.len(),
            mesh: obj.positions.len(),
        });
    }
    let positions = fit_positions(b, body)?;
    PolyMesh::new(positions, obj.faces.clone()).map_err(|source| FitError::Mesh {
        name: b.name.clone(),
        source,
    })
}

/// [`fit_garment`], then every vertex the collider finds inside the body (the binding leaves
/// about 1% of a garment's vertices a few millimetres inside, at collars and armpits) is moved onto
/// the surface plus the collider's skin. Returns the mesh and how many vertices moved.
pub fn fit_garment_outside(
    b: &ClothBinding,
    obj: &ObjMesh,
    body: &[Vec3],
    collider: &mut dyn Collider,
) -> Result<(PolyMesh, usize), FitError> {
    let mut mesh = fit_garment(b, obj, body)?;
    let moved = crate::place_outside(&mut mesh, collider);
    Ok((mesh, moved))
}

#[cfg(test)]
mod tests {
    use super::*;
    use tryon_core::assets::ScaleRef;

    #[test]
    fn scale_references_and_deleted_vertices_off_the_body_are_errors_naming_the_key() {
        let body = vec![Vec3::zeros(), Vec3::x(), Vec3::y()];
        let mut b = ClothBinding {
            name: "g".into(),
            refs: vec![[0, 1, 2]],
            weights: vec![[0.2, 0.3, 0.5]],
            offsets: vec![Vec3::zeros()],
            ..ClothBinding::default()
        };
        assert!(fit_positions(&b, &body).is_ok());
        b.delete_verts = vec![1, 4_000_000_000];
        let e = fit_positions(&b, &body).unwrap_err().to_string();
        assert!(
            e.contains("delete_verts names body vertex 4000000000, beyond the body's 3 (0..=2)"),
            "{e}"
        );
        b.delete_verts.clear();
        b.scales[1] = Some(tryon_core::assets::ScaleRef {
            a: 0,
            b: 7,
            rest: 1.0,
        });
        let e = fit_positions(&b, &body).unwrap_err().to_string();
        assert!(e.contains("y_scale names body vertex 7"), "{e}");
    }

    #[test]
    fn weights_mix_references_and_offsets_scale_with_the_body() {
        let body = vec![
            Vec3::zeros(),
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(0.0, 2.0, 0.0),
        ];
        let b = ClothBinding {
            refs: vec![[0, 1, 2]],
            weights: vec![[0.5, 0.25, 0.25]],
            offsets: vec![Vec3::new(0.1, 0.1, 0.1)],
            scales: [
                Some(ScaleRef {
                    a: 0,
                    b: 1,
                    rest: 1.0,
                }),
                None,
                None,
            ],
            ..ClothBinding::default()
        };
        let p = fit_positions(&b, &body).unwrap();
        // Mix (0.5, 0.5, 0); offset x doubled because the body is twice the rest width.
        assert!(
            (p[0] - Vec3::new(0.7, 0.6, 0.1)).norm() < 1e-12,
            "{:?}",
            p[0]
        );
        let mut bad = b.clone();
        bad.refs[0][2] = 9;
        assert!(matches!(
            fit_positions(&bad, &body),
            Err(FitError::ReferenceOutOfRange { body_vertex: 9, .. })
        ));
    }
}
