//! A still, textured mesh: a picture of it with its texture (the preview's camera and shading)
//! and a GLB of it with the texture embedded as PNG, repeating. UVs are given in the texture's
//! own length units (for cloth, metres of fabric); one tile of the texture covers `tile` of them.

use crate::atomic::write_atomic;
use crate::preview::{Camera, Image, View, canvas, fill_with};
use serde_json::json;
use std::path::Path;
use thiserror::Error;
use tryon_core::math::{Real, Vec3};

/// An RGB picture repeated over a surface.
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    pub width: u32,
    pub height: u32,
    pub rgb: Vec<u8>,
    /// How many UV units one tile spans, both ways.
    pub tile: Real,
}

impl Texture {
    /// Whether the texture holds its `width` x `height` texels (neither 0) and a positive tile.
    pub fn is_valid(&self) -> bool {
        let texels = (self.width as usize).checked_mul(self.height as usize);
        texels.is_some_and(|n| n > 0 && n.checked_mul(3) == Some(self.rgb.len())) && self.tile > 0.0
    }

    /// The colour at `uv`, the texture repeating (nearest texel; v runs down the picture). A
    /// texture that is not valid ([`Texture::is_valid`]) samples as mid grey everywhere.
    pub fn sample(&self, uv: [Real; 2]) -> [u8; 3] {
        if !self.is_valid() {
            return [128; 3];
        }
        let (w, h) = (self.width as usize, self.height as usize);
        let f = |t: Real, n: usize| {
            let t = (t / self.tile).rem_euclid(1.0);
            ((t * n as Real) as usize).min(n - 1)
        };
        let k = 3 * (f(uv[1], h) * w + f(uv[0], w));
        [self.rgb[k], self.rgb[k + 1], self.rgb[k + 2]]
    }
}

/// A mesh with a UV per vertex (a vertex on a texture seam appears once per side).
#[derive(Clone, Copy, Debug)]
pub struct TexturedMesh<'a> {
    pub positions: &'a [Vec3],
    pub uvs: &'a [[Real; 2]],
    pub triangles: &'a [[u32; 3]],
}

/// Why a textured output could not be written.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum TexturedError {
    #[error("textured mesh: {0}")]
    Invalid(String),
    #[error("cannot encode the texture as PNG: {0}")]
    Encode(String),
    #[error("cannot write {path}: {source}")]
    Io {
        path: std::path::PathBuf,
        source: std::io::Error,
    },
}

fn validate(m: &TexturedMesh, t: &Texture) -> Result<(), TexturedError> {
    let bad = |s: String| Err(TexturedError::Invalid(s));
    if m.uvs.len() != m.positions.len() {
        return bad(format!(
            "{} UVs for {} vertices",
            m.uvs.len(),
            m.positions.len()
        ));
    }
    if let Some(k) = m
        .triangles
        .iter()
        .flatten()
        .find(|&&v| v as usize >= m.positions.len())
    {
        return bad(format!(
            "a triangle names vertex {k} of {}",
            m.positions.len()
        ));
    }
    if !t.is_valid() {
        return bad(format!(
            "texture {}x{} with {} bytes, tile {}",
            t.width,
            t.height,
            t.rgb.len(),
            t.tile
        ));
    }
    Ok(())
}

/// The mesh as `camera` sees it, textured and shaded.
pub fn render_textured(
    m: &TexturedMesh,
    tex: &Texture,
    camera: &Camera,
    width: u32,
    height: u32,
) -> Image {
    let (w, h) = (width.max(1) as usize, height.max(1) as usize);
    let (mut rgb, mut depth) = canvas(w, h);
    let view = View::new(camera, w, h);
    if validate(m, tex).is_ok() {
        for t in m.triangles {
            let p = t.map(|v| m.positions[v as usize]);
            let Some(n) = (p[1] - p[0]).cross(&(p[2] - p[0])).try_normalize(0.0) else {
                continue;
            };
            let shade = 0.35 + 0.65 * n.dot(&view.light).abs();
            let Some(s) = p
                .iter()
                .map(|q| view.project(q))
                .collect::<Option<Vec<_>>>()
            else {
                continue;
            };
            let uv = t.map(|v| m.uvs[v as usize]);
            // Perspective-correct: interpolate uv / z and 1 / z.
            let iz = [1.0 / s[0].2, 1.0 / s[1].2, 1.0 / s[2].2];
            let color = |b: [Real; 3]| {
                let q = b[0] * iz[0] + b[1] * iz[1] + b[2] * iz[2];
                let at = |c: usize| {
                    (b[0] * uv[0][c] * iz[0] + b[1] * uv[1][c] * iz[1] + b[2] * uv[2][c] * iz[2])
                        / q
                };
                tex.sample([at(0), at(1)])
                    .map(|c| (c as Real * shade).min(255.0) as u8)
            };
            fill_with(&mut rgb, &mut depth, w, h, [s[0], s[1], s[2]], &color);
        }
    }
    Image {
        width: w as u32,
        height: h as u32,
        rgb,
    }
}

/// The texture as PNG bytes.
pub fn encode_png(t: &Texture) -> Result<Vec<u8>, TexturedError> {
    let mut bytes = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut bytes, t.width, t.height);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let err = |e: png::EncodingError| TexturedError::Encode(e.to_string());
        let mut writer = enc.write_header().map_err(err)?;
        writer.write_image_data(&t.rgb).map_err(err)?;
    }
    Ok(bytes)
}

/// The GLB of a still textured mesh (positions, normals, texture coordinates scaled by the tile,
/// the texture embedded as PNG with a repeating sampler, double-sided).
pub fn textured_glb(m: &TexturedMesh, tex: &Texture, name: &str) -> Result<Vec<u8>, TexturedError> {
    validate(m, tex)?;
    let normals = crate::glb_layout::normals(m.positions, m.triangles);
    let mut bin: Vec<u8> = Vec::new();
    let mut views = Vec::new();
    let mut push = |bytes: &[u8], target: Option<u32>| {
        while !bin.len().is_multiple_of(4) {
            bin.push(0);
        }
        let mut v = json!({"buffer": 0, "byteOffset": bin.len(), "byteLength": bytes.len()});
        if let Some(t) = target {
            v["target"] = json!(t);
        }
        bin.extend_from_slice(bytes);
        views.push(v);
        views.len() - 1
    };
    let f32s =
        |v: &mut dyn Iterator<Item = f32>| v.flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();
    let pos: Vec<u8> = f32s(
        &mut m
            .positions
            .iter()
            .flat_map(|p| [p.x as f32, p.y as f32, p.z as f32]),
    );
    let nor: Vec<u8> = f32s(
        &mut normals
            .iter()
            .flat_map(|p| [p.x as f32, p.y as f32, p.z as f32]),
    );
    let tc: Vec<u8> = f32s(
        &mut m
            .uvs
            .iter()
            .flat_map(|u| [(u[0] / tex.tile) as f32, (u[1] / tex.tile) as f32]),
    );
    let idx: Vec<u8> = m
        .triangles
        .iter()
        .flatten()
        .flat_map(|i| i.to_le_bytes())
        .collect();
    let (vp, vn, vt, vi) = (
        push(&pos, Some(34962)),
        push(&nor, Some(34962)),
        push(&tc, Some(34962)),
        push(&idx, Some(34963)),
    );
    let png = encode_png(tex)?;
    let vimg = push(&png, None);
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let (lo, hi) = m
        .positions
        .iter()
        .fold(([f32::MAX; 3], [f32::MIN; 3]), |(lo, hi), p| {
            let q = [p.x as f32, p.y as f32, p.z as f32];
            (
                std::array::from_fn(|i| lo[i].min(q[i])),
                std::array::from_fn(|i| hi[i].max(q[i])),
            )
        });
    let n = m.positions.len();
    let doc = json!({
        "asset": {"version": "2.0", "generator": "tryon"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "name": name}],
        "meshes": [{"name": name, "primitives": [{
            "attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2},
            "indices": 3, "material": 0}]}],
        "materials": [{"name": "print", "doubleSided": true, "pbrMetallicRoughness": {
            "baseColorTexture": {"index": 0}, "metallicFactor": 0.0, "roughnessFactor": 0.9}}],
        "textures": [{"sampler": 0, "source": 0}],
        "samplers": [{"magFilter": 9729, "minFilter": 9987, "wrapS": 10497, "wrapT": 10497}],
        "images": [{"bufferView": vimg, "mimeType": "image/png"}],
        "accessors": [
            {"bufferView": vp, "componentType": 5126, "count": n, "type": "VEC3", "min": lo, "max": hi},
            {"bufferView": vn, "componentType": 5126, "count": n, "type": "VEC3"},
            {"bufferView": vt, "componentType": 5126, "count": n, "type": "VEC2"},
            {"bufferView": vi, "componentType": 5125, "count": 3 * m.triangles.len(), "type": "SCALAR"}
        ],
        "bufferViews": views,
        "buffers": [{"byteLength": bin.len()}]
    });
    let mut js = serde_json::to_vec(&doc).map_err(|e| TexturedError::Encode(e.to_string()))?;
    while !js.len().is_multiple_of(4) {
        js.push(b' ');
    }
    let total = 12 + 8 + js.len() + 8 + bin.len();
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(js.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&js);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&bin);
    Ok(out)
}

/// [`textured_glb`] written atomically to `path`.
pub fn write_textured_glb(
    path: &Path,
    m: &TexturedMesh,
    tex: &Texture,
    name: &str,
) -> Result<(), TexturedError> {
    let bytes = textured_glb(m, tex, name)?;
    write_atomic(path, &bytes).map_err(|source| TexturedError::Io {
        path: path.to_path_buf(),
        source,
    })
}

#[cfg(test)]
#[path = "textured_tests.rs"]
mod tests;
