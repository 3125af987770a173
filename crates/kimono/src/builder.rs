//! Grids of vertices made into triangles with their part, sub-mesh and bolt UVs: what every part
//! of the kimono is built with.

use crate::mesh::{DimensionSet, Part};
use tryon_core::math::{Real, Vec3};

/// The mesh as it is built: positions, triangles and, per triangle, its part, sub-mesh and the UVs
/// of its corners.
#[derive(Debug, Default)]
pub(crate) struct Builder {
    pub pos: Vec<Vec3>,
    pub tris: Vec<[u32; 3]>,
    pub part: Vec<Part>,
    pub sub: Vec<u8>,
    pub corner_uv: Vec<[[Real; 2]; 3]>,
    pub dims: Vec<DimensionSet>,
}

impl Builder {
    pub fn vert(&mut self, x: Real, y: Real, z: Real) -> u32 {
        self.pos.push(Vec3::new(x, y, z));
        (self.pos.len() - 1) as u32
    }

    /// Two triangles per cell of `ids` (rows of vertex indices, `uv` their bolt coordinates); a
    /// triangle that names a vertex twice (a row collapsed to a point) is left out.
    pub fn grid(&mut self, ids: &[Vec<u32>], uv: &[Vec<[Real; 2]>], part: Part, sub: u8) {
        for r in 0..ids.len() - 1 {
            for j in 0..ids[r].len() - 1 {
                let c = [(r, j), (r, j + 1), (r + 1, j + 1), (r + 1, j)];
                for t in [[0, 1, 2], [0, 2, 3]] {
                    let v = t.map(|k| ids[c[k].0][c[k].1]);
                    if v[0] == v[1] || v[1] == v[2] || v[0] == v[2] {
                        continue;
                    }
                    self.tris.push(v);
                    self.part.push(part);
                    self.sub.push(sub);
                    self.corner_uv.push(t.map(|k| uv[c[k].0][c[k].1]));
                }
            }
        }
    }

    /// A dimension measured along `chain`, leaving out the edges `skip` names (by position).
    pub fn dimension(
        &mut self,
        table_index: usize,
        in_table: bool,
        sub_mesh: u8,
        chain: &[u32],
        skip: &dyn Fn(usize) -> bool,
    ) {
        let edges = chain
            .windows(2)
            .enumerate()
            .filter(|(i, _)| !skip(*i))
            .map(|(_, w)| [w[0], w[1]])
            .collect();
        self.dims.push(DimensionSet {
            name: crate::dims::TABLE_1[table_index],
            table_index,
            in_table,
            sub_mesh,
            edges,
        });
    }
}

/// `a` to `b` by `t`.
pub(crate) fn lerp(a: Real, b: Real, t: Real) -> Real {
    a + (b - a) * t
}
