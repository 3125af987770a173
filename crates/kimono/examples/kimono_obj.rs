//! Writes the flat kimono as OBJ (with its bolt UVs) to stdout, and its dimensions to stderr: a
//! quick look for a person.

use kimono::{Layout, Wearer, build, tailor};

fn main() {
    let d = tailor(&Wearer::new(1.58, 0.84, 0.66, 0.92)).expect("tailor");
    let layout = Layout::for_dims(&d, 0.03).expect("layout");
    let k = build(&d, &layout).expect("build");
    let table = d.table();
    for (i, s) in k.dimensions.iter().enumerate() {
        eprintln!(
            "{:40} {:5} target {:.4} mesh {:.4}",
            s.name,
            s.in_table,
            table[s.table_index].1,
            k.measure(i, &k.positions)
        );
    }
    eprintln!(
        "{} vertices, {} triangles, {} uvs",
        k.positions.len(),
        k.triangles.len(),
        k.uvs.len()
    );
    for p in &k.positions {
        println!("v {} {} {}", p.x, p.y, p.z);
    }
    for uv in &k.uvs {
        println!("vt {} {}", uv[0] / 0.38, uv[1] / 0.38);
    }
    for (t, u) in k.triangles.iter().zip(&k.uv_triangles) {
        println!(
            "f {}/{} {}/{} {}/{}",
            t[0] + 1,
            u[0] + 1,
            t[1] + 1,
            u[1] + 1,
            t[2] + 1,
            u[2] + 1
        );
    }
}
