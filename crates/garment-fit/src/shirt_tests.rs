//! Unit tests of the shirt pattern: the four-way split, settings out of range, and bodies that are
//! not a figure. The shirt cut from the mannequin is tested in `tests/shirt.rs`.

use super::*;
use tryon_core::mesh::grid_xz;
use tryon_core::stages::NoCollider;
use tryon_core::topology::Topology;

fn area(mesh: &PolyMesh) -> Real {
    let (tris, _) = mesh.triangulate();
    tris.iter()
        .map(|t| {
            let x = t.map(|v| mesh.positions[v as usize]);
            0.5 * (x[1] - x[0]).cross(&(x[2] - x[0])).norm()
        })
        .sum()
}

#[test]
fn splitting_in_four_keeps_the_mesh_conforming_and_its_area() {
    let sheet = grid_xz(3, 2, 0.3, 0.2, 0.0);
    let once = split_in_four(&sheet);
    let twice = split_in_four(&once);
    let (tris, _) = sheet.triangulate();
    assert_eq!(once.faces.len(), 4 * tris.len());
    assert_eq!(twice.faces.len(), 16 * tris.len());
    // A 3 x 2 grid has (3 * 2 + 1) * (2 * 2 + 1) = 35 vertices after one split of its quads'
    // triangles, each edge split once: vertices + edges of the triangulated grid.
    let topo = Topology::build(&PolyMesh {
        positions: sheet.positions.clone(),
        faces: tris.iter().map(|t| Face::Tri(*t)).collect(),
    })
    .unwrap();
    assert_eq!(
        once.positions.len(),
        sheet.positions.len() + topo.edges.len()
    );
    // Conforming: the boundary of the split sheet is the sheet's boundary, each edge halved.
    let split = Topology::build(&once).unwrap();
    assert_eq!(split.boundary_edges.len(), 2 * topo.boundary_edges.len());
    assert!((area(&twice) - 0.3 * 0.2).abs() < 1e-12);
}

fn nothing() -> (PolyMesh, Vec<Option<u8>>) {
    (grid_xz(1, 1, 1.0, 1.0, 1.0), vec![None; 4])
}

fn arms() -> [Arm; 2] {
    [Arm {
        root: Vec3::zeros(),
        dir: Vec3::x(),
    }; 2]
}

#[test]
fn settings_out_of_range_are_named() {
    let (mesh, arm_of) = nothing();
    let body = ShirtBody {
        mesh: &mesh,
        arm_of: &arm_of,
        arms: arms(),
    };
    let m = Measurements::default();
    for (p, name) in [
        (
            ShirtParams {
                sleeve_length: 0.05,
                ..Default::default()
            },
            "sleeve_length",
        ),
        (
            ShirtParams {
                ease: [0.1, Real::NAN, 0.1],
                ..Default::default()
            },
            "ease.waist",
        ),
        (
            ShirtParams {
                subdivisions: 4,
                ..Default::default()
            },
            "subdivisions",
        ),
    ] {
        match shirt(&m, &body, &mut NoCollider, &p) {
            Err(PatternError::BadParameter { name: n, .. }) => assert_eq!(n, name),
            other => panic!("{name}: {other:?}"),
        }
    }
}

#[test]
fn a_body_that_is_not_a_figure_is_refused_with_what_was_found() {
    let (mesh, arm_of) = nothing();
    let body = ShirtBody {
        mesh: &mesh,
        arm_of: &arm_of[..3],
        arms: arms(),
    };
    let m = Measurements::default();
    let e = shirt(&m, &body, &mut NoCollider, &ShirtParams::default()).unwrap_err();
    assert!(
        e.to_string().contains("3 arm labels for 4 body vertices"),
        "{e}"
    );
    // A flat square at 1 m: within the shirt's heights, one opening, not four.
    let body = ShirtBody {
        arm_of: &arm_of,
        ..body
    };
    let e = shirt(&m, &body, &mut NoCollider, &ShirtParams::default()).unwrap_err();
    assert!(e.to_string().contains("1 openings in 1 pieces"), "{e}");
}

#[test]
fn bad_arm_labels_and_broken_body_meshes_are_errors_not_panics() {
    let (mesh, mut arm_of) = nothing();
    arm_of[2] = Some(2);
    let m = Measurements::default();
    let body = ShirtBody {
        mesh: &mesh,
        arm_of: &arm_of,
        arms: arms(),
    };
    let e = shirt(&m, &body, &mut NoCollider, &ShirtParams::default()).unwrap_err();
    assert!(e.to_string().contains("vertex 2 is labelled arm 2"), "{e}");
    let mut broken = mesh.clone();
    broken.faces.push(tryon_core::mesh::Face::Tri([0, 1, 9]));
    let (_, arm_of) = nothing();
    let body = ShirtBody {
        mesh: &broken,
        arm_of: &arm_of,
        arms: arms(),
    };
    let e = shirt(&m, &body, &mut NoCollider, &ShirtParams::default()).unwrap_err();
    assert!(e.to_string().contains("refers to vertex 9"), "{e}");
}
