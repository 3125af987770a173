//! Several garments in one cloth model: each garment's particles are a range of the model's, with
//! its own layer (for contact between garments), areal density and stiffness. The garments share
//! no spring: they are separate pieces of one mesh, solved together so that contact between them
//! is inside the same solve.

use crate::model::ClothModel;
use std::ops::Range;
use tryon_core::math::Real;

/// One garment of a cloth model.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct GarmentWear {
    /// Its particles.
    pub particles: Range<u32>,
    /// Its layer: higher is worn over lower.
    pub layer: u32,
    /// Its areal density over the parameters' (masses scale by it).
    pub density_ratio: Real,
    /// Its stiffness over the parameters' (its springs' stiffness and damping scale by it).
    pub stiffness: Real,
}

/// Why garments could not be given to a model.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum WearError {
    #[error(
        "garment {index}: particles {start}..{end} do not lie within the model's {count}, after the previous garment's"
    )]
    Range {
        index: usize,
        start: u32,
        end: u32,
        count: usize,
    },
    #[error(
        "garment {index}: density ratio {density} and stiffness {stiffness} must be finite and positive"
    )]
    Material {
        index: usize,
        density: Real,
        stiffness: Real,
    },
    #[error("garment {index}: a spring joins particles {i} and {j} of different garments")]
    Shared { index: usize, i: u32, j: u32 },
}

impl ClothModel {
    /// Marks each garment's particles with its index and layer and scales its masses and springs.
    /// Garments are given in order of their particles, without overlap; particles of none stay
    /// garment 0's.
    pub fn wear(&mut self, garments: &[GarmentWear]) -> Result<(), WearError> {
        let n = self.particle_count();
        let mut end = 0;
        let mut of = vec![None; n];
        for (index, g) in garments.iter().enumerate() {
            let r = &g.particles;
            if r.start < end || r.end < r.start || r.end as usize > n {
                return Err(WearError::Range {
                    index,
                    start: r.start,
                    end: r.end,
                    count: n,
                });
            }
            let fine = |x: Real| x.is_finite() && x > 0.0;
            if !(fine(g.density_ratio) && fine(g.stiffness)) {
                return Err(WearError::Material {
                    index,
                    density: g.density_ratio,
                    stiffness: g.stiffness,
                });
            }
            end = r.end;
            for p in r.clone() {
                of[p as usize] = Some(index);
            }
        }
        let s = &self.springs;
        for k in 0..s.len() {
            let (i, j) = (s.i[k], s.j[k]);
            if of[i as usize] != of[j as usize] {
                let index = of[i as usize].or(of[j as usize]).unwrap_or(0);
                return Err(WearError::Shared { index, i, j });
            }
        }
        for (p, g) in of.iter().enumerate() {
            let Some(g) = g.map(|g| &garments[g]) else {
                continue;
            };
            self.garment[p] = of[p].unwrap_or(0) as u16;
            self.layer[p] = g.layer;
            self.mass[p] *= g.density_ratio;
            if self.inv_mass[p] != 0.0 {
                self.inv_mass[p] /= g.density_ratio;
            }
        }
        let s = &mut self.springs;
        for k in 0..s.len() {
            if let Some(g) = of[s.i[k] as usize].map(|g| &garments[g]) {
                s.k_stretch[k] *= g.stiffness;
                s.k_compress[k] *= g.stiffness;
                s.damping[k] *= g.stiffness;
                self.spring_scale[k] = g.stiffness;
            }
        }
        self.packed = self.springs.packed();
        Ok(())
    }

    /// The number of garments (at least 1).
    pub fn garments(&self) -> usize {
        self.garment
            .iter()
            .map(|&g| g as usize + 1)
            .max()
            .unwrap_or(1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::ClothParams;
    use tryon_core::mesh::{Face, PolyMesh, grid_xz};

    /// Two separate 3 x 3 sheets, the second 1 cm above the first.
    fn two_sheets() -> PolyMesh {
        let a = grid_xz(2, 2, 0.1, 0.1, 0.0);
        let b = grid_xz(2, 2, 0.1, 0.1, 0.01);
        let base = a.positions.len() as u32;
        let mut m = a.clone();
        m.positions.extend(&b.positions);
        m.faces.extend(b.faces.iter().map(|f| match f {
            Face::Tri(t) => Face::Tri(t.map(|v| v + base)),
            Face::Quad(q) => Face::Quad(q.map(|v| v + base)),
        }));
        m
    }

    #[test]
    fn each_garment_gets_its_layer_mass_and_stiffness() {
        let p = ClothParams::conservative();
        let mut m = ClothModel::build(&two_sheets(), &p, vec![]).unwrap();
        let (mass, ks) = (m.mass.clone(), m.springs.k_stretch.clone());
        let g = |r: Range<u32>, layer, density_ratio, stiffness| GarmentWear {
            particles: r,
            layer,
            density_ratio,
            stiffness,
        };
        m.wear(&[g(0..9, 0, 1.0, 1.0), g(9..18, 3, 2.0, 0.5)])
            .unwrap();
        assert_eq!(m.garments(), 2);
        assert_eq!(m.layer[..9], [0; 9]);
        assert_eq!(m.layer[9..], [3; 9]);
        for p in 0..18 {
            let want = if p < 9 { mass[p] } else { 2.0 * mass[p] };
            assert_eq!(m.mass[p], want);
            assert!((m.mass[p] * m.inv_mass[p] - 1.0).abs() < 1e-12);
        }
        for k in 0..m.springs.len() {
            let upper = m.springs.i[k] >= 9;
            let want = if upper { 0.5 * ks[k] } else { ks[k] };
            assert_eq!(m.springs.k_stretch[k], want);
            assert_eq!(m.spring_scale[k], if upper { 0.5 } else { 1.0 });
            let per_rest = m.packed[k].stretch_per_rest * m.springs.rest[k];
            assert!((per_rest - want).abs() < 1e-9 * want);
        }
    }

    #[test]
    fn garments_that_share_a_spring_or_overlap_are_refused() {
        let p = ClothParams::conservative();
        let mut m = ClothModel::build(&two_sheets(), &p, vec![]).unwrap();
        let g = |r: Range<u32>| GarmentWear {
            particles: r,
            layer: 0,
            density_ratio: 1.0,
            stiffness: 1.0,
        };
        assert!(matches!(
            m.wear(&[g(0..5), g(5..18)]),
            Err(WearError::Shared { .. })
        ));
        assert!(matches!(
            m.wear(&[g(0..10), g(9..18)]),
            Err(WearError::Range { .. })
        ));
        assert!(matches!(m.wear(&[g(0..19)]), Err(WearError::Range { .. })));
        let bad = GarmentWear {
            stiffness: Real::NAN,
            ..g(0..9)
        };
        assert!(matches!(m.wear(&[bad]), Err(WearError::Material { .. })));
    }
}
