//! The print's aspect per part of the fitted kimono, before and after the print correction, for a
//! wearer outside the family: where the correction leaves the print least square.

use kimono::family::flat_family;
use kimono::{FitParams, Part, PrintParams, Wearer, correct_print, fit, print_aspect, tailor};

fn main() {
    let fam = flat_family().expect("family");
    let w = Wearer::new(1.75, 0.90, 0.70, 0.97);
    let d = tailor(&w).expect("tailor");
    let k = &fam.base;
    let f = fit(k, &k.positions, &fam.targets, &d, &FitParams::default()).expect("fit");
    let uv = correct_print(k, &k.positions, &f.positions, &PrintParams::default())
        .expect("shapes of the mesh");
    let stretched: Vec<_> = k
        .positions
        .iter()
        .map(|p| tryon_core::math::Vec3::new(p.x * 1.03, p.y * 1.12, p.z))
        .collect();
    let uvs = correct_print(k, &k.positions, &stretched, &PrintParams::default())
        .expect("shapes of the mesh");
    let (b, a) = (
        print_aspect(k, &stretched, &k.uvs).expect("shapes of the mesh"),
        print_aspect(k, &stretched, &uvs).expect("shapes of the mesh"),
    );
    println!(
        "stretched 1.03 x 1.12: before {:.4} after {:.4} (initial {:.4})",
        b.mean,
        a.mean,
        print_aspect(k, &k.positions, &k.uvs)
            .expect("shapes of the mesh")
            .mean
    );
    for part in [
        Part::LeftBody,
        Part::LeftSleeve,
        Part::LeftOkumi,
        Part::Collar,
        Part::OverCollar,
    ] {
        let mut m = k.clone();
        let keep: Vec<usize> = (0..k.triangles.len())
            .filter(|&t| k.part[t] == part)
            .collect();
        m.triangles = keep.iter().map(|&t| k.triangles[t]).collect();
        m.uv_triangles = keep.iter().map(|&t| k.uv_triangles[t]).collect();
        let (a0, a1, a2) = (
            print_aspect(&m, &k.positions, &k.uvs).expect("shapes of the mesh"),
            print_aspect(&m, &f.positions, &k.uvs).expect("shapes of the mesh"),
            print_aspect(&m, &f.positions, &uv).expect("shapes of the mesh"),
        );
        println!(
            "{part:?}: initial {:.4}, fitted before {:.4} after {:.4} (scale {:.4})",
            a0.mean, a1.mean, a2.mean, a2.scale
        );
    }
}
