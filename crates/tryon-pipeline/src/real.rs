//! Real assets in a scene: asset paths resolved beside the scene file or in the shared asset folder
//! (`TRYON_DATA`), the MakeHuman body with measurements filled from the raw base, .mhclo garments
//! fitted onto it, and BVH clips retargeted onto the body's skeleton.

use crate::scene::{BvhSpec, MakeHumanSpec, RigName, Scene};
use body_model::{MakeHumanBody, MakeHumanError, Press, SkinnedBody};
use mocap_retarget::clearance::{Envelope, SMOOTHING_S, keep_arms_clear};
use mocap_retarget::names::{Role, RoleMap};
use mocap_retarget::turns::limit_turns;
use mocap_retarget::{Placement, RetargetError, RetargetOptions, Retargeted, Rig, retarget};
use std::path::{Path, PathBuf};
use thiserror::Error;
use tryon_core::math::{Real, Vec3};
use tryon_core::measure::Measurements;
use tryon_core::pose::Skeleton;
use tryon_io::{MhRig, ReadError};

/// Why a scene's real assets could not be used.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum AssetError {
    #[error(
        "`{key}` = \"{value}\": no such file beside the scene, and the shared asset folder was not found (set {env})",
        env = tryon_io::DATA_ENV
    )]
    NoData { key: &'static str, value: String },
    #[error("`{key}` = \"{value}\": {path} does not exist", path = path.display())]
    Missing {
        key: &'static str,
        value: String,
        path: PathBuf,
    },
    #[error(transparent)]
    Read(#[from] ReadError),
    #[error("MakeHuman body: {0}")]
    Body(#[from] MakeHumanError),
    #[error("garment: {0}")]
    Fit(#[from] garment_fit::FitError),
    #[error("motion: {0}")]
    Retarget(#[from] RetargetError),
}

/// The folder a scene's relative paths start from, and the shared asset folder.
fn roots(scene: &Scene) -> (Option<PathBuf>, Option<PathBuf>) {
    let dir = scene
        .source
        .as_ref()
        .and_then(|p| p.parent())
        .map(Path::to_path_buf);
    let data = match &dir {
        Some(d) => tryon_io::data_root_from(d).or_else(tryon_io::data_root),
        None => tryon_io::data_root(),
    };
    (dir, data)
}

/// Resolves a scene's asset path: absolute, else beside the scene file, else in the asset folder.
pub fn resolve(scene: &Scene, key: &'static str, value: &str) -> Result<PathBuf, AssetError> {
    let p = Path::new(value);
    if p.is_absolute() {
        return if p.exists() {
            Ok(p.to_path_buf())
        } else {
            Err(AssetError::Missing {
                key,
                value: value.into(),
                path: p.to_path_buf(),
            })
        };
    }
    let (dir, data) = roots(scene);
    if let Some(d) = dir
        && d.join(p).exists()
    {
        return Ok(d.join(p));
    }
    let data = data.ok_or_else(|| AssetError::NoData {
        key,
        value: value.into(),
    })?;
    let full = data.join(p);
    if full.exists() {
        Ok(full)
    } else {
        Err(AssetError::Missing {
            key,
            value: value.into(),
            path: full,
        })
    }
}

/// The MakeHuman body of a scene; measurements not given keep the raw base's.
pub fn makehuman_body(scene: &Scene, b: &MakeHumanSpec) -> Result<MakeHumanBody, AssetError> {
    let data = resolve(scene, "body.kind", "makehuman/base.obj")?
        .parent()
        .and_then(Path::parent)
        .map(Path::to_path_buf)
        .unwrap_or_default();
    let rig = match b.rig {
        RigName::CmuMb => MhRig::CmuMb,
        RigName::Default => MhRig::Default,
    };
    let assets = tryon_io::load_makehuman(&data, rig)?;
    let gender = b.gender;
    let raw = MakeHumanBody::build(&assets, gender, None)?;
    if [b.height, b.bust, b.waist, b.hip]
        .iter()
        .all(Option::is_none)
    {
        return Ok(raw);
    }
    let d = Measurements::default();
    let g = raw.girths;
    let m = Measurements {
        height: b.height.unwrap_or(g.height),
        bust: b.bust.unwrap_or(g.bust),
        waist: b.waist.unwrap_or(g.waist),
        hip: b.hip.unwrap_or(g.hip),
        shoulder_width: d.shoulder_width,
        arm_length: d.arm_length,
        inseam: d.inseam,
    };
    Ok(MakeHumanBody::build(&assets, gender, Some(&m))?)
}

/// Reads a .mhclo garment and its OBJ.
pub fn mhclo(
    scene: &Scene,
    file: &str,
) -> Result<
    (
        tryon_core::assets::ClothBinding,
        tryon_core::assets::ObjMesh,
    ),
    AssetError,
> {
    let path = resolve(scene, "garment.file", file)?;
    let b = tryon_io::read_binding(&path)?;
    let obj = tryon_io::read_obj(&path.with_file_name(&b.obj_file))?;
    Ok((b, obj))
}

/// Reads a BVH clip and retargets it onto a skeleton at the scene's frame rate.
pub fn bvh_motion(
    scene: &Scene,
    m: &BvhSpec,
    skeleton: &Skeleton,
    joint_rest: &[Vec3],
    tips: Vec<Option<Vec3>>,
    skin: Option<BodySkin<'_>>,
) -> Result<Retargeted, AssetError> {
    let path = resolve(scene, "motion.file", &m.file)?;
    let mut clip = tryon_io::read_bvh(&path, m.unit)?;
    clip.frame_time /= m.speed;
    let rig = Rig::new(skeleton.clone(), joint_rest.to_vec(), tips);
    let opt = RetargetOptions {
        fps: scene.scene.fps,
        placement: Placement::StartAtTarget,
        start: m.start,
        duration: m.duration,
        ease_in: m.ease_in,
        skip_synthetic: true,
    };
    let mut motion = retarget(&clip, &rig, &opt)?;
    if let Some(b) = skin.filter(|_| m.arm_clearance > 0.0) {
        let envelope = Envelope::from_skin(b.points, b.joints, b.weights, skeleton, joint_rest);
        if let Some(e) = envelope {
            let window = (SMOOTHING_S * opt.fps).round() as usize;
            keep_arms_clear(
                &mut motion,
                joint_rest,
                &rig.tips,
                &e,
                m.arm_clearance,
                window,
            );
        }
    }
    if m.max_turn > 0.0 {
        let dt = motion.frame_time;
        limit_turns(
            &motion.skeleton,
            joint_rest,
            &mut motion.poses,
            dt,
            m.max_turn,
        );
    }
    Ok(motion)
}

/// A skinned body at rest: the vertices and their four strongest joints and weights.
#[derive(Clone, Copy, Debug)]
pub struct BodySkin<'a> {
    pub points: &'a [Vec3],
    pub joints: &'a [[u16; 4]],
    pub weights: &'a [[Real; 4]],
}

/// `body` with its parts pressed apart where they meet (`[effects] body_press`), keeping `gap`
/// between them: the parts are the limbs and the head, found by their joints' roles in the
/// skeleton (`Press::parts_from_roots` assigns the vertices). A skeleton whose roles are not
/// recognised is left as it is.
pub fn pressed(mut body: SkinnedBody, gap: Real) -> SkinnedBody {
    let Some(map) = RoleMap::detect(&body.skeleton) else {
        return body;
    };
    let roots = [
        Role::LUpperArm,
        Role::RUpperArm,
        Role::LThigh,
        Role::RThigh,
        Role::Neck,
    ]
    .map(|r| map.get(r));
    let parts = Press::parts_from_roots(
        &body.skeleton,
        &body.skin.joints,
        &body.skin.weights,
        &roots,
    );
    body.press = Some(Press { parts, gap });
    body
}
