//! A kimono in a scene (`[garment] kind = "kimono"`, issue 23 item 5): the kimono fitted to the
//! mannequin's measurements (P2's fit on the flat targets), put on that mannequin as the worn
//! targets were ([`super::wear_on`]: arms raised, inflated, tied), and the motion led in from the
//! pose it was put on in. The cord's and band head's rows stay tied to the body.

use crate::build::AssembleError;
use crate::kimono::{KimonoError, Targets, fit_kimono};
use crate::scene::KimonoSpec;
use crate::scene::{GarmentSection, Scene};
use mocap_retarget::LeadIn;
use std::sync::Mutex;
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

/// A kimono put on the mannequin.
#[derive(Clone)]
pub(crate) struct WornKimono {
    /// As worn, on the body in the pose it was put on in (arms raised).
    pub mesh: PolyMesh,
    /// The vertices the cord holds to the body.
    pub tied: Vec<u32>,
}

/// The kimonos put on in this process, by wearer and settings: putting one on takes about 40 s,
/// and a process may build the same scene more than once (a check, then a run; tests).
type Memo = Vec<(String, WornKimono)>;
static WORN: Mutex<Memo> = Mutex::new(Vec::new());
/// How many are kept (about 0.1 MB each).
const MEMO_LEN: usize = 8;

/// The kimono fitted to the mannequin of `m` and put on it (once per process for each wearer and
/// setting).
pub(crate) fn garment(
    m: &Measurements,
    k: &KimonoSpec,
    progress: crate::Progress,
) -> Result<WornKimono, AssembleError> {
    let key = format!("{m:?} {k:?}");
    // One at a time: a second scene of the same wearer waits for the first instead of repeating it.
    let mut memo = WORN.lock().unwrap_or_else(|e| e.into_inner());
    if let Some((_, w)) = memo.iter().find(|(name, _)| *name == key) {
        return Ok(w.clone());
    }
    let worn = put_on(m, k, progress)?;
    if memo.len() >= MEMO_LEN {
        memo.remove(0);
    }
    memo.push((key, worn.clone()));
    Ok(worn)
}

fn put_on(
    m: &Measurements,
    k: &KimonoSpec,
    progress: crate::Progress,
) -> Result<WornKimono, AssembleError> {
    let w = kimono::Wearer {
        height: m.height,
        bust: m.bust,
        waist: m.waist,
        hip: m.hip,
        yuki: k.yuki,
        sleeve_length: k.sleeve_length,
    };
    let fit = fit_kimono(&w, Targets::Flat)?;
    let settings = super::WearSettings {
        hold_frames: k.hold_frames,
        under_bust_tie: k.under_bust_tie,
        ..super::WearSettings::default()
    };
    let worn = super::wear_on(
        m,
        &w,
        &fit.positions,
        &fit.family.base,
        &settings,
        &mut |act, f, n| {
            if f == n || f % 15 == 0 {
                progress(&format!("kimono: putting it on, {act} {f}/{n}"));
            }
        },
    )?;
    let mesh = PolyMesh::from_triangles(worn.positions, &fit.family.base.triangles)
        .map_err(|e| KimonoError::Output(e.to_string()))?;
    Ok(WornKimono {
        mesh,
        tied: worn.tied,
    })
}

/// `motion` led in from the kimono's pose over `k.lead` seconds.
pub(crate) fn lead_in(
    skeleton: &Skeleton,
    k: &KimonoSpec,
    motion: Box<dyn MotionSource>,
) -> Box<dyn MotionSource> {
    Box::new(LeadIn {
        from: kimono::dress::dress_pose(skeleton),
        lead: k.lead,
        inner: motion,
    })
}
