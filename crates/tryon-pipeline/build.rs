//! Builds the worn kimono shapes of data/kimono (made by `cargo xtask kimono-targets`) into the
//! library, so `tryon kimono` and kimono scenes find them wherever the program runs. Only the
//! files that exist are built in: the generator is an example of this crate, and it must build
//! before they exist (a missing shape is then a run-time error naming the file).

use std::path::Path;

fn main() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/kimono");
    println!("cargo:rerun-if-changed={}", dir.display());
    let mut names: Vec<String> = std::fs::read_dir(&dir)
        .map(|r| {
            r.filter_map(Result::ok)
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .filter(|n| n.ends_with(".obj") && !n.starts_with('.'))
                .collect()
        })
        .unwrap_or_default();
    names.sort();
    let mut code = String::from(
        "/// Every built-in shape: (file name, OBJ text).\npub const SHAPES: &[(&str, &str)] = &[\n",
    );
    for n in &names {
        let path = dir.join(n);
        println!("cargo:rerun-if-changed={}", path.display());
        code += &format!(
            "    ({n:?}, include_str!({:?})),\n",
            path.display().to_string()
        );
    }
    code += "];\n";
    let out =
        Path::new(&std::env::var("OUT_DIR").expect("cargo sets OUT_DIR")).join("kimono_shapes.rs");
    std::fs::write(&out, code).expect("OUT_DIR is writable");
}
