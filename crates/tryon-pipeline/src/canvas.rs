//! The canvas a fold is drawn on, as P3 draws them: the dressed garment on the body at the start
//! (after `[folding] drape`, as the folds are made), seen by the preview's camera (`Camera::framing` of body and garment) at the scene's preview
//! size. `tryon canvas` writes it; a `[[fold]] screen` line's pixels land on the garment where the
//! ray through each pixel first meets it.

use crate::build::AssembleError;
use crate::scene::Scene;
use crate::wardrobe::Dressed;
pub use fold::Miss;
use std::path::Path;
use tryon_core::math::{Real, Vec3};
use tryon_core::mesh::PolyMesh;
use tryon_io::preview::{Camera, Image, PreviewMesh, garment_colour, render};

/// The picture folds are drawn in: its camera and size (pixels).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Canvas {
    pub camera: Camera,
    pub width: u32,
    pub height: u32,
}

impl Canvas {
    /// The scene's canvas for `body` dressed in `garment`.
    pub fn new(scene: &Scene, body: &PolyMesh, garment: &PolyMesh) -> Canvas {
        let (w, h) = (scene.output.preview_width, scene.output.preview_height);
        Canvas::framing(body, garment, w, h)
    }

    /// A `width` x `height` canvas framing `body` and `garment` as the preview does.
    pub fn framing(body: &PolyMesh, garment: &PolyMesh, width: u32, height: u32) -> Canvas {
        let meshes = [
            PreviewMesh {
                positions: &body.positions,
                triangles: &[],
                color: [0; 3],
            },
            PreviewMesh {
                positions: &garment.positions,
                triangles: &[],
                color: [0; 3],
            },
        ];
        Canvas {
            camera: Camera::framing(&meshes),
            width,
            height,
        }
    }

    /// The point of `garment` that pixel `(x, y)` shows, unless the body is in front of it.
    pub fn land(
        &self,
        pixel: [Real; 2],
        body: (&[Vec3], &[[u32; 3]]),
        garment: (&[Vec3], &[[u32; 3]]),
    ) -> Result<Vec3, Miss> {
        let (eye, dir) = self.camera.ray(pixel[0], pixel[1], self.width, self.height);
        fold::land(eye, dir, body, garment)
    }

    /// The canvas picture: the body and the garment, shaded as the preview shades them.
    pub fn draw(&self, body: &PolyMesh, garment: &PolyMesh) -> Image {
        let (bt, _) = body.triangulate();
        let (gt, _) = garment.triangulate();
        let meshes = [
            PreviewMesh {
                positions: &body.positions,
                triangles: &bt,
                color: [205, 170, 150],
            },
            PreviewMesh {
                positions: &garment.positions,
                triangles: &gt,
                color: garment_colour(0),
            },
        ];
        render(&meshes, &self.camera, self.width, self.height)
    }
}

/// The canvas of `scene` (the body dressed and draped, before any fold) and its picture.
pub fn picture(scene: &Scene) -> Result<(Canvas, Image), AssembleError> {
    let body = crate::build::body(scene)?;
    let collides = scene.effects.body_collision != crate::scene::CollisionMethod::None;
    let dressed = crate::wardrobe::dress(scene, &body, collides, &|_| {})?;
    let (draped, body) = drape(scene, &body.mesh, &dressed)?;
    let mut garment = dressed.mesh;
    if let Some(x) = draped {
        garment.positions = x;
    }
    let canvas = Canvas::new(scene, &body, &garment);
    let image = canvas.draw(&body, &garment);
    Ok((canvas, image))
}

/// Writes the canvas picture of `scene` to `path` (atomically).
pub fn write(scene: &Scene, path: &Path) -> Result<(), AssembleError> {
    let (_, image) = picture(scene)?;
    tryon_io::preview::write_png(path, &image).map_err(AssembleError::Canvas)
}

/// The garment's positions after it hangs `[folding] drape` seconds on the body held in the
/// motion's first pose (P3 draws folds on a garment at rest: a fold drawn on the garment as
/// placed is pushed about while the garment settles), with the body's positions in that pose;
/// `None` and the body as given for a drape of 0.
pub fn drape(
    scene: &Scene,
    body: &PolyMesh,
    dressed: &Dressed,
) -> Result<(Option<Vec<Vec3>>, PolyMesh), AssembleError> {
    let t = scene.folding.drape;
    if t <= 0.0 {
        return Ok((None, body.clone()));
    }
    let mut s = scene.clone();
    s.fold.clear();
    s.scene.settle = s.scene.settle.max(t);
    s.scene.duration = Some(t);
    s.output.referee_every = 0;
    // The coarse cloth hangs; the surface stages would only cost time (and their output is not
    // the garment's vertices).
    s.effects.refine = 0;
    let mut p = crate::Pipeline::new(s)?;
    let frames = (t * scene.scene.fps).round().max(1.0) as usize;
    let out = p.run(Some(frames), |_, _| {});
    let mut posed = body.clone();
    let Some(last) = out.frames.last().filter(|f| {
        f.garment.len() == dressed.mesh.positions.len()
            && f.garment.iter().all(|x| x.iter().all(|c| c.is_finite()))
    }) else {
        return Ok((None, posed));
    };
    let b = p.body_at(last.pose.as_ref());
    if b.len() == posed.positions.len() {
        posed.positions = b;
    }
    Ok((Some(last.garment.clone()), posed))
}

/// The scene's `[[fold]]` lines as the fold stage takes them, `screen` lines landed on `garment`.
pub(crate) fn fold_lines(
    scene: &Scene,
    body: &PolyMesh,
    garment: &PolyMesh,
) -> Result<Vec<fold::FoldLine>, AssembleError> {
    let mut lines: Vec<fold::FoldLine> = scene.fold.iter().map(|f| f.line()).collect();
    if scene.fold.iter().all(|f| f.screen.is_empty()) {
        return Ok(lines);
    }
    let canvas = Canvas::new(scene, body, garment);
    let (bt, _) = body.triangulate();
    let (gt, _) = garment.triangulate();
    for (n, f) in scene.fold.iter().enumerate() {
        if f.screen.is_empty() {
            continue;
        }
        lines[n].points = f
            .screen
            .iter()
            .enumerate()
            .map(|(k, &pixel)| {
                canvas
                    .land(pixel, (&body.positions, &bt), (&garment.positions, &gt))
                    .map_err(|m| AssembleError::FoldScreen {
                        fold: n,
                        point: k,
                        pixel,
                        reason: m.describe(),
                    })
            })
            .collect::<Result<_, _>>()?;
    }
    Ok(lines)
}

#[cfg(test)]
mod tests {
    use super::*;
    use tryon_core::mesh::grid_xz;
    use tryon_core::shapes::icosphere;

    /// A sheet upright in the xy plane facing +z and a small ball just in front of its middle.
    fn sheet_and_ball() -> (PolyMesh, PolyMesh) {
        let mut sheet = grid_xz(8, 8, 1.0, 1.0, 0.0);
        for p in &mut sheet.positions {
            *p = Vec3::new(p.x, p.z, 0.0);
        }
        (icosphere(0.1, 2, Vec3::new(0.0, 0.0, 0.3)), sheet)
    }

    fn mesh_pair<'a>(m: &'a PolyMesh, t: &'a [[u32; 3]]) -> (&'a [Vec3], &'a [[u32; 3]]) {
        (&m.positions, t)
    }

    #[test]
    fn a_pixel_lands_on_the_garment_it_shows_and_is_refused_where_it_shows_none_or_the_body() {
        let (ball, sheet) = sheet_and_ball();
        let canvas = Canvas::framing(&ball, &sheet, 400, 300);
        let (bt, _) = ball.triangulate();
        let (st, _) = sheet.triangulate();
        let image = canvas.draw(&ball, &sheet);
        let garment = garment_colour(0);
        let colour = |x: usize, y: usize| {
            let k = (y * 400 + x) * 3;
            [image.rgb[k], image.rgb[k + 1], image.rgb[k + 2]]
        };
        // Every pixel drawn in the garment's hue lands on the sheet (z = 0, inside its square);
        // every background pixel shows no garment; pixels of the ball are hidden.
        let (mut on, mut hidden, mut none) = (0, 0, 0);
        for y in (0..300).step_by(7) {
            for x in (0..400).step_by(7) {
                let c = colour(x, y);
                let px = [x as Real + 0.5, y as Real + 0.5];
                let got = canvas.land(px, mesh_pair(&ball, &bt), mesh_pair(&sheet, &st));
                let blue = c[2] as i32 > c[0] as i32 + 30 && c[2] as i32 > c[1] as i32;
                let grey = c[0].abs_diff(c[1]) < 4 && c[2] >= c[1];
                if blue && garment[2] > garment[0] {
                    let p = got.expect("a garment pixel lands");
                    assert!(p.z.abs() < 1e-9 && p.x.abs() <= 0.5 + 1e-9 && p.y.abs() <= 0.5 + 1e-9);
                    on += 1;
                } else if grey {
                    assert_eq!(got, Err(Miss::NoGarment), "background pixel {x},{y}");
                    none += 1;
                } else if c[0] > c[2] {
                    assert_eq!(got, Err(Miss::Hidden), "ball pixel {x},{y}");
                    hidden += 1;
                }
            }
        }
        assert!(on > 100 && none > 100 && hidden > 3, "{on} {none} {hidden}");
    }
}
