//! The fine lattice over the coarse mesh and its per-frame evaluation.

use crate::pn::PnPatch;
use std::collections::HashMap;
use thiserror::Error;
use tryon_core::frames::{FineSurface, FineVertexSource, lattice_index, lattice_len};
use tryon_core::math::{Real, Vec3};
use tryon_core::mesh::{MeshError, PolyMesh};

/// Highest tessellation level accepted (64 segments per coarse edge).
pub const MAX_LEVEL: u8 = 6;

/// Why a refiner could not be built.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum RefineError {
    #[error("refine level {level} is out of range: expected 0..={MAX_LEVEL}")]
    Level { level: u8 },
    #[error("coarse mesh: {0}")]
    Mesh(#[from] MeshError),
    #[error("refine level {level} would make {count} fine vertices, more than the {limit} allowed")]
    TooMany {
        level: u8,
        count: usize,
        limit: usize,
    },
}

/// Most fine vertices a refiner will build.
pub const MAX_FINE_VERTICES: usize = 20_000_000;

/// PN-triangle refinement of a coarse mesh at a fixed level. Fine vertex `k < coarse count` is
/// coarse vertex `k`.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct PnRefiner {
    pub level: u8,
    /// Segments per coarse edge, `2^level`.
    pub segments: u32,
    pub coarse_vertices: usize,
    /// The coarse mesh's triangulated view.
    pub coarse_triangles: Vec<[u32; 3]>,
    pub sources: Vec<FineVertexSource>,
    pub lattice: Vec<u32>,
    pub triangles: Vec<[u32; 3]>,
    patches: Vec<PnPatch>,
}

/// Level at which lattice point `(i, j)` of a `2^level` lattice first appears.
pub fn point_level(level: u8, i: u32, j: u32) -> u8 {
    let tz = |x: u32| {
        if x == 0 {
            level as u32
        } else {
            x.trailing_zeros().min(level as u32)
        }
    };
    level - tz(i).min(tz(j)) as u8
}

/// Fine vertices of a coarse mesh of `vertices`, `edges` and `triangles` refined at `level`:
/// its vertices, `2^level - 1` on each edge and the lattice's inner points on each triangle.
pub fn fine_vertex_count(vertices: usize, edges: usize, triangles: usize, level: u8) -> usize {
    let n = 1usize << level.min(MAX_LEVEL);
    let inner = (n - 1) * n.saturating_sub(2) / 2;
    vertices + edges * (n - 1) + triangles * inner
}

impl PnRefiner {
    /// Builds the fine topology of `coarse` at `level` (validating the coarse mesh).
    pub fn new(coarse: &PolyMesh, level: u8) -> Result<Self, RefineError> {
        if level > MAX_LEVEL {
            return Err(RefineError::Level { level });
        }
        coarse.validate()?;
        let (tris, _) = coarse.triangulate();
        let n = 1u32 << level;
        let nv = coarse.positions.len();
        let per = lattice_len(n);
        let mut edges: HashMap<(u32, u32), usize> = HashMap::new();
        for t in &tris {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                let len = edges.len();
                edges.entry((a.min(b), a.max(b))).or_insert(len);
            }
        }
        let count = fine_vertex_count(nv, edges.len(), tris.len(), level);
        if count > MAX_FINE_VERTICES {
            return Err(RefineError::TooMany {
                level,
                count,
                limit: MAX_FINE_VERTICES,
            });
        }
        let mut sources = vec![
            FineVertexSource {
                face: u32::MAX,
                bary: [1.0, 0.0, 0.0],
                level: 0,
            };
            nv
        ];
        // Coarse vertices: their first triangle.
        for (f, t) in tris.iter().enumerate().rev() {
            for k in 0..3 {
                let mut bary = [0.0; 3];
                bary[k] = 1.0;
                sources[t[k] as usize] = FineVertexSource {
                    face: f as u32,
                    bary,
                    level: 0,
                };
            }
        }
        // Edge vertices: ordered from the smaller coarse index; created by the first triangle.
        let edge_base = |e: usize| (nv + e * (n as usize - 1)) as u32;
        sources.resize(
            nv + edges.len() * (n as usize - 1),
            FineVertexSource::default(),
        );
        let mut made = vec![false; edges.len()];
        let mut lattice = vec![0u32; tris.len() * per];
        let mut next = sources.len() as u32;
        for (f, t) in tris.iter().enumerate() {
            let lat = &mut lattice[f * per..(f + 1) * per];
            for j in 0..=n {
                for i in 0..=n - j {
                    let k = n - i - j;
                    let bary = [
                        k as Real / n as Real,
                        i as Real / n as Real,
                        j as Real / n as Real,
                    ];
                    // Which coarse edge (if any) holds the point, as (from, to, steps from `from`).
                    let on_edge = if (i, j) == (0, 0) {
                        lat[lattice_index(n, i, j)] = t[0];
                        continue;
                    } else if (i, j) == (n, 0) {
                        lat[lattice_index(n, i, j)] = t[1];
                        continue;
                    } else if (i, j) == (0, n) {
                        lat[lattice_index(n, i, j)] = t[2];
                        continue;
                    } else if j == 0 {
                        Some((t[0], t[1], i))
                    } else if k == 0 {
                        Some((t[1], t[2], j))
                    } else if i == 0 {
                        Some((t[2], t[0], n - j))
                    } else {
                        None
                    };
                    let v = match on_edge {
                        Some((a, b, s)) => {
                            let e = edges[&(a.min(b), a.max(b))];
                            let step = if a < b { s } else { n - s };
                            let v = edge_base(e) + step - 1;
                            if !made[e] {
                                sources[v as usize] = FineVertexSource {
                                    face: f as u32,
                                    bary,
                                    level: point_level(level, i, j),
                                };
                            }
                            v
                        }
                        None => {
                            sources.push(FineVertexSource {
                                face: f as u32,
                                bary,
                                level: point_level(level, i, j),
                            });
                            next += 1;
                            next - 1
                        }
                    };
                    lat[lattice_index(n, i, j)] = v;
                }
            }
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                made[edges[&(a.min(b), a.max(b))]] = true;
            }
        }
        debug_assert_eq!(sources.len(), count);
        let mut triangles = Vec::with_capacity(tris.len() * (n * n) as usize);
        for f in 0..tris.len() {
            let lat = &lattice[f * per..(f + 1) * per];
            let at = |i: u32, j: u32| lat[lattice_index(n, i, j)];
            for j in 0..n {
                for i in 0..n - j {
                    triangles.push([at(i, j), at(i + 1, j), at(i, j + 1)]);
                    if i + j + 1 < n {
                        triangles.push([at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)]);
                    }
                }
            }
        }
        Ok(PnRefiner {
            level,
            segments: n,
            coarse_vertices: nv,
            coarse_triangles: tris,
            sources,
            lattice,
            triangles,
            patches: Vec::new(),
        })
    }

    /// Number of fine vertices.
    pub fn fine_vertices(&self) -> usize {
        self.sources.len()
    }

    /// The PN patch of coarse triangle `f` as last evaluated.
    pub fn patch(&self, f: usize) -> Option<&PnPatch> {
        self.patches.get(f)
    }

    /// Evaluates the fine surface for the coarse positions and unit vertex normals.
    pub fn evaluate(&mut self, x: &[Vec3], normals: &[Vec3], out: &mut FineSurface) {
        self.patches.clear();
        self.patches.extend(self.coarse_triangles.iter().map(|t| {
            let [a, b, c] = t.map(|v| v as usize);
            PnPatch::new([x[a], x[b], x[c]], [normals[a], normals[b], normals[c]])
        }));
        if out.segments != self.segments
            || out.lattice.len() != self.lattice.len()
            || out.sources.len() != self.sources.len()
        {
            out.segments = self.segments;
            out.coarse_triangles.clone_from(&self.coarse_triangles);
            out.lattice.clone_from(&self.lattice);
            out.triangles.clone_from(&self.triangles);
            out.sources.clone_from(&self.sources);
        }
        let m = self.sources.len();
        out.positions.resize(m, Vec3::zeros());
        out.normals.resize(m, Vec3::zeros());
        for (k, s) in self.sources.iter().enumerate() {
            if k < self.coarse_vertices {
                // The patch interpolates its corners exactly; isolated vertices stay as they are.
                out.positions[k] = x[k];
                out.normals[k] = normals[k];
            } else {
                let p = &self.patches[s.face as usize];
                out.positions[k] = p.position(s.bary);
                out.normals[k] = p.normal(s.bary);
            }
        }
    }
}
