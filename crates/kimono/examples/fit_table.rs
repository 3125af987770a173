//! Fits the flat family to sizes that are not among its targets and prints Table 1 for each:
//! target, initial and fitted value, relative errors.

use kimono::family::flat_family;
use kimono::{FitParams, Wearer, fit, tailor};

fn main() {
    let fam = flat_family().expect("family");
    let sizes = [
        Wearer::new(1.50, 0.82, 0.64, 0.88),
        Wearer::new(1.57, 0.88, 0.70, 0.96),
        Wearer::new(1.62, 0.84, 0.64, 0.90),
        Wearer::new(1.68, 0.94, 0.76, 1.02),
        Wearer::new(1.75, 0.90, 0.70, 0.97),
    ];
    for w in sizes {
        let d = tailor(&w).expect("tailor");
        let t0 = std::time::Instant::now();
        let f = fit(
            &fam.base,
            &fam.base.positions,
            &fam.targets,
            &d,
            &FitParams::default(),
        )
        .expect("fit");
        let uv = kimono::correct_print(
            &fam.base,
            &fam.base.positions,
            &f.positions,
            &kimono::PrintParams::default(),
        )
        .expect("shapes of the mesh");
        let ms = t0.elapsed().as_secs_f64() * 1e3;
        let a0 = kimono::print_aspect(&fam.base, &fam.base.positions, &fam.base.uvs)
            .expect("shapes of the mesh");
        let a1 = kimono::print_aspect(&fam.base, &f.positions, &fam.base.uvs)
            .expect("shapes of the mesh");
        let a2 = kimono::print_aspect(&fam.base, &f.positions, &uv).expect("shapes of the mesh");
        println!(
            "  aspect initial {:.4}/{:.4}  fitted before {:.4}/{:.4}  after {:.4}/{:.4}",
            a0.mean, a0.scale, a1.mean, a1.scale, a2.mean, a2.scale
        );
        let table = d.table();
        let (mut e0, mut e1, mut m1, mut n) = (0.0, 0.0, 0.0f64, 0.0);
        for (k, s) in fam.base.dimensions.iter().enumerate() {
            if !s.in_table {
                continue;
            }
            let target = table[s.table_index].1;
            let init = fam.base.measure(k, &fam.base.positions);
            let r0 = ((init - target) / target).abs();
            let r1 = ((f.measured[k] - target) / target).abs();
            if std::env::var("DETAIL").is_ok() {
                println!(
                    "  {:40} target {:.4} init {:.4} fit {:.4}",
                    s.name, target, init, f.measured[k]
                );
            }
            e0 += r0;
            e1 += r1;
            m1 = m1.max(r1);
            n += 1.0;
        }
        println!(
            "{:.2} {:.2} {:.2} {:.2}: initial mean {:.2}%  fitted mean {:.3}% max {:.3}%  {:.2} ms",
            w.height,
            w.bust,
            w.waist,
            w.hip,
            100.0 * e0 / n,
            100.0 * e1 / n,
            100.0 * m1,
            ms
        );
    }
}
