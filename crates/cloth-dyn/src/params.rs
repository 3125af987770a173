//! Cloth parameters with sensible defaults and validation that names the bad value.

use tryon_core::math::{GRAVITY, Real, Vec3};

/// Physical and numerical parameters of a cloth. Stiffnesses are per spring (N/m, as in P1 eq. 1).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ClothParams {
    /// Mass per unit area (kg/m^2), lumped to the vertices by area.
    pub density: Real,
    /// Structural stiffness when an edge is longer than rest (N/m).
    pub k_stretch: Real,
    /// Structural stiffness when an edge is shorter than rest (N/m): small, so the coarse cloth can shrink.
    pub k_compress: Real,
    /// Shear spring stiffness (both ways, N/m).
    pub k_shear: Real,
    /// Bending spring stiffness (both ways, N/m).
    pub k_bend: Real,
    /// Viscous damping along every spring (N s/m).
    pub spring_damping: Real,
    /// Gravity acceleration (m/s^2).
    pub gravity: Vec3,
    /// Linear air drag per unit area relative to the wind (N s/m^3).
    pub air_drag: Real,
    /// Wind velocity (m/s).
    pub wind: Vec3,
    /// Absolute velocity damping (1/s): force = -c m v.
    pub velocity_damping: Real,
    /// Coulomb friction coefficient at body contacts.
    pub friction: Real,
    /// Largest substep (s). The solver may go smaller (stability bound, retries).
    pub max_substep: Real,
    /// Pick the substep from a Gershgorin bound of the stiffness so the integrator is stable.
    pub auto_substep: bool,
    /// Provot's strain limit: structural and shear edges are not allowed longer than this ratio of
    /// rest length after a substep (`None` disables it).
    pub max_strain: Option<Real>,
    /// Gauss-Seidel passes of the strain limit per substep.
    pub strain_iterations: u32,
    /// Bending limit: a bending spring (spanning two edges) may not get shorter than this ratio of
    /// its rest length, which bounds the fold angle at every vertex so soft cloth folds broadly instead
    /// of crumpling at the grid scale (`None` disables it). Structural edges may still shrink (P1).
    pub min_bend_ratio: Option<Real>,
    /// Long-range stretch constraints along straight lines of quad meshes (see `lines`).
    pub long_range: bool,
    /// Quality guard: a substep that leaves any structural edge longer than this ratio of rest (when
    /// none was before it) is retried at half the step (at most `STRETCH_HALVINGS` times, counted as retries); spends time
    /// only where the cloth moves fast, as at an impact. `None` disables it.
    pub stretch_guard: Option<Real>,
    /// Long-range tethers to contacts, pins and handles during the strain limit.
    pub tethers: bool,
    /// Over-relaxation of the strain limit's corrections (1 = plain Gauss-Seidel, < 2).
    pub strain_relaxation: Real,
    /// A particle faster than this (m/s) counts as exploding.
    pub max_speed: Real,
    /// How many times a failing substep may be halved before offending particles are rolled back.
    pub max_halvings: u32,
    /// Least particle mass as a fraction of the median particle mass (0: off). Meshes made for
    /// rendering have slivers whose tiny masses would force tiny substeps; the floor adds a little
    /// mass there (a negligible share of the total) and bounds the substep.
    pub mass_floor: Real,
    /// Rest lengths of stretch and shear springs as a fraction of the mesh's edge lengths (1: the
    /// mesh is the rest shape). Below 1 the garment is worn under a little tension, so that friction
    /// can hold it (a waistband that is exactly its modelled size grips nothing).
    pub rest_scale: Real,
    /// Bending rigidity (N m) of Bergou et al.'s quadratic bending model over the triangulated
    /// cloth (see [`crate::hinges`]); 0 leaves it out. It assumes a flat rest shape.
    pub bending_rigidity: Real,
}

impl Default for ClothParams {
    fn default() -> Self {
        ClothParams {
            density: 0.2,
            k_stretch: 50.0,
            k_compress: 5.0,
            k_shear: 5.0,
            k_bend: 0.5,
            spring_damping: 0.01,
            gravity: GRAVITY,
            air_drag: 0.05,
            wind: Vec3::zeros(),
            velocity_damping: 0.05,
            friction: 0.3,
            max_substep: 1.0 / 120.0,
            auto_substep: true,
            max_strain: Some(1.02),
            strain_iterations: 4,
            strain_relaxation: 1.0,
            tethers: true,
            long_range: false,
            stretch_guard: None,
            min_bend_ratio: Some(0.95),
            max_speed: 50.0,
            max_halvings: 16,
            mass_floor: 0.0,
            rest_scale: 1.0,
            bending_rigidity: 0.0,
        }
    }
}

/// A parameter outside its allowed range.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("cloth parameter `{name}` = {value} is invalid: expected {expected}")]
pub struct ParamError {
    pub name: &'static str,
    pub value: String,
    pub expected: &'static str,
}

impl ClothParams {
    /// A cloth without external forces, damping or strain limit (for conservation tests).
    pub fn conservative() -> Self {
        ClothParams {
            gravity: Vec3::zeros(),
            air_drag: 0.0,
            velocity_damping: 0.0,
            friction: 0.0,
            max_strain: None,
            min_bend_ratio: None,
            ..ClothParams::default()
        }
    }

    /// Checks every value; the error names the first bad one.
    pub fn validate(&self) -> Result<(), ParamError> {
        let nonneg = [
            ("k_stretch", self.k_stretch),
            ("k_compress", self.k_compress),
            ("k_shear", self.k_shear),
            ("k_bend", self.k_bend),
            ("spring_damping", self.spring_damping),
            ("air_drag", self.air_drag),
            ("velocity_damping", self.velocity_damping),
            ("friction", self.friction),
            ("bending_rigidity", self.bending_rigidity),
        ];
        for (name, value) in nonneg {
            if !(value.is_finite() && value >= 0.0) {
                return Err(ParamError {
                    name,
                    value: value.to_string(),
                    expected: "a finite number >= 0",
                });
            }
        }
        let positive = [
            ("density", self.density),
            ("max_substep", self.max_substep),
            ("max_speed", self.max_speed),
        ];
        for (name, value) in positive {
            if !(value.is_finite() && value > 0.0) {
                return Err(ParamError {
                    name,
                    value: value.to_string(),
                    expected: "a finite number > 0",
                });
            }
        }
        for (name, v) in [("gravity", self.gravity), ("wind", self.wind)] {
            if !tryon_core::math::is_finite(&v) {
                return Err(ParamError {
                    name,
                    value: format!("{v:?}"),
                    expected: "a finite vector",
                });
            }
        }
        if let Some(s) = self.max_strain
            && !(s.is_finite() && s >= 1.0)
        {
            return Err(ParamError {
                name: "max_strain",
                value: s.to_string(),
                expected: "a ratio >= 1",
            });
        }
        if let Some(r) = self.min_bend_ratio
            && !(r > 0.0 && r <= 1.0)
        {
            return Err(ParamError {
                name: "min_bend_ratio",
                value: r.to_string(),
                expected: "a ratio in (0, 1]",
            });
        }
        if let Some(r) = self.stretch_guard
            && !(r.is_finite() && r > 1.0)
        {
            return Err(ParamError {
                name: "stretch_guard",
                value: r.to_string(),
                expected: "a ratio > 1",
            });
        }
        if !(self.strain_relaxation > 0.0 && self.strain_relaxation < 2.0) {
            return Err(ParamError {
                name: "strain_relaxation",
                value: self.strain_relaxation.to_string(),
                expected: "a factor in (0, 2)",
            });
        }
        if !(self.mass_floor.is_finite() && (0.0..=1.0).contains(&self.mass_floor)) {
            return Err(ParamError {
                name: "mass_floor",
                value: self.mass_floor.to_string(),
                expected: "a fraction in 0..=1 of the median particle mass",
            });
        }
        if !(self.rest_scale.is_finite() && (0.5..=1.5).contains(&self.rest_scale)) {
            return Err(ParamError {
                name: "rest_scale",
                value: self.rest_scale.to_string(),
                expected: "a fraction in 0.5..=1.5 of the mesh's edge lengths",
            });
        }
        if self.max_halvings > 40 {
            return Err(ParamError {
                name: "max_halvings",
                value: self.max_halvings.to_string(),
                expected: "at most 40",
            });
        }
        Ok(())
    }
}
