//! Edge lengths of the fitted kimono against those of the kimono built straight for the same
//! wearer (the same topology): where the fit distorts the cloth.

use kimono::family::flat_family;
use kimono::{FitParams, Wearer, build, fit, tailor};

fn main() {
    let fam = flat_family().expect("family");
    let w = Wearer::new(1.75, 0.90, 0.70, 0.97);
    let d = tailor(&w).expect("tailor");
    let own = build(&d, &fam.layout).expect("build");
    let f = fit(
        &fam.base,
        &fam.base.positions,
        &fam.targets,
        &d,
        &FitParams::default(),
    )
    .expect("fit");
    let mut worst: Vec<(f64, usize)> = Vec::new();
    for (t, tri) in fam.base.triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (tri[k] as usize, tri[(k + 1) % 3] as usize);
            let r = (f.positions[a] - f.positions[b]).norm()
                / (own.positions[a] - own.positions[b]).norm();
            worst.push(((r - 1.0).abs(), t));
        }
    }
    worst.sort_by(|a, b| b.0.total_cmp(&a.0));
    let n = worst.len();
    println!(
        "edges {n}; |ratio-1| p50 {:.3} p90 {:.3} p99 {:.3} max {:.3}",
        worst[n / 2].0,
        worst[n / 10].0,
        worst[n / 100].0,
        worst[0].0
    );
    for (e, t) in worst.iter().take(8) {
        let c = fam.base.triangles[*t].map(|v| own.positions[v as usize]);
        println!(
            "{e:.3} part {:?} sub {} at {:.3?}",
            fam.base.part[*t],
            fam.base.sub_mesh[*t],
            (c[0] + c[1] + c[2]) / 3.0
        );
    }
    println!("weights {:.3?}", f.weights);
}
