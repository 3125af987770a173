//! The kimono mesh, built from the eight straight-cut parts of one bolt: two sleeves, two body
//! panels (each one strip folded over the shoulder, back half and front half), two okumi (the
//! front overlap panels), the collar and the over-collar (共衿, a second layer on the collar's
//! middle, one surface here). It is laid out flat, as a kimono is shown open on a stand: the back
//! layer at z = −GAP, the front at +GAP, folds and sewn side seams at z = 0, the left front (上前,
//! +x) over the right (下前), y up from the hem, x toward the wearer's left.
//!
//! Every part is a grid whose rows fall on the pattern's levels ([`crate::levels`]); parts share
//! the vertices of their seams, so the mesh is one sewn surface. Each tailoring dimension is a set
//! of mesh edges whose lengths sum to it (P2), each belonging to one sub-mesh. UVs are the bolt's
//! own coordinates in metres (u across the bolt, v along it), so a print runs on along the bolt.

use crate::builder::Builder;
use crate::dims::{BOLT_WIDTH, Dimensions, SUN};
use crate::levels::{Layout, LevelError, Levels, okumi_drop};
use crate::orient::orient;
use std::collections::HashMap;
use tryon_core::math::{Real, Vec3};

/// Half the distance between the flat kimono's back and front layers, m.
pub const GAP: Real = 0.01;
/// How far an overlapping layer (okumi, collar) sits above the one beneath, m.
pub const LAYER: Real = 0.003;
/// The over-collar reaches this far down each front from the shoulder fold, m (1尺3寸).
pub const OVER_COLLAR: Real = 13.0 * SUN;

/// The parts cut from the bolt.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Part {
    RightSleeve,
    LeftSleeve,
    RightBody,
    LeftBody,
    RightOkumi,
    LeftOkumi,
    Collar,
    OverCollar,
}

/// The sub-meshes P2 fits separately (indices into the fit's weights).
pub mod sub {
    pub const RIGHT_SLEEVE: u8 = 0;
    pub const LEFT_SLEEVE: u8 = 1;
    pub const BACK: u8 = 2;
    pub const LEFT_FRONT: u8 = 3;
    pub const RIGHT_FRONT: u8 = 4;
    pub const COLLAR: u8 = 5;
    pub const COUNT: usize = 6;
}

/// A tailoring dimension as mesh edges: their lengths sum to it.
#[derive(Clone, Debug, PartialEq)]
pub struct DimensionSet {
    pub name: &'static str,
    /// Index into [`Dimensions::table`] of the value it measures.
    pub table_index: usize,
    /// Whether it is one of Table 1's entries (the rest are the right side's mirror images, fitted
    /// but not reported).
    pub in_table: bool,
    pub sub_mesh: u8,
    pub edges: Vec<[u32; 2]>,
}

/// The kimono: a sewn triangle mesh with its parts, sub-meshes, bolt UVs and dimension sets.
#[derive(Clone, Debug, PartialEq)]
pub struct KimonoMesh {
    pub positions: Vec<Vec3>,
    pub triangles: Vec<[u32; 3]>,
    pub part: Vec<Part>,
    pub sub_mesh: Vec<u8>,
    /// Bolt coordinates, m: a vertex on a seam between parts has one per side.
    pub uvs: Vec<[Real; 2]>,
    pub uv_triangles: Vec<[u32; 3]>,
    /// The mesh vertex of each UV vertex.
    pub uv_vertex: Vec<u32>,
    pub dimensions: Vec<DimensionSet>,
}

impl KimonoMesh {
    /// The length of dimension set `k` on `positions`.
    /// NaN when `k` names no set or an edge's vertex is missing from `positions`.
    pub fn measure(&self, k: usize, positions: &[Vec3]) -> Real {
        let Some(set) = self.dimensions.get(k) else {
            return Real::NAN;
        };
        set.edges
            .iter()
            .map(
                |&[a, b]| match (positions.get(a as usize), positions.get(b as usize)) {
                    (Some(p), Some(q)) => (p - q).norm(),
                    _ => Real::NAN,
                },
            )
            .sum()
    }

    /// Vertices of each sub-mesh (a vertex on the border of two belongs to both).
    pub fn sub_mesh_vertices(&self) -> Vec<Vec<u32>> {
        let mut seen = vec![[false; sub::COUNT]; self.positions.len()];
        let mut out = vec![Vec::new(); sub::COUNT];
        for (t, s) in self.triangles.iter().zip(&self.sub_mesh) {
            for &v in t {
                let f = &mut seen[v as usize][*s as usize];
                if !*f {
                    *f = true;
                    out[*s as usize].push(v);
                }
            }
        }
        out.iter_mut().for_each(|v| v.sort_unstable());
        out
    }
}

/// The kimono tailored to `d`, with the rows and columns of `layout`.
pub fn build(d: &Dimensions, layout: &Layout) -> Result<KimonoMesh, LevelError> {
    let lv = Levels::new(d)?;
    let mut b = Builder::default();
    let centre = crate::panels::back_centre(&mut b, &lv, layout);
    let chains =
        [false, true].map(|left| crate::panels::side(&mut b, d, &lv, layout, left, &centre));
    crate::collar::collar(&mut b, d, layout, &chains);
    let mut dims = std::mem::take(&mut b.dims);
    let mut tris = b.tris;
    let mut flipped = orient(&mut tris, b.pos.len());
    // The first triangle is the right back's, at the hem: it faces away from the wearer (-z).
    let p = |i: u32| b.pos[i as usize];
    let t0 = tris[0];
    if (p(t0[1]) - p(t0[0])).cross(&(p(t0[2]) - p(t0[0]))).z > 0.0 {
        tris.iter_mut().for_each(|t| t.swap(1, 2));
        flipped.iter_mut().for_each(|f| *f = !*f);
    }
    for (t, f) in b.corner_uv.iter_mut().zip(&flipped) {
        if *f {
            t.swap(1, 2);
        }
    }
    let (uvs, uv_triangles, uv_vertex) = uv_vertices(&tris, &b.corner_uv);
    dims.sort_by_key(|s| (!s.in_table, s.table_index));
    Ok(KimonoMesh {
        positions: b.pos,
        triangles: tris,
        part: b.part,
        sub_mesh: b.sub,
        uvs,
        uv_triangles,
        uv_vertex,
        dimensions: dims,
    })
}

/// One UV vertex per mesh vertex and distinct UV.
fn uv_vertices(
    tris: &[[u32; 3]],
    corner: &[[[Real; 2]; 3]],
) -> (Vec<[Real; 2]>, Vec<[u32; 3]>, Vec<u32>) {
    let mut index: HashMap<(u32, u64, u64), u32> = HashMap::new();
    let (mut uvs, mut of) = (Vec::new(), Vec::new());
    let uv_tris = tris
        .iter()
        .zip(corner)
        .map(|(t, c)| {
            std::array::from_fn(|k| {
                let key = (t[k], c[k][0].to_bits(), c[k][1].to_bits());
                *index.entry(key).or_insert_with(|| {
                    uvs.push(c[k]);
                    of.push(t[k]);
                    (uvs.len() - 1) as u32
                })
            })
        })
        .collect();
    (uvs, uv_tris, of)
}

/// Where each part starts along the bolt, m: the sleeves, the bodies, the okumi strip (both okumi
/// side by side, each half the bolt's width), the collar strip (collar and over-collar side by side).
pub(crate) fn bolt_starts(d: &Dimensions) -> [Real; 6] {
    let (s, l) = (d.sleeve_length, d.body_length);
    let ok = 4.0 * s + 4.0 * l;
    [
        0.0,
        2.0 * s,
        4.0 * s,
        4.0 * s + 2.0 * l,
        ok,
        ok + l - okumi_drop(d),
    ]
}

/// Half the bolt's width: the okumi and the collar strips are cut from halves.
pub(crate) const HALF_BOLT: Real = 0.5 * BOLT_WIDTH;
