//! BVH motion reader: the HIERARCHY (joints, offsets, any channel order, position channels on any
//! joint, end sites) and the MOTION block, with LF or CRLF line ends. Units are converted to metres
//! at load, either as the caller says or guessed from the figure's size ([`guess_unit`]).

use crate::read::{At, ReadError, read_text, short};
use std::path::Path;
use tryon_core::assets::MotionClip;
use tryon_core::math::{Real, UnitQuat, Vec3};
use tryon_core::pose::{Pose, Skeleton};

/// Most joints a BVH may declare.
pub const MAX_BVH_JOINTS: usize = 4096;
/// Most channel values (frames x channels) a BVH may hold.
pub const MAX_BVH_VALUES: usize = 100_000_000;
/// The longest frame time read, s (0.1 frames a second).
pub const MAX_BVH_FRAME_TIME: Real = 10.0;
/// The largest channel value read, in the file's units or degrees: a rotation of 2,700 turns
/// or a translation of a kilometre in millimetres is not motion capture.
pub const MAX_BVH_CHANNEL: Real = 1e6;

/// Known units (metres per file unit), with names for reports.
pub const KNOWN_UNITS: [(Real, &str); 6] = [
    (1.0, "metres"),
    (0.1, "decimetres"),
    (0.01, "centimetres"),
    (0.001, "millimetres"),
    (0.0254, "inches"),
    (0.056444, "CMU units (0.056444 m)"),
];

#[derive(Clone, Copy, Debug, PartialEq)]
enum Channel {
    Pos(usize),
    Rot(usize),
}

/// A BVH file as written, before unit conversion.
#[derive(Clone, Debug, Default)]
pub struct BvhFile {
    pub skeleton: Skeleton,
    pub end_sites: Vec<(usize, Vec3)>,
    /// Channel names of each joint, as written.
    pub channels: Vec<Vec<String>>,
    pub frame_time: Real,
    pub frames: Vec<Pose>,
    /// Joints other than the root that carry position channels: their first-frame values are added
    /// to the rest offset, as Blender reads them (a pose has no per-joint translations).
    pub translated_joints: Vec<usize>,
}

/// Reads a BVH clip; `unit` is metres per file unit, or `None` to guess it from the figure's size.
pub fn read_bvh(path: &Path, unit: Option<Real>) -> Result<MotionClip, ReadError> {
    let f = parse_bvh(&read_text(path)?, path)?;
    let unit = unit.unwrap_or_else(|| guess_unit(&f.skeleton, &f.end_sites).0);
    Ok(f.into_clip(unit))
}

impl BvhFile {
    /// The clip with lengths multiplied by `unit` (metres per file unit).
    pub fn into_clip(self, unit: Real) -> MotionClip {
        let mut skeleton = self.skeleton;
        for o in &mut skeleton.rest_offsets {
            *o *= unit;
        }
        let frames = self
            .frames
            .into_iter()
            .map(|mut p| {
                p.root_translation *= unit;
                p
            })
            .collect();
        MotionClip {
            skeleton,
            end_sites: self
                .end_sites
                .into_iter()
                .map(|(j, o)| (j, o * unit))
                .collect(),
            frame_time: self.frame_time,
            frames,
            unit,
        }
    }
}

/// Rest-pose joint and end-site positions (all rotations zero, root at its offset).
pub fn rest_points(s: &Skeleton, end_sites: &[(usize, Vec3)]) -> Vec<Vec3> {
    let mut pos: Vec<Vec3> = Vec::with_capacity(s.parents.len());
    for j in 0..s.parents.len() {
        let base = s.parents[j].map_or(Vec3::zeros(), |p| pos[p]);
        pos.push(base + s.rest_offsets[j]);
    }
    let ends: Vec<Vec3> = end_sites.iter().map(|(j, o)| pos[*j] + o).collect();
    pos.extend(ends);
    pos
}

/// Guesses metres per unit: the known unit that makes the rest figure's largest extent closest to
/// 1.7 m (in ratio). Returns the unit and its name.
pub fn guess_unit(s: &Skeleton, end_sites: &[(usize, Vec3)]) -> (Real, &'static str) {
    let pts = rest_points(s, end_sites);
    let (mut lo, mut hi) = (Vec3::repeat(Real::MAX), Vec3::repeat(Real::MIN));
    for p in &pts {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    let extent = (hi - lo).max();
    if !(extent > 0.0) {
        return (1.0, "metres");
    }
    KNOWN_UNITS
        .iter()
        .copied()
        .min_by(|a, b| {
            let da = (extent * a.0 / 1.7).ln().abs();
            let db = (extent * b.0 / 1.7).ln().abs();
            da.total_cmp(&db)
        })
        .unwrap_or((1.0, "metres"))
}

/// Whitespace tokens with their line numbers.
struct Tokens<'a> {
    toks: Vec<(&'a str, usize)>,
    i: usize,
    file: &'a Path,
}

impl<'a> Tokens<'a> {
    fn new(text: &'a str, file: &'a Path) -> Self {
        let toks = text
            .lines()
            .enumerate()
            .flat_map(|(l, s)| s.split_whitespace().map(move |t| (t, l + 1)))
            .collect();
        Tokens { toks, i: 0, file }
    }
    fn at(&self) -> At<'a> {
        let line = self
            .toks
            .get(self.i)
            .or(self.toks.last())
            .map_or(1, |t| t.1);
        At {
            file: self.file,
            line,
        }
    }
    fn peek(&self) -> Option<&'a str> {
        self.toks.get(self.i).map(|t| t.0)
    }
    fn next(&mut self, what: &str) -> Result<&'a str, ReadError> {
        let t = self.peek().ok_or_else(|| {
            self.at()
                .err(format!("expected {what}, found the end of the file"))
        })?;
        self.i += 1;
        Ok(t)
    }
    fn expect(&mut self, word: &str) -> Result<(), ReadError> {
        let at = self.at();
        let t = self.next(&format!("`{word}`"))?;
        if t.eq_ignore_ascii_case(word) {
            Ok(())
        } else {
            Err(at.err(format!("expected `{word}`, found `{t}`")))
        }
    }
    fn real(&mut self, what: &str) -> Result<Real, ReadError> {
        let at = self.at();
        let t = self.next(what)?;
        at.real(Some(t), what)
    }
    fn vec3(&mut self, what: &str) -> Result<Vec3, ReadError> {
        Ok(Vec3::new(
            self.real(what)?,
            self.real(what)?,
            self.real(what)?,
        ))
    }
}

/// Parses BVH text; `file` names the source in errors.
pub fn parse_bvh(text: &str, file: &Path) -> Result<BvhFile, ReadError> {
    let mut t = Tokens::new(text, file);
    t.expect("HIERARCHY")?;
    let at = t.at();
    let root = t.next("`ROOT`")?;
    if !root.eq_ignore_ascii_case("ROOT") {
        return Err(at.err(format!("expected `ROOT`, found `{root}`")));
    }
    let mut f = BvhFile::default();
    let mut layout: Vec<(usize, Channel)> = Vec::new();
    joint(&mut t, &mut f, &mut layout, None)?;
    t.expect("MOTION")?;
    t.expect("Frames:")?;
    let at = t.at();
    let n = t.next("the frame count")?;
    let frames: usize = n
        .parse()
        .map_err(|_| at.err(format!("expected the frame count, found `{n}`")))?;
    if frames.saturating_mul(layout.len().max(1)) > MAX_BVH_VALUES {
        return Err(at.limit("frames x channels", MAX_BVH_VALUES));
    }
    t.expect("Frame")?;
    t.expect("Time:")?;
    let at = t.at();
    f.frame_time = t.real("the frame time")?;
    if !(f.frame_time > 0.0 && f.frame_time <= MAX_BVH_FRAME_TIME) {
        return Err(at.err(format!(
            "the frame time must be positive and at most {MAX_BVH_FRAME_TIME} s, found {}",
            short(f.frame_time)
        )));
    }
    let joints = f.skeleton.parents.len();
    let mut translations: Vec<Option<Vec3>> = vec![None; joints];
    for k in 0..frames {
        let mut pose = Pose::rest(joints);
        pose.time = k as Real * f.frame_time;
        let mut pos = vec![Vec3::zeros(); joints];
        for &(j, ch) in &layout {
            let at = t.at();
            let what = format!("channel value {} of frame {}", ch_name(ch), k + 1);
            let v = t.real(&what)?;
            if v.abs() > MAX_BVH_CHANNEL {
                return Err(at.err(format!(
                    "{what}: {} is beyond the {MAX_BVH_CHANNEL:e} a channel may hold",
                    short(v)
                )));
            }
            match ch {
                Channel::Pos(a) => pos[j][a] = v,
                Channel::Rot(a) => {
                    let q = UnitQuat::from_scaled_axis(Vec3::ith(a, v.to_radians()));
                    pose.local_rotations[j] *= q;
                }
            }
        }
        pose.root_translation = pos[0];
        for &j in &f.translated_joints {
            translations[j].get_or_insert(pos[j]);
        }
        f.frames.push(pose);
    }
    if let Some(extra) = t.peek() {
        return Err(t.at().err(format!(
            "more values than {frames} frames of {} channels: `{extra}`",
            layout.len()
        )));
    }
    for &j in &f.translated_joints {
        if let Some(p) = translations[j] {
            f.skeleton.rest_offsets[j] += p;
        }
    }
    Ok(f)
}

fn ch_name(c: Channel) -> &'static str {
    match c {
        Channel::Pos(a) => ["Xposition", "Yposition", "Zposition"][a],
        Channel::Rot(a) => ["Xrotation", "Yrotation", "Zrotation"][a],
    }
}

/// Parses one joint block (after its ROOT/JOINT keyword) and its children.
fn joint(
    t: &mut Tokens,
    f: &mut BvhFile,
    layout: &mut Vec<(usize, Channel)>,
    parent: Option<usize>,
) -> Result<(), ReadError> {
    let at = t.at();
    let name = t.next("a joint name")?.to_string();
    if f.skeleton.names.len() >= MAX_BVH_JOINTS {
        return Err(at.limit("joint count", MAX_BVH_JOINTS));
    }
    if f.skeleton.names.contains(&name) {
        return Err(at.err(format!("joint `{name}` is declared twice")));
    }
    t.expect("{")?;
    t.expect("OFFSET")?;
    let offset = t.vec3("an OFFSET coordinate")?;
    let j = f.skeleton.names.len();
    f.skeleton.names.push(name);
    f.skeleton.parents.push(parent);
    f.skeleton.rest_offsets.push(offset);
    t.expect("CHANNELS")?;
    let at = t.at();
    let n = t.next("the channel count")?;
    let count: usize = n
        .parse()
        .ok()
        .filter(|c| *c <= 6)
        .ok_or_else(|| at.err(format!("expected a channel count 0..=6, found `{n}`")))?;
    let mut names = Vec::with_capacity(count);
    for _ in 0..count {
        let at = t.at();
        let c = t.next("a channel name")?;
        let ch = match c.to_ascii_lowercase().as_str() {
            "xposition" => Channel::Pos(0),
            "yposition" => Channel::Pos(1),
            "zposition" => Channel::Pos(2),
            "xrotation" => Channel::Rot(0),
            "yrotation" => Channel::Rot(1),
            "zrotation" => Channel::Rot(2),
            _ => {
                return Err(at.err(format!(
                    "unknown channel `{c}` (expected X/Y/Z followed by position or rotation)"
                )));
            }
        };
        if matches!(ch, Channel::Pos(_)) && parent.is_some() && !f.translated_joints.contains(&j) {
            f.translated_joints.push(j);
        }
        layout.push((j, ch));
        names.push(c.to_string());
    }
    f.channels.push(names);
    loop {
        let at = t.at();
        let k = t.next("`JOINT`, `End Site` or `}`")?;
        match k {
            "}" => return Ok(()),
            _ if k.eq_ignore_ascii_case("JOINT") => joint(t, f, layout, Some(j))?,
            _ if k.eq_ignore_ascii_case("End") => {
                t.expect("Site")?;
                t.expect("{")?;
                t.expect("OFFSET")?;
                let o = t.vec3("an End Site OFFSET coordinate")?;
                t.expect("}")?;
                f.end_sites.push((j, o));
            }
            _ => return Err(at.err(format!("expected `JOINT`, `End Site` or `}}`, found `{k}`"))),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SMALL: &str = "HIERARCHY\r\nROOT Hips\r\n{\r\n OFFSET 0 0 0\r\n CHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation\r\n JOINT Leg\r\n {\r\n  OFFSET 0 -10 0\r\n  CHANNELS 3 Xrotation Zrotation Yrotation\r\n  End Site\r\n  {\r\n   OFFSET 0 -10 0\r\n  }\r\n }\r\n}\r\nMOTION\r\nFrames: 2\r\nFrame Time: 0.0083333\r\n1 20 3 0 0 0 90 0 0\r\n1 20 3 90 0 0 0 0 0\r\n";

    fn parse(s: &str) -> Result<BvhFile, ReadError> {
        parse_bvh(s, Path::new("t.bvh"))
    }

    #[test]
    fn reads_crlf_hierarchy_motion_and_channel_order() {
        let f = parse(SMALL).unwrap();
        assert_eq!(f.skeleton.names, ["Hips", "Leg"]);
        assert_eq!(f.skeleton.parents, [None, Some(0)]);
        assert_eq!(f.frames.len(), 2);
        assert_eq!(f.frames[0].root_translation, Vec3::new(1.0, 20.0, 3.0));
        // Frame 1: Leg rotates 90 degrees about X: its child offset (0,-10,0) turns to (0,0,-10).
        let q = f.frames[0].local_rotations[1];
        assert!((q * Vec3::new(0.0, -10.0, 0.0) - Vec3::new(0.0, 0.0, -10.0)).norm() < 1e-9);
        // Frame 2: Hips rotates 90 degrees about Z.
        let q = f.frames[1].local_rotations[0];
        assert!((q * Vec3::x() - Vec3::y()).norm() < 1e-9);
        assert_eq!(f.end_sites, vec![(1, Vec3::new(0.0, -10.0, 0.0))]);
    }

    #[test]
    fn channel_order_is_intrinsic_in_file_order() {
        let text = SMALL.replace("0 0 0 90 0 0\r\n1 20 3 90", "0 0 0 90 30 0\r\n1 20 3 90");
        let f = parse(&text).unwrap();
        let r = |a: Vec3, d: Real| UnitQuat::from_scaled_axis(a * d.to_radians());
        let want = r(Vec3::x(), 90.0) * r(Vec3::z(), 30.0);
        assert!(f.frames[0].local_rotations[1].angle_to(&want) < 1e-9);
    }

    #[test]
    fn unit_guess_picks_a_plausible_unit() {
        let f = parse(SMALL).unwrap();
        // A 20-unit figure: decimetres (2 m) beat CMU units (1.13 m).
        assert_eq!(guess_unit(&f.skeleton, &f.end_sites).0, 0.1);
    }

    #[test]
    fn malformed_files_name_the_line() {
        for (text, line, needle) in [
            (
                SMALL.replace("Frames: 2", "Frames: 3"),
                20,
                "end of the file",
            ),
            (SMALL.replace("Frames: 2", "Frames: 1"), 20, "more values"),
            (
                SMALL.replace(
                    "Zrotation Yrotation Xrotation",
                    "Zrotation Yrotation Wrotation",
                ),
                5,
                "unknown channel",
            ),
            (
                SMALL.replace("OFFSET 0 -10 0\r\n  CHANNELS", "OFFSET 0 x 0\r\n  CHANNELS"),
                8,
                "OFFSET",
            ),
            (
                SMALL.replace("Frame Time: 0.0083333", "Frame Time: 0"),
                18,
                "positive",
            ),
            (
                SMALL.replace("Frame Time: 0.0083333", "Frame Time: 1e300"),
                18,
                "at most 10 s",
            ),
            (
                SMALL.replace("90 0 0\r\n1 20", "9e999 0 0\r\n1 20"),
                19,
                "finite",
            ),
            (
                SMALL.replace("90 0 0\r\n1 20", "1e308 0 0\r\n1 20"),
                19,
                "beyond the 1e6",
            ),
            (
                SMALL.replace("\r\n1 20 3 90", "\r\n1e300 20 3 90"),
                20,
                "channel value Xposition of frame 2",
            ),
            (SMALL.replace("JOINT Leg", "JOINT Hips"), 6, "twice"),
            (SMALL.replace("MOTION", "MOTON"), 16, "MOTION"),
            ("".to_string(), 1, "HIERARCHY"),
        ] {
            let e = parse(&text).unwrap_err();
            assert_eq!(e.line(), Some(line), "{e}");
            assert!(e.to_string().contains(needle), "{e}");
        }
    }
}
