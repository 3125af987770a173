//! The scene's garments as one cloth: each built and placed clear of the body, each worn over
//! those of lower layers (`garment_fit::place_over`), then joined into one mesh whose vertex
//! ranges say which garment is which. Contact between them is then the cloth's contact with
//! itself, inside the one solve.

use crate::build::{AssembleError, BuiltBody};
use crate::scene::{GarmentSection, Scene};
use body_collide::ExactCollider;
use cloth_dyn::wear::GarmentWear;
use garment_fit::{Attachment, LayerPlacement};
use std::ops::Range;
use tryon_core::math::Real;
use tryon_core::mesh::{Face, PolyMesh};

/// Farthest along the body's normal an inner garment's point counts as under an outer vertex
/// (m): layers are millimetres to centimetres apart; beyond this, a point is another part of the
/// body's garment (the other side of a sleeve).
const LAYER_DEPTH: Real = 0.04;

/// The gap placement leaves between layers, in the cloth's self-contact thickness: a little more
/// than it, so the layers start apart.
const LAYER_GAP: Real = 1.5;

/// A piece of a real garment with fewer than this share of the garment's vertices (or, when
/// pieces are worn over each other, of each piece beneath it) is sewn on (a patch, a pocket): it
/// rides on its host and is lifted whole.
const SMALL_PIECE: Real = 0.1;

/// The garments as one cloth.
#[derive(Clone, Debug)]
pub struct Dressed {
    /// All garments' vertices and faces, garment after garment in the order listed.
    pub mesh: PolyMesh,
    /// Each garment's vertices in `mesh`, with its layer and material.
    pub wear: Vec<GarmentWear>,
    /// Vertices moved out of the body when placed.
    pub placed_moved: usize,
    /// What wearing each garment over the lower layers moved (one per garment).
    pub layered: Vec<LayerPlacement>,
    /// What wearing each garment's separate pieces over each other moved (one per garment).
    pub pieces: Vec<LayerPlacement>,
    /// Small separate pieces of the real garments riding on the piece beneath them (in `mesh`'s
    /// numbering).
    pub attachments: Vec<Attachment>,
    /// Vertices tied to the body (a kimono's cord), held to it as bands are.
    pub tied: Vec<u32>,
}

impl Dressed {
    /// The garment vertex `v` belongs to.
    pub fn garment_of(&self, v: u32) -> usize {
        self.wear
            .iter()
            .position(|w| w.particles.contains(&v))
            .unwrap_or(0)
    }
}

/// `mesh`'s faces with every index moved up by `base`.
fn shifted(mesh: &PolyMesh, base: u32) -> impl Iterator<Item = Face> + '_ {
    mesh.faces.iter().map(move |f| match f {
        Face::Tri(t) => Face::Tri(t.map(|v| v + base)),
        Face::Quad(q) => Face::Quad(q.map(|v| v + base)),
    })
}

/// Meshes joined into one, in order.
fn join<'a>(meshes: impl IntoIterator<Item = &'a PolyMesh>) -> PolyMesh {
    let mut out = PolyMesh::default();
    for m in meshes {
        let base = out.positions.len() as u32;
        out.positions.extend_from_slice(&m.positions);
        out.faces.extend(shifted(m, base));
    }
    out
}

/// Wears a real garment's separate pieces over each other (`garment_fit::place_pieces`) and
/// clears the body again; only where the cloth meets itself, which alone keeps them apart.
fn wear_pieces(
    scene: &Scene,
    garment: &GarmentSection,
    m: &mut PolyMesh,
    placer: &mut ExactCollider,
) -> LayerPlacement {
    if !scene.effects.self_collision || !matches!(garment, GarmentSection::Mhclo(_)) {
        return LayerPlacement::default();
    }
    let gap = LAYER_GAP * scene.cloth.self_thickness;
    let cell = garment_fit::median_edge(m).max(0.005);
    let r = garment_fit::place_pieces(m, placer, (gap, cell, LAYER_DEPTH), SMALL_PIECE);
    if r.moved > 0 {
        garment_fit::place_outside(m, placer);
    }
    r
}

/// Builds, places and joins the scene's garments on `body`; `collides` says whether the body is
/// collided with (placement needs it).
pub(crate) fn dress(
    scene: &Scene,
    body: &BuiltBody,
    collides: bool,
    progress: crate::Progress,
) -> Result<Dressed, AssembleError> {
    let worn = scene.garments();
    let made = worn
        .iter()
        .map(|w| crate::garments::made(scene, w.garment, body.makehuman.as_ref(), progress))
        .collect::<Result<Vec<_>, _>>()?;
    let mut tied_own = Vec::with_capacity(made.len());
    let mut meshes = Vec::with_capacity(made.len());
    for m in made {
        tied_own.push(m.tied);
        meshes.push(m.mesh);
    }
    let mut placed_moved = 0;
    let mut layered = vec![LayerPlacement::default(); meshes.len()];
    let mut pieces = vec![LayerPlacement::default(); meshes.len()];
    if collides {
        let thickness = scene.cloth.thickness;
        let mut placer = ExactCollider::new(body.start_mesh(), thickness)?;
        let gap = LAYER_GAP * scene.cloth.self_thickness;
        for (k, m) in meshes.iter_mut().enumerate() {
            placed_moved += garment_fit::place_outside(m, &mut placer);
            pieces[k] = wear_pieces(scene, worn[k].garment, m, &mut placer);
        }
        // Lowest layer first; ties in the order listed.
        let mut order: Vec<usize> = (0..meshes.len()).collect();
        order.sort_by_key(|&k| (worn[k].layer, k));
        for (rank, &k) in order.iter().enumerate() {
            let lower: Vec<usize> = order[..rank]
                .iter()
                .copied()
                .filter(|&j| worn[j].layer < worn[k].layer)
                .collect();
            if lower.is_empty() {
                continue;
            }
            let inner = join(lower.iter().map(|&j| &meshes[j]));
            let cell = garment_fit::median_edge(&inner).max(0.005);
            let m = &mut meshes[k];
            layered[k] = garment_fit::place_over(m, &inner, &mut placer, (gap, cell, LAYER_DEPTH));
            placed_moved += garment_fit::place_outside(m, &mut placer);
            // Lifted over the garments beneath, its pieces may have closed on each other.
            let again = wear_pieces(scene, worn[k].garment, m, &mut placer);
            pieces[k].moved += again.moved;
            pieces[k].farthest = pieces[k].farthest.max(again.farthest);
        }
    }
    let mut wear = Vec::new();
    let mut attachments = Vec::new();
    let mut tied = Vec::new();
    let mut base = 0u32;
    for ((w, m), own) in worn.iter().zip(&meshes).zip(&tied_own) {
        tied.extend(own.iter().map(|v| v + base));
        if matches!(w.garment, GarmentSection::Mhclo(_)) {
            for mut a in garment_fit::attach_small_pieces(m, SMALL_PIECE, 0.03) {
                a.vertex += base;
                a.triangle = a.triangle.map(|v| v + base);
                attachments.push(a);
            }
        }
        let n = m.positions.len() as u32;
        let density = w.wear.density.unwrap_or(scene.cloth.density);
        wear.push(GarmentWear {
            particles: base..base + n,
            layer: w.layer,
            density_ratio: density / scene.cloth.density,
            stiffness: w.wear.stiffness,
        });
        base += n;
    }
    Ok(Dressed {
        mesh: join(&meshes),
        wear,
        placed_moved,
        layered,
        pieces,
        attachments,
        tied,
    })
}

/// The vertex range of each garment, for reports.
pub fn ranges(wear: &[GarmentWear]) -> Vec<Range<u32>> {
    wear.iter().map(|w| w.particles.clone()).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn joined_meshes_keep_their_faces_on_their_own_vertices() {
        let a = tryon_core::mesh::grid_xz(1, 1, 1.0, 1.0, 0.0);
        let b = tryon_core::mesh::grid_xz(2, 1, 1.0, 1.0, 0.5);
        let j = join([&a, &b]);
        assert_eq!(j.positions.len(), 4 + 6);
        assert_eq!(j.faces.len(), a.faces.len() + b.faces.len());
        let first = |f: &Face| match f {
            Face::Tri(t) => t.to_vec(),
            Face::Quad(q) => q.to_vec(),
        };
        assert!(
            j.faces[..a.faces.len()]
                .iter()
                .all(|f| first(f).iter().all(|&v| v < 4))
        );
        assert!(
            j.faces[a.faces.len()..]
                .iter()
                .all(|f| first(f).iter().all(|&v| v >= 4))
        );
        assert_eq!(j.positions[4..], b.positions[..]);
    }
}
