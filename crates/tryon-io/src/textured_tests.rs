//! The textured GLB read back by the gltf crate, and the texture's sampling and picture.

use super::*;

fn square() -> (Vec<Vec3>, Vec<[Real; 2]>, Vec<[u32; 3]>) {
    (
        vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ],
        vec![[0.0, 0.0], [0.5, 0.0], [0.5, 0.5], [0.0, 0.5]],
        vec![[0, 1, 2], [0, 2, 3]],
    )
}

fn checker() -> Texture {
    let mut rgb = Vec::new();
    for y in 0..4 {
        for x in 0..4 {
            rgb.extend_from_slice(if (x / 2 + y / 2) % 2 == 0 {
                &[250, 10, 10]
            } else {
                &[10, 10, 250]
            });
        }
    }
    Texture {
        width: 4,
        height: 4,
        rgb,
        tile: 0.25,
    }
}

#[test]
fn the_texture_repeats_and_samples_the_nearest_texel() {
    let t = checker();
    assert_eq!(t.sample([0.01, 0.01]), [250, 10, 10]);
    assert_eq!(t.sample([0.2, 0.01]), [10, 10, 250]);
    assert_eq!(
        t.sample([0.26, 0.01]),
        [250, 10, 10],
        "repeats after one tile"
    );
    assert_eq!(t.sample([-0.05, 0.01]), [10, 10, 250], "and before it");
}

#[test]
fn a_texture_without_its_texels_samples_grey_instead_of_panicking() {
    let good = checker();
    let cases = [
        Texture {
            width: 0,
            ..good.clone()
        },
        Texture {
            height: 0,
            ..good.clone()
        },
        Texture {
            rgb: vec![1, 2, 3],
            ..good.clone()
        },
        Texture {
            width: u32::MAX,
            height: u32::MAX,
            ..good.clone()
        },
        Texture {
            tile: 0.0,
            ..good.clone()
        },
        Texture {
            tile: Real::NAN,
            ..good.clone()
        },
    ];
    for t in &cases {
        assert!(!t.is_valid(), "{}x{} tile {}", t.width, t.height, t.tile);
        assert_eq!(t.sample([0.3, 0.7]), [128; 3]);
    }
    assert!(good.is_valid());
    // Non-finite UVs land on a texel of a valid texture, not outside it.
    for uv in [
        [Real::NAN, 0.0],
        [Real::INFINITY, Real::NEG_INFINITY],
        [1e300, -1e300],
    ] {
        let c = good.sample(uv);
        assert!(c == [250, 10, 10] || c == [10, 10, 250], "{uv:?} -> {c:?}");
    }
}

#[test]
fn the_glb_reads_back_with_its_uvs_and_embedded_png() {
    let (p, uv, tris) = square();
    let m = TexturedMesh {
        positions: &p,
        uvs: &uv,
        triangles: &tris,
    };
    let bytes = textured_glb(&m, &checker(), "sheet").unwrap();
    let g = gltf::Gltf::from_slice(&bytes).unwrap();
    let blob = g.blob.clone().unwrap();
    let prim = g.meshes().next().unwrap().primitives().next().unwrap();
    let floats = |sem: gltf::Semantic| -> Vec<f32> {
        let acc = prim.get(&sem).unwrap();
        let view = acc.view().unwrap();
        let at = view.offset() + acc.offset();
        let n = acc.count() * acc.dimensions().multiplicity();
        (0..n)
            .map(|i| f32::from_le_bytes(blob[at + 4 * i..at + 4 * i + 4].try_into().unwrap()))
            .collect()
    };
    let tc = floats(gltf::Semantic::TexCoords(0));
    assert_eq!(&tc[4..6], &[2.0, 2.0], "UVs over the tile: 0.5 / 0.25");
    let pos = floats(gltf::Semantic::Positions);
    assert_eq!(&pos[6..9], &[1.0, 1.0, 0.0]);
    let image = g.images().next().unwrap();
    let gltf::image::Source::View { view, mime_type } = image.source() else {
        panic!("the image is not embedded");
    };
    assert_eq!(mime_type, "image/png");
    let png_bytes = &blob[view.offset()..view.offset() + view.length()];
    let dec = png::Decoder::new(std::io::Cursor::new(png_bytes))
        .read_info()
        .unwrap();
    assert_eq!((dec.info().width, dec.info().height), (4, 4));
    let tex = prim
        .material()
        .pbr_metallic_roughness()
        .base_color_texture()
        .unwrap();
    assert_eq!(
        tex.texture().sampler().wrap_s(),
        gltf::texture::WrappingMode::Repeat
    );
}

#[test]
fn bad_textured_meshes_are_refused_with_the_reason() {
    let (p, uv, _) = square();
    let tris = vec![[0, 1, 7]];
    let m = TexturedMesh {
        positions: &p,
        uvs: &uv,
        triangles: &tris,
    };
    let e = textured_glb(&m, &checker(), "x").unwrap_err().to_string();
    assert!(e.contains("vertex 7"), "{e}");
    let m = TexturedMesh {
        positions: &p,
        uvs: &uv[..3],
        triangles: &tris,
    };
    assert!(
        textured_glb(&m, &checker(), "x")
            .unwrap_err()
            .to_string()
            .contains("3 UVs for 4")
    );
}

#[test]
fn the_picture_shows_the_texture() {
    let (p, uv, tris) = square();
    let m = TexturedMesh {
        positions: &p,
        uvs: &uv,
        triangles: &tris,
    };
    let cam = Camera {
        eye: Vec3::new(0.5, 0.5, 3.0),
        target: Vec3::new(0.5, 0.5, 0.0),
        up: Vec3::y(),
        fov_y: 35.0,
    };
    let img = render_textured(&m, &checker(), &cam, 64, 64);
    let at = |x: usize, y: usize| &img.rgb[3 * (y * 64 + x)..3 * (y * 64 + x) + 3];
    let (mut red, mut blue) = (0, 0);
    for y in 0..64 {
        for x in 0..64 {
            let c = at(x, y);
            red += (c[0] > 150 && c[2] < 60) as usize;
            blue += (c[2] > 150 && c[0] < 60) as usize;
        }
    }
    assert!(red > 200 && blue > 200, "red {red}, blue {blue}");
}
