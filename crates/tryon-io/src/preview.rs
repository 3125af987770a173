//! Preview pictures: a small software rasteriser (perspective camera, z-buffer, two-sided Lambert
//! shading, one colour per mesh) and PNG output through the `png` crate.

use crate::atomic::write_atomic;
use std::path::{Path, PathBuf};
use thiserror::Error;
use tryon_core::math::{Real, Vec3, is_finite};

/// A mesh to draw.
#[derive(Clone, Copy, Debug)]
pub struct PreviewMesh<'a> {
    pub positions: &'a [Vec3],
    pub triangles: &'a [[u32; 3]],
    pub color: [u8; 3],
}

/// The colour garment `k` of a scene is drawn in (in the preview and the GLB's materials): the
/// first blue, as one garment always was, then colours that tell layers apart.
pub fn garment_colour(k: usize) -> [u8; 3] {
    const PALETTE: [[u8; 3]; 6] = [
        [55, 85, 170],
        [170, 60, 55],
        [60, 140, 80],
        [200, 160, 50],
        [120, 70, 150],
        [60, 150, 160],
    ];
    PALETTE[k % PALETTE.len()]
}

/// A perspective camera.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Camera {
    pub eye: Vec3,
    pub target: Vec3,
    pub up: Vec3,
    /// Vertical field of view (degrees).
    pub fov_y: Real,
}

impl Camera {
    /// A camera looking at the meshes' bounding box from the front (+Z), to the right and above,
    /// far enough to see all of it.
    pub fn framing(meshes: &[PreviewMesh]) -> Camera {
        let mut lo = Vec3::repeat(Real::INFINITY);
        let mut hi = Vec3::repeat(Real::NEG_INFINITY);
        for p in meshes
            .iter()
            .flat_map(|m| m.positions.iter())
            .filter(|p| is_finite(p))
        {
            lo = lo.inf(p);
            hi = hi.sup(p);
        }
        if lo.x > hi.x {
            (lo, hi) = (Vec3::repeat(-1.0), Vec3::repeat(1.0));
        }
        let center = (lo + hi) * 0.5;
        let radius = ((hi - lo).norm() * 0.5).max(1e-3);
        let fov_y: Real = 35.0;
        let dist = radius / (fov_y.to_radians() * 0.5).sin() * 1.05;
        let dir = Vec3::new(0.55, 0.45, 1.0).normalize();
        Camera {
            eye: center + dir * dist,
            target: center,
            up: Vec3::y(),
            fov_y,
        }
    }
}

impl Camera {
    /// The ray through pixel `(px, py)` (pixel units, the origin at the top-left corner of the
    /// picture, x to the right, y down) of a `width` x `height` picture taken by this camera, as
    /// [`render`] projects: the eye and a unit direction.
    pub fn ray(&self, px: Real, py: Real, width: u32, height: u32) -> (Vec3, Vec3) {
        let (w, h) = (width.max(1) as Real, height.max(1) as Real);
        let fwd = (self.target - self.eye).normalize();
        let right = fwd.cross(&self.up).normalize();
        let up = right.cross(&fwd);
        let f = 1.0 / (self.fov_y.to_radians() * 0.5).tan();
        let x = px / w * 2.0 - 1.0;
        let y = 1.0 - py / h * 2.0;
        let dir = fwd + right * (x * w / h / f) + up * (y / f);
        (self.eye, dir.normalize())
    }
}

/// An RGB image.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    pub rgb: Vec<u8>,
}

/// Why a preview could not be written.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum PreviewError {
    #[error("cannot write {path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("cannot encode PNG for {path}: {message}")]
    Encode { path: PathBuf, message: String },
}

/// The picture's frame: a soft vertical gradient to draw on, and a depth buffer.
pub(crate) fn canvas(w: usize, h: usize) -> (Vec<u8>, Vec<Real>) {
    let mut rgb = vec![0u8; w * h * 3];
    for (k, px) in rgb.chunks_mut(3).enumerate() {
        let t = (k / w) as Real / h as Real;
        let g = (235.0 - 40.0 * t) as u8;
        px.copy_from_slice(&[g, g, (g as Real * 1.03).min(255.0) as u8]);
    }
    (rgb, vec![Real::INFINITY; w * h])
}

/// A camera's projection onto a `w` x `h` picture and the light that shades it.
pub(crate) struct View {
    eye: Vec3,
    fwd: Vec3,
    right: Vec3,
    up: Vec3,
    f: Real,
    aspect: Real,
    w: Real,
    h: Real,
    pub light: Vec3,
}

impl View {
    pub fn new(camera: &Camera, w: usize, h: usize) -> View {
        let fwd = (camera.target - camera.eye).normalize();
        let right = fwd.cross(&camera.up).normalize();
        let up = right.cross(&fwd);
        View {
            eye: camera.eye,
            fwd,
            right,
            up,
            f: 1.0 / (camera.fov_y.to_radians() * 0.5).tan(),
            aspect: w as Real / h as Real,
            w: w as Real,
            h: h as Real,
            light: (-fwd + up * 0.6 + right * 0.3).normalize(),
        }
    }

    /// Screen x, y and depth of `p`, if it is in front of the camera.
    pub fn project(&self, p: &Vec3) -> Option<(Real, Real, Real)> {
        let r = p - self.eye;
        let z = r.dot(&self.fwd);
        if z <= 1e-6 || !z.is_finite() {
            return None;
        }
        let x = r.dot(&self.right) * self.f / (z * self.aspect);
        let y = r.dot(&self.up) * self.f / z;
        Some(((x + 1.0) * 0.5 * self.w, (1.0 - y) * 0.5 * self.h, z))
    }
}

/// Renders the meshes as seen by `camera` into a `width` x `height` picture.
pub fn render(meshes: &[PreviewMesh], camera: &Camera, width: u32, height: u32) -> Image {
    let (w, h) = (width.max(1) as usize, height.max(1) as usize);
    let (mut rgb, mut depth) = canvas(w, h);
    let view = View::new(camera, w, h);
    let (light, project) = (view.light, |p: &Vec3| view.project(p));
    for m in meshes {
        for t in m.triangles {
            let Some(tri) = t
                .iter()
                .map(|&v| m.positions.get(v as usize))
                .collect::<Option<Vec<_>>>()
            else {
                continue;
            };
            let n = (tri[1] - tri[0]).cross(&(tri[2] - tri[0]));
            let Some(n) = n.try_normalize(0.0) else {
                continue;
            };
            let shade = 0.25 + 0.75 * n.dot(&light).abs();
            let color = m.color.map(|c| (c as Real * shade).min(255.0) as u8);
            let Some(s) = tri.iter().map(|p| project(p)).collect::<Option<Vec<_>>>() else {
                continue;
            };
            fill(&mut rgb, &mut depth, w, h, [s[0], s[1], s[2]], color);
        }
    }
    Image {
        width: w as u32,
        height: h as u32,
        rgb,
    }
}

/// Fills one screen triangle (x, y, depth) with a z-test.
fn fill(
    rgb: &mut [u8],
    depth: &mut [Real],
    w: usize,
    h: usize,
    s: [(Real, Real, Real); 3],
    color: [u8; 3],
) {
    fill_with(rgb, depth, w, h, s, &|_| color);
}

/// Fills one screen triangle (x, y, depth) with a z-test, each pixel the colour `color` gives for
/// its barycentric coordinates.
pub(crate) fn fill_with(
    rgb: &mut [u8],
    depth: &mut [Real],
    w: usize,
    h: usize,
    s: [(Real, Real, Real); 3],
    color: &dyn Fn([Real; 3]) -> [u8; 3],
) {
    let area = (s[1].0 - s[0].0) * (s[2].1 - s[0].1) - (s[2].0 - s[0].0) * (s[1].1 - s[0].1);
    if area.abs() < 1e-12 {
        return;
    }
    let x0 = s
        .iter()
        .map(|p| p.0)
        .fold(Real::INFINITY, Real::min)
        .floor()
        .max(0.0) as usize;
    let x1 = (s
        .iter()
        .map(|p| p.0)
        .fold(Real::NEG_INFINITY, Real::max)
        .ceil() as usize)
        .min(w);
    let y0 = s
        .iter()
        .map(|p| p.1)
        .fold(Real::INFINITY, Real::min)
        .floor()
        .max(0.0) as usize;
    let y1 = (s
        .iter()
        .map(|p| p.1)
        .fold(Real::NEG_INFINITY, Real::max)
        .ceil() as usize)
        .min(h);
    for y in y0..y1 {
        for x in x0..x1 {
            let (px, py) = (x as Real + 0.5, y as Real + 0.5);
            let e = |a: (Real, Real, Real), b: (Real, Real, Real)| {
                (b.0 - a.0) * (py - a.1) - (px - a.0) * (b.1 - a.1)
            };
            let (w0, w1, w2) = (
                e(s[1], s[2]) / area,
                e(s[2], s[0]) / area,
                e(s[0], s[1]) / area,
            );
            if w0 < 0.0 || w1 < 0.0 || w2 < 0.0 {
                continue;
            }
            let z = w0 * s[0].2 + w1 * s[1].2 + w2 * s[2].2;
            let k = y * w + x;
            if z < depth[k] {
                depth[k] = z;
                rgb[3 * k..3 * k + 3].copy_from_slice(&color([w0, w1, w2]));
            }
        }
    }
}

/// Encodes `image` as PNG and writes it atomically to `path`.
pub fn write_png(path: &Path, image: &Image) -> Result<(), PreviewError> {
    let mut bytes = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut bytes, image.width, image.height);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let err = |e: png::EncodingError| PreviewError::Encode {
            path: path.to_path_buf(),
            message: e.to_string(),
        };
        let mut writer = enc.write_header().map_err(err)?;
        writer.write_image_data(&image.rgb).map_err(err)?;
    }
    write_atomic(path, &bytes).map_err(|source| PreviewError::Io {
        path: path.to_path_buf(),
        source,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use tryon_core::shapes::icosphere;

    #[test]
    fn the_ray_through_a_drawn_pixel_passes_through_what_was_drawn_there() {
        // A big grey ball frames the picture; a small red one sits off to one side. The ray
        // through the middle of the red pixels must pass through the red ball.
        let big = icosphere(1.0, 2, Vec3::zeros());
        let centre = Vec3::new(-0.9, -0.3, 0.6);
        let small = icosphere(0.05, 2, centre);
        let (tb, _) = big.triangulate();
        let (ts, _) = small.triangulate();
        let meshes = [
            PreviewMesh {
                positions: &big.positions,
                triangles: &tb,
                color: [90, 90, 90],
            },
            PreviewMesh {
                positions: &small.positions,
                triangles: &ts,
                color: [250, 0, 0],
            },
        ];
        let cam = Camera::framing(&meshes);
        let (w, h) = (300, 200);
        let img = render(&meshes, &cam, w, h);
        let (mut sx, mut sy, mut n) = (0.0, 0.0, 0.0);
        for (k, px) in img.rgb.chunks(3).enumerate() {
            if px[0] > 60 && px[1] == 0 && px[2] == 0 {
                sx += (k % w as usize) as Real + 0.5;
                sy += (k / w as usize) as Real + 0.5;
                n += 1.0;
            }
        }
        assert!(n > 10.0, "the small ball is drawn ({n} pixels)");
        let (eye, dir) = cam.ray(sx / n, sy / n, w, h);
        assert!((dir.norm() - 1.0).abs() < 1e-12);
        let miss = (centre - eye) - dir * (centre - eye).dot(&dir);
        assert!(
            miss.norm() < 0.05,
            "the ray misses the ball's centre by {}",
            miss.norm()
        );
    }

    #[test]
    fn sphere_is_drawn_in_the_middle_and_round_trips_through_png() {
        let s = icosphere(1.0, 2, Vec3::zeros());
        let (tris, _) = s.triangulate();
        let meshes = [PreviewMesh {
            positions: &s.positions,
            triangles: &tris,
            color: [200, 60, 60],
        }];
        let cam = Camera::framing(&meshes);
        let img = render(&meshes, &cam, 64, 48);
        let px = |x: usize, y: usize| &img.rgb[3 * (y * 64 + x)..3 * (y * 64 + x) + 3];
        let centre = px(32, 24);
        assert!(
            centre[0] as u32 > 2 * centre[1] as u32,
            "centre should be red: {centre:?}"
        );
        assert_eq!(px(0, 0)[0], px(0, 0)[1], "corner should be background grey");
        let path = std::env::temp_dir().join(format!("tryon-preview-{}.png", std::process::id()));
        write_png(&path, &img).unwrap();
        let dec = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&path).unwrap()));
        let mut reader = dec.read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size().unwrap()];
        reader.next_frame(&mut buf).unwrap();
        assert_eq!(&buf[..img.rgb.len()], &img.rgb[..]);
        std::fs::remove_file(&path).unwrap();
        let bad = Path::new("/nonexistent-dir/x.png");
        assert!(matches!(write_png(bad, &img), Err(PreviewError::Io { .. })));
    }
}
