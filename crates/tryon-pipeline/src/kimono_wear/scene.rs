//! A kimono in a scene (`[garment] kind = "kimono"`, issue 23 item 5): the kimono fitted to the
//! mannequin's measurements on the built-in worn targets, in the pose it was put on in (arms
//! raised), and the motion led in from that pose.

use crate::build::AssembleError;
use crate::kimono::{Targets, fit_kimono};
use crate::scene::KimonoSpec;
use crate::scene::{GarmentSection, Scene};
use mocap_retarget::LeadIn;
use tryon_core::math::Real;
use tryon_core::measure::Measurements;
use tryon_core::mesh::PolyMesh;
use tryon_core::pose::Skeleton;
use tryon_core::stages::MotionSource;

/// The scene's first kimono, if it wears one.
pub(crate) fn spec(scene: &Scene) -> Option<&KimonoSpec> {
    scene.garments().into_iter().find_map(|w| match w.garment {
        GarmentSection::Kimono(k) => Some(k),
        _ => None,
    })
}

/// The kimono fitted to the mannequin of `m`, as worn (arms raised).
pub(crate) fn garment(m: &Measurements, k: &KimonoSpec) -> Result<PolyMesh, AssembleError> {
    let w = kimono::Wearer {
        height: m.height,
        bust: m.bust,
        waist: m.waist,
        hip: m.hip,
        yuki: k.yuki,
        sleeve_length: k.sleeve_length,
    };
    let fit = fit_kimono(&w, Targets::Worn(&super::embedded::shape_text))?;
    // The blend follows the dimensions, not the wearer's height: its shoulders land where the
    // blended targets' are (8 cm low on a 1.62 m wearer). Set them on this wearer's shoulders, as
    // the dressing laid every target (its fold line just over them).
    let st =
        super::stand::stand(&w).map_err(|e| crate::kimono::KimonoError::Output(e.to_string()))?;
    let shoulders = |p: &[tryon_core::math::Vec3]| {
        p.iter()
            .filter(|v| (0.1..0.3).contains(&v.x.abs()))
            .map(|v| v.y)
            .fold(Real::NEG_INFINITY, Real::max)
    };
    let base_top = shoulders(&fit.family.base.positions);
    let base_stand = super::stand::stand(&kimono::family::BASE)
        .map_err(|e| crate::kimono::KimonoError::Output(e.to_string()))?;
    let lift = (st.top + base_top - base_stand.top) - shoulders(&fit.positions);
    let positions = fit
        .positions
        .iter()
        .map(|p| p + tryon_core::math::Vec3::new(0.0, lift, 0.0))
        .collect();
    let mesh = PolyMesh::from_triangles(positions, &fit.family.base.triangles);
    Ok(mesh.map_err(|e| AssembleError::Kimono(crate::kimono::KimonoError::Output(e.to_string())))?)
}

/// `motion` led in from the kimono's pose over `k.lead` seconds.
pub(crate) fn lead_in(
    skeleton: &Skeleton,
    k: &KimonoSpec,
    motion: Box<dyn MotionSource>,
) -> Box<dyn MotionSource> {
    Box::new(LeadIn {
        from: super::stand::dress_pose(skeleton),
        lead: k.lead,
        inner: motion,
    })
}
