//! A MakeHuman body: the base mesh's `body` group as render and collision mesh (helper groups kept,
//! morphed alongside, for garment bindings), skinned by the default rig's weights or by a rig such as
//! cmu_mb that takes its weights from default-rig bones (`weights_reference`), and morphed by the
//! measurement targets toward requested girths, then scaled to the requested height.

use crate::girth::girth_at;
use crate::skin::{SkinWeights, SkinnedBody};
use thiserror::Error;
use tryon_core::assets::{MakeHumanAssets, MhSkeleton};
use tryon_core::math::{Mat3, Real, Vec3};
use tryon_core::measure::Measurements;
use tryon_core::mesh::{Face, PolyMesh};
use tryon_core::pose::Skeleton;

/// Why a MakeHuman body cannot be built.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum MakeHumanError {
    #[error("base mesh has no `body` group")]
    NoBodyGroup,
    #[error("the `body` group uses vertex {vertex}, beyond its first {count} vertices")]
    BodyNotFirst { vertex: u32, count: usize },
    #[error(
        "bone `{bone}`: its {end} refers to vertex {vertex}, beyond the base's {count} vertices"
    )]
    JointVertex {
        bone: String,
        end: &'static str,
        vertex: u32,
        count: usize,
    },
    #[error("the default rig has no bone `{0}` (needed for landmarks)")]
    MissingBone(&'static str),
    #[error("morph target `{0}` is needed to reach the requested measurements but was not loaded")]
    MissingTarget(String),
    #[error(
        "measurement `{name}`: the body can be morphed to {reached:.3} m, not {requested:.3} m"
    )]
    Unreachable {
        name: &'static str,
        requested: Real,
        reached: Real,
    },
    #[error("gender {0} is outside 0 (female) ..= 1 (male)")]
    Gender(Real),
    #[error(transparent)]
    Measure(#[from] tryon_core::measure::MeasureError),
}

/// Girths (m) measured on a body with this module's own tape loops.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Girths {
    pub height: Real,
    pub bust: Real,
    pub waist: Real,
    pub hip: Real,
    /// Heights (m above the floor) where they were found.
    pub bust_y: Real,
    pub waist_y: Real,
    pub hip_y: Real,
}

/// A MakeHuman body in metres, standing on y = 0, facing +Z, in MakeHuman's A-pose.
/// The gender value that leaves the base mesh as it is (0 female ..= 1 male).
pub const NEUTRAL_GENDER: Real = 0.5;

#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct MakeHumanBody {
    /// Every base vertex (body and helpers), morphed.
    pub rest: Vec<Vec3>,
    /// The body group is vertices `0..body_vertices`.
    pub body_vertices: usize,
    /// Triangles of the body group.
    pub triangles: Vec<[u32; 3]>,
    /// The skinning skeleton: one joint per bone at its head; rest orientations are the world axes.
    pub skeleton: Skeleton,
    pub joint_rest: Vec<Vec3>,
    pub joint_tails: Vec<Vec3>,
    /// Skin weights of the body vertices (normalised, strongest four).
    pub skin: SkinWeights,
    /// Morph weights applied (target base name without -incr/-decr, weight in -1..=1).
    pub morphs: Vec<(String, Real)>,
    /// Uniform scale applied after morphing.
    pub scale: Real,
    pub girths: Girths,
}

/// The girth targets and the measurement each one drives.
const GIRTH_TARGETS: [&str; 3] = [
    "measure-bust-circ",
    "measure-waist-circ",
    "measure-hips-circ",
];

impl MakeHumanBody {
    /// Builds the body: `gender` 0 (female) ..= 1 (male), 0.5 the raw base, applied through the
    /// young-adult macro targets (ethnicities weighted equally, as MakeHuman's default); then, with
    /// `request`, morphs bust, waist and hip toward it and scales to its height.
    pub fn build(
        a: &MakeHumanAssets,
        gender: Real,
        request: Option<&Measurements>,
    ) -> Result<Self, MakeHumanError> {
        let faces = a.base.group_faces("body");
        if faces.is_empty() {
            return Err(MakeHumanError::NoBodyGroup);
        }
        let mut triangles = Vec::with_capacity(faces.len() * 2);
        let mut body_vertices = 0usize;
        for f in &faces {
            let face = a.base.faces[*f];
            for &v in face.vertices() {
                body_vertices = body_vertices.max(v as usize + 1);
            }
            match face {
                Face::Tri(t) => triangles.push(t),
                Face::Quad([p, q, r, s]) => {
                    triangles.push([p, q, r]);
                    triangles.push([p, r, s]);
                }
            }
        }
        let used: std::collections::HashSet<u32> = triangles.iter().flatten().copied().collect();
        if used.len() != body_vertices {
            let vertex = (0..body_vertices as u32)
                .find(|v| !used.contains(v))
                .unwrap_or(0);
            return Err(MakeHumanError::BodyNotFirst {
                vertex,
                count: used.len(),
            });
        }
        for b in &a.default_rig.bones {
            check_joint(b, &a.base.positions)?;
        }
        let mut rest = a.base.positions.clone();
        if !(0.0..=1.0).contains(&gender) {
            return Err(MakeHumanError::Gender(gender));
        }
        let (sex, w) = if gender < 0.5 {
            ("female", (0.5 - gender) * 2.0)
        } else {
            ("male", (gender - 0.5) * 2.0)
        };
        if w > 0.0 {
            for eth in ["african", "asian", "caucasian"] {
                let name = format!("{eth}-{sex}-young");
                let t = a
                    .macros
                    .iter()
                    .find(|t| t.name == name)
                    .ok_or(MakeHumanError::MissingTarget(name))?;
                t.apply(w / 3.0, &mut rest);
            }
        }
        let floor = rest[..body_vertices]
            .iter()
            .map(|p| p.y)
            .fold(Real::MAX, Real::min);
        for p in &mut rest {
            p.y -= floor;
        }
        let mut morphs = Vec::new();
        let mut scale = 1.0;
        if let Some(m) = request {
            m.validate()?;
            let h0 = height(&rest[..body_vertices]);
            scale = m.height / h0;
            let want = [m.bust / scale, m.waist / scale, m.hip / scale];
            let w = solve_girths(a, &rest, &triangles, body_vertices, want)?;
            for (k, name) in GIRTH_TARGETS.iter().enumerate() {
                apply_morph(a, name, w[k], &mut rest)?;
                morphs.push((name.to_string(), w[k]));
            }
            for p in &mut rest {
                *p *= scale;
            }
        }
        let girths = measure(&a.default_rig, &rest, &triangles, body_vertices)?;
        if let Some(m) = request {
            for (name, want, got) in [
                ("bust", m.bust, girths.bust),
                ("waist", m.waist, girths.waist),
                ("hip", m.hip, girths.hip),
            ] {
                if (got - want).abs() > 0.01 * want {
                    return Err(MakeHumanError::Unreachable {
                        name,
                        requested: want,
                        reached: got,
                    });
                }
            }
        }
        let rig = a.rig.as_ref().unwrap_or(&a.default_rig);
        for b in &rig.bones {
            check_joint(b, &rest)?;
        }
        let joint_rest: Vec<Vec3> = rig
            .bones
            .iter()
            .map(|b| MhSkeleton::joint_position(&b.head, &rest).unwrap_or_default())
            .collect();
        let joint_tails: Vec<Vec3> = rig
            .bones
            .iter()
            .map(|b| MhSkeleton::joint_position(&b.tail, &rest).unwrap_or_default())
            .collect();
        let skeleton = Skeleton {
            names: rig.bones.iter().map(|b| b.name.clone()).collect(),
            parents: rig.bones.iter().map(|b| b.parent).collect(),
            rest_offsets: rig
                .bones
                .iter()
                .enumerate()
                .map(|(i, b)| match b.parent {
                    Some(p) => joint_rest[i] - joint_rest[p],
                    None => joint_rest[i],
                })
                .collect(),
        };
        let skin = skin_weights(a, rig, body_vertices);
        Ok(MakeHumanBody {
            rest,
            body_vertices,
            triangles,
            skeleton,
            joint_rest,
            joint_tails,
            skin,
            morphs,
            scale,
            girths,
        })
    }

    /// The body group as a triangle mesh (rest pose).
    pub fn mesh(&self) -> PolyMesh {
        PolyMesh {
            positions: self.rest[..self.body_vertices].to_vec(),
            faces: self.triangles.iter().map(|t| Face::Tri(*t)).collect(),
        }
    }

    /// The body group skinned by linear blend skinning.
    pub fn skinned(&self) -> SkinnedBody {
        SkinnedBody::new(
            self.rest[..self.body_vertices].to_vec(),
            self.triangles.clone(),
            self.skeleton.clone(),
            self.joint_rest.clone(),
            self.skin.clone(),
        )
    }
}

fn check_joint(b: &tryon_core::assets::MhBone, pos: &[Vec3]) -> Result<(), MakeHumanError> {
    for (end, list) in [("head", &b.head), ("tail", &b.tail)] {
        if let Some(&v) = list.iter().find(|v| **v as usize >= pos.len()) {
            return Err(MakeHumanError::JointVertex {
                bone: b.name.clone(),
                end,
                vertex: v,
                count: pos.len(),
            });
        }
    }
    Ok(())
}

fn height(p: &[Vec3]) -> Real {
    let (lo, hi) = p
        .iter()
        .fold((Real::MAX, Real::MIN), |(l, h), q| (l.min(q.y), h.max(q.y)));
    hi - lo
}

/// Applies `name`-incr (w > 0) or `name`-decr (w < 0) with weight |w|.
fn apply_morph(
    a: &MakeHumanAssets,
    name: &str,
    w: Real,
    pos: &mut [Vec3],
) -> Result<(), MakeHumanError> {
    if w == 0.0 {
        return Ok(());
    }
    let full = format!("{name}-{}", if w > 0.0 { "incr" } else { "decr" });
    let t = a
        .targets
        .iter()
        .find(|t| t.name == full)
        .ok_or(MakeHumanError::MissingTarget(full))?;
    t.apply(w.abs(), pos);
    Ok(())
}

/// Morph weights (bust, waist, hip) that bring the girths to `want`, by Newton steps with a
/// finite-difference Jacobian, weights clamped to -1..=1.
fn solve_girths(
    a: &MakeHumanAssets,
    rest: &[Vec3],
    tris: &[[u32; 3]],
    nb: usize,
    want: [Real; 3],
) -> Result<[Real; 3], MakeHumanError> {
    let eval = |w: &[Real; 3]| -> Result<[Real; 3], MakeHumanError> {
        let mut p = rest.to_vec();
        for k in 0..3 {
            apply_morph(a, GIRTH_TARGETS[k], w[k], &mut p)?;
        }
        let g = measure(&a.default_rig, &p, tris, nb)?;
        Ok([g.bust, g.waist, g.hip])
    };
    let mut w = [0.0; 3];
    for _ in 0..4 {
        let g = eval(&w)?;
        let r: Vec<Real> = (0..3).map(|k| want[k] - g[k]).collect();
        if r.iter().all(|x| x.abs() < 1e-4) {
            break;
        }
        let mut jac = Mat3::zeros();
        for c in 0..3 {
            let h = if w[c] > 0.5 { -0.25 } else { 0.25 };
            let mut wp = w;
            wp[c] += h;
            let gp = eval(&wp)?;
            for row in 0..3 {
                jac[(row, c)] = (gp[row] - g[row]) / h;
            }
        }
        let rhs = Vec3::new(r[0], r[1], r[2]);
        let Some(step) = jac.lu().solve(&rhs) else {
            break;
        };
        for k in 0..3 {
            w[k] = (w[k] + step[k]).clamp(-1.0, 1.0);
        }
    }
    Ok(w)
}

/// Measures height, bust, waist and hip with this project's own loops: horizontal slices around
/// the spine's vertical axis; hip = fullest slice around the hip joints, waist = narrowest slice
/// between hips and chest, bust = fullest slice between waist and armpits.
pub fn measure(
    rig: &MhSkeleton,
    pos: &[Vec3],
    tris: &[[u32; 3]],
    nb: usize,
) -> Result<Girths, MakeHumanError> {
    let joint = |name: &'static str| -> Result<Vec3, MakeHumanError> {
        let b = rig.index(name).ok_or(MakeHumanError::MissingBone(name))?;
        Ok(MhSkeleton::joint_position(&rig.bones[b].head, pos).unwrap_or_default())
    };
    let hipj = joint("upperleg01.L")?.y;
    let shoulder = joint("upperarm01.L")?;
    let root = joint("root")?;
    let body = &pos[..nb];
    let (x, z) = (root.x, root.z);
    let girth = |y: Real| girth_at(body, tris, y, x, z).unwrap_or(0.0);
    let scan = |lo: Real, hi: Real, widest: bool| -> (Real, Real) {
        let n = 24;
        let mut best = (if widest { 0.0 } else { Real::MAX }, lo);
        for i in 0..=n {
            let y = lo + (hi - lo) * i as Real / n as Real;
            let g = girth(y);
            if g > 0.0 && ((widest && g > best.0) || (!widest && g < best.0)) {
                best = (g, y);
            }
        }
        best
    };
    let torso = shoulder.y - hipj;
    let (hip, hip_y) = scan(hipj - 0.2 * torso, hipj + 0.15 * torso, true);
    let (waist, waist_y) = scan(hip_y + 0.15 * torso, hipj + 0.75 * torso, false);
    let (bust, bust_y) = scan(waist_y + 0.1 * torso, shoulder.y - 0.2 * torso, true);
    Ok(Girths {
        height: height(body),
        bust,
        waist,
        hip,
        bust_y,
        waist_y,
        hip_y,
    })
}

/// Skin weights of the body vertices for `rig`. A rig bone takes the weights of the default bones
/// it lists in `weights_reference` (or else `reference`); any other default bone's weights go to the
/// rig bone that takes its nearest listed ancestor.
fn skin_weights(a: &MakeHumanAssets, rig: &MhSkeleton, nb: usize) -> SkinWeights {
    let d = &a.default_rig;
    let mut owner: Vec<Option<usize>> = vec![None; d.bones.len()];
    if a.rig.is_none() {
        owner = (0..d.bones.len()).map(Some).collect();
    } else {
        for (ri, rb) in rig.bones.iter().enumerate() {
            let list = if rb.weights_reference.is_empty() {
                &rb.reference
            } else {
                &rb.weights_reference
            };
            for name in list {
                if let Some(di) = d.index(name) {
                    owner[di].get_or_insert(ri);
                }
            }
        }
        for di in 0..d.bones.len() {
            let mut cur = Some(di);
            while let Some(c) = cur {
                if let Some(o) = owner[c] {
                    owner[di] = Some(o);
                    break;
                }
                cur = d.bones[c].parent;
            }
        }
    }
    let mut infl: Vec<Vec<(usize, Real)>> = vec![Vec::new(); nb];
    for (bone, list) in &a.weights.bones {
        let Some(o) = d.index(bone).and_then(|di| owner[di]) else {
            continue;
        };
        for &(v, w) in list {
            if let Some(slot) = infl.get_mut(v as usize) {
                slot.push((o, w));
            }
        }
    }
    SkinWeights::from_influences(&infl)
}
