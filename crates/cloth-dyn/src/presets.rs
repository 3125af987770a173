//! Material presets: the parameters a garment, a flat sheet or a modelled (MakeHuman) garment
//! starts from, scaled to the mesh's resolution. Scenes override single values on top of these.

use crate::params::ClothParams;
use tryon_core::math::Real;
use tryon_core::mesh::PolyMesh;

/// Distance a garment keeps from the body unless a scene says otherwise (m).
pub const THICKNESS: Real = 0.004;

/// Area density of a garment unless a scene says otherwise (kg/m^2).
pub const DENSITY: Real = 0.2;

/// What a scene's cloth meets unless the scene says otherwise: gravity on, still air, friction
/// 0.5 at body contacts, velocity damping 0.2 /s.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Environment {
    pub gravity: bool,
    /// Air drag coefficient (N s/m^3 per unit area).
    pub air_drag: Real,
    /// Wind velocity (m/s).
    pub wind: [Real; 3],
    /// Coulomb friction coefficient at body contacts.
    pub friction: Real,
    /// Velocity damping (1/s).
    pub velocity_damping: Real,
}

impl Default for Environment {
    fn default() -> Self {
        Environment {
            gravity: true,
            air_drag: 0.0,
            wind: [0.0; 3],
            friction: 0.5,
            velocity_damping: 0.2,
        }
    }
}

/// Default material for a garment whose edges average `h` metres (P1's springs with flexion springs
/// and the bending limit): the springs scale with particle mass, so an explicit integrator's
/// stable step does not depend on the resolution; inextensibility comes from the strain limit.
pub fn garment(h: Real, density: Real) -> ClothParams {
    let base = ClothParams::default();
    let m = density * h * h;
    let k = 2500.0 * m;
    ClothParams {
        density,
        k_stretch: k,
        k_compress: 0.1 * k,
        k_shear: 0.1 * k,
        k_bend: 0.02 * k,
        spring_damping: 0.02 * m * 120.0,
        max_strain: Some(1.03),
        strain_iterations: 6,
        strain_relaxation: 1.8,
        min_bend_ratio: Some(0.97),
        stretch_guard: Some(1.1),
        ..base
    }
}

/// A garment modelled for rendering (MakeHuman's): `p` with a mass floor for its slivers (0.5 mm
/// edges beside 1.5 cm ones) and rest lengths at 95%, so that it is worn under a little tension
/// and friction holds its waistbands.
pub fn modelled(p: ClothParams) -> ClothParams {
    ClothParams {
        mass_floor: 0.3,
        rest_scale: 0.95,
        ..p
    }
}

/// The drape fixture's material at `n` particles per side of a 1 m sheet: [`sheet`] at its edge.
pub fn drape(n: usize) -> ClothParams {
    sheet(1.0 / (n.max(2) - 1) as Real, ClothParams::default().density)
}

/// The material of a flat sheet of edge `h` (m) and `density` (kg/m^2). An explicit integrator at
/// a fixed substep can only hold springs whose stiffness scales with particle mass (k / m bounds
/// the stable step), so the springs are soft: inextensibility comes from Provot's strain limit (at
/// rest length, with long-range lines); the compress/stretch ratio of P1 is kept. Bending is
/// Bergou et al.'s quadratic model (the sheet is flat at rest), with a rigidity of 2e-6 N m at
/// N = 64 scaled by the fourth power of the edge length, for the same reason as the springs: its
/// squared frequency grows as rigidity / (density edge^4), so it stays a fixed share (about 40%)
/// of the springs' bound, which keeps 3 substeps per frame at N = 64. (Flexion springs with the
/// bending limit crumpled less but pumped energy into the sheet until it slid off the sphere; see
/// docs/decisions, *vbd strain limit*.)
pub fn sheet(h: Real, density: Real) -> ClothParams {
    let base = ClothParams::default();
    let m = density * h * h;
    let k = 2500.0 * m;
    ClothParams {
        density,
        k_stretch: k,
        k_compress: 0.1 * k,
        k_shear: 0.1 * k,
        k_bend: 0.0,
        bending_rigidity: 2e-6 * (63.0 * h).powi(4),
        spring_damping: 0.02 * m * 120.0,
        // The limit at rest length with long-range lines and 8 passes keeps the whole run, impact
        // included, within 3% (1.02 with 6 passes and no lines: about 1.10, for 2/3 of the time).
        max_strain: Some(1.0),
        strain_iterations: 8,
        long_range: true,
        // Plain Gauss-Seidel: over-relaxing a limit at rest length overshoots every correction
        // into compression (mean edge 0.91 of rest at 1.8), and converges no faster here.
        strain_relaxation: 1.0,
        min_bend_ratio: None,
        stretch_guard: Some(1.1),
        ..base
    }
}

/// Mean edge length of a mesh's triangulated view (quads count their diagonals).
pub fn mean_edge(mesh: &PolyMesh) -> Real {
    let (tris, _) = mesh.triangulate();
    let mut sum = 0.0;
    for t in &tris {
        for e in 0..3 {
            sum += (mesh.positions[t[e] as usize] - mesh.positions[t[(e + 1) % 3] as usize]).norm();
        }
    }
    sum / (3 * tris.len()).max(1) as Real
}

#[cfg(test)]
mod tests {
    use super::*;
    use tryon_core::mesh::grid_xz;

    #[test]
    fn presets_scale_the_springs_with_particle_mass() {
        // Half the edge: a quarter of the mass per particle, so a quarter of the stiffness.
        let (a, b) = (garment(0.02, 0.2), garment(0.01, 0.2));
        assert!((a.k_stretch / b.k_stretch - 4.0).abs() < 1e-12);
        assert!((a.spring_damping / b.spring_damping - 4.0).abs() < 1e-12);
        let (a, b) = (sheet(0.02, 0.2), sheet(0.01, 0.2));
        assert!((a.bending_rigidity / b.bending_rigidity - 16.0).abs() < 1e-9);
        assert!(a.validate().is_ok() && garment(0.02, 0.2).validate().is_ok());
    }

    #[test]
    fn the_drape_material_is_the_sheet_at_its_spacing() {
        assert_eq!(drape(33), sheet(1.0 / 32.0, ClothParams::default().density));
        let m = modelled(garment(0.01, 0.2));
        assert_eq!((m.mass_floor, m.rest_scale), (0.3, 0.95));
        assert_eq!(m.k_stretch, garment(0.01, 0.2).k_stretch);
    }

    #[test]
    fn mean_edge_counts_the_diagonals_of_quads() {
        // A unit square split once: edges 1, 1, sqrt(2) per triangle.
        let m = grid_xz(1, 1, 1.0, 1.0, 0.0);
        let want = (2.0 + (2.0 as Real).sqrt()) / 3.0;
        assert!((mean_edge(&m) - want).abs() < 1e-12);
    }
}
