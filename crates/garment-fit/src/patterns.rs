//! Coarse garment patterns from measurements. A garment is a tube of rings, each ring the torso's
//! elliptic section at that height (`Measurements::torso_keys`, the same the mannequin is built
//! from) grown outward by ease / 2 pi, so the ring's girth is the body's plus the ease. Below the hip
//! the tube keeps the hip section and flares toward the hem. The dress adds two shoulder straps that
//! arch from the front of the top ring over each shoulder to the back.

use thiserror::Error;
use tryon_core::math::{Real, Vec3};
use tryon_core::measure::{MeasureError, Measurements, profile, smoothstep};
use tryon_core::mesh::{Face, PolyMesh};
use tryon_core::stages::Collider;

/// A coarse garment: the cloth mesh in the body's rest pose, with a name for reports.
#[derive(Clone, Debug, PartialEq)]
pub struct Garment {
    pub name: String,
    pub mesh: PolyMesh,
}

/// Why a pattern cannot be made.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum PatternError {
    #[error(transparent)]
    Measurements(#[from] MeasureError),
    #[error("pattern parameter `{name}` = {value} is outside {min}..={max}")]
    BadParameter {
        name: &'static str,
        value: Real,
        min: Real,
        max: Real,
    },
    #[error("cannot cut the shirt from the body: {0}")]
    Cut(String),
}

pub(crate) fn check(
    name: &'static str,
    value: Real,
    min: Real,
    max: Real,
) -> Result<(), PatternError> {
    if value.is_finite() && value >= min && value <= max {
        Ok(())
    } else {
        Err(PatternError::BadParameter {
            name,
            value,
            min,
            max,
        })
    }
}

/// Settings of the dress.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DressParams {
    /// Ease (extra girth) at bust, waist and hip, m.
    pub ease: [Real; 3],
    /// Extra girth at the hem over the hip girth, m.
    pub flare: Real,
    /// Hem height above the knee, m (negative: below the knee).
    pub hem_above_knee: Real,
    /// Samples around a ring (a multiple of 4).
    pub columns: usize,
    /// Target spacing of rings, m.
    pub row_spacing: Real,
}

impl Default for DressParams {
    fn default() -> Self {
        DressParams {
            ease: [0.06, 0.10, 0.08],
            flare: 0.45,
            hem_above_knee: 0.02,
            columns: 24,
            row_spacing: 0.06,
        }
    }
}

/// Settings of the skirt.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SkirtParams {
    /// Ease at the waistband and the hip, m.
    pub ease: [Real; 2],
    pub flare: Real,
    pub hem_above_knee: Real,
    pub columns: usize,
    pub row_spacing: Real,
}

impl Default for SkirtParams {
    fn default() -> Self {
        SkirtParams {
            ease: [0.01, 0.07],
            flare: 0.40,
            hem_above_knee: 0.06,
            columns: 24,
            row_spacing: 0.055,
        }
    }
}

/// A tube of rings from `top` down to `hem` whose girth is the body's plus `ease(y)`.
struct Tube {
    positions: Vec<Vec3>,
    faces: Vec<Face>,
    rings: Vec<Vec<u32>>,
}

/// `dip` lowers the top ring at the sides (an armhole), by `dip * cos^2` of the angle from the side.
fn tube(
    m: &Measurements,
    top: Real,
    hem: Real,
    cols: usize,
    spacing: Real,
    dip: Real,
    ease: impl Fn(Real) -> Real,
) -> Tube {
    let keys = m.torso_keys(cols);
    let lm = m.landmarks();
    let hip = keys[1].1;
    let rows = ((top - hem) / spacing).round().max(1.0) as usize;
    let mut t = Tube {
        positions: Vec::new(),
        faces: Vec::new(),
        rings: Vec::new(),
    };
    for r in 0..=rows {
        let u = r as Real / rows as Real;
        let ring = (0..cols)
            .map(|k| {
                let th = std::f64::consts::TAU * k as Real / cols as Real;
                let y = top - dip * th.cos().powi(2) * (1.0 - u) + (hem - top) * u;
                let [a, b, c] = if y < lm.hip { hip } else { profile(&keys, y) };
                let grow = ease(y) / std::f64::consts::TAU;
                t.positions.push(Vec3::new(
                    (a + grow) * th.cos(),
                    y,
                    c + (b + grow) * th.sin(),
                ));
                (t.positions.len() - 1) as u32
            })
            .collect::<Vec<u32>>();
        t.rings.push(ring);
    }
    // Rings run counter-clockwise seen from above and descend: (upper k, lower k, lower k+1,
    // upper k+1) faces outward.
    for r in 0..rows {
        for k in 0..cols {
            let k1 = (k + 1) % cols;
            let (u, l) = (&t.rings[r], &t.rings[r + 1]);
            t.faces.push(Face::Quad([u[k], u[k1], l[k1], l[k]]));
        }
    }
    t
}

/// The girth the garment adds below the hip: `flare` reached at the hem.
fn flare_at(y: Real, hip: Real, hem: Real, flare: Real) -> Real {
    if y >= hip {
        0.0
    } else {
        flare * smoothstep((hip - y) / (hip - hem)).sqrt()
    }
}

/// A sleeveless one-piece dress from just above the bust to about the knee, held by two straps.
pub fn dress(m: &Measurements, p: &DressParams) -> Result<Garment, PatternError> {
    m.validate()?;
    for (name, v) in [
        ("ease.bust", p.ease[0]),
        ("ease.waist", p.ease[1]),
        ("ease.hip", p.ease[2]),
    ] {
        check(name, v, 0.0, 0.5)?;
    }
    check("flare", p.flare, 0.0, 2.0)?;
    check("hem_above_knee", p.hem_above_knee, -0.3, 0.3)?;
    check("columns", p.columns as Real, 16.0, 192.0)?;
    check("row_spacing", p.row_spacing, 0.005, 0.2)?;
    let cols = p.columns / 4 * 4;
    let lm = m.landmarks();
    let sc = m.scale();
    let top = lm.bust + 0.025 * sc;
    let hem = lm.knee + p.hem_above_knee;
    let ease = |y: Real| {
        let e = profile(
            &[
                (lm.hip, [p.ease[2]]),
                (lm.waist, [p.ease[1]]),
                (lm.bust, [p.ease[0]]),
            ],
            y,
        )[0];
        e + flare_at(y, lm.hip, hem, p.flare)
    };
    let mut t = tube(m, top, hem, cols, p.row_spacing, 0.05 * sc, ease);
    // Straps: one quad wide, at the columns nearest 52 and 67 degrees from the side, lying on the
    // body (a clearance above the torso's section in the strap's vertical plane) from the front
    // of the top ring over the shoulder to the mirrored columns at the back.
    let keys = m.torso_keys(cols);
    let deg = |d: Real| ((d / 360.0 * cols as Real).round() as usize) % cols;
    let strap_cols = [
        [deg(52.0), deg(67.0)],
        [deg(180.0 - 52.0), deg(180.0 - 67.0)],
    ];
    let top_ring = t.rings[0].clone();
    let mut inner: Vec<Vec<u32>> = Vec::new();
    for side in strap_cols {
        let c_of = |k: usize| side.iter().position(|&q| q == k).unwrap_or(0);
        let paths: Vec<Vec<Vec3>> = side
            .iter()
            .map(|&k| {
                let back = (cols - k) % cols;
                let (f, b) = (
                    t.positions[top_ring[k] as usize],
                    t.positions[top_ring[back] as usize],
                );
                // Straps meet the shoulder on its flat part beside the neck.
                let x_top = if c_of(k) == 0 { 0.095 } else { 0.07 } * sc * f.x.signum();
                strap_path(&keys, f, b, x_top, lm.neck - 0.012 * sc, 0.008 * sc)
            })
            .collect();
        let longest = paths.iter().map(|q| path_length(q)).fold(0.0, Real::max);
        let rows = (longest / p.row_spacing).round().max(2.0) as usize;
        let mut columns: Vec<Vec<u32>> = Vec::new();
        for (c, &k) in side.iter().enumerate() {
            let back = (cols - k) % cols;
            let pts = resample(&paths[c], rows);
            let mut col = vec![top_ring[k]];
            for q in &pts[1..rows] {
                t.positions.push(*q);
                col.push((t.positions.len() - 1) as u32);
            }
            col.push(top_ring[back]);
            columns.push(col);
        }
        for i in 0..rows {
            let (a, b) = (&columns[0], &columns[1]);
            push_quad(&mut t, [a[i], a[i + 1], b[i + 1], b[i]], lm.shoulder);
        }
        inner.push(columns[1].clone());
    }
    // Front and back panels between the straps' inner columns, up to a neckline: the neck passes
    // through the neck opening, so the straps cannot slide off the shoulders.
    let [left, right] = [&inner[0], &inner[1]];
    let n = left.len() - 1;
    let row_at = |col: &[u32], y: Real, from_back: bool| {
        (1..n)
            .map(|i| if from_back { n - i } else { i })
            .find(|&i| t.positions[col[i] as usize].y >= y)
            .map_or(1, |i| if from_back { n - i } else { i })
            .max(1)
    };
    let (kl, kr) = (deg(67.0), deg(180.0 - 67.0));
    let front_rows = row_at(left, top + 0.5 * (lm.neck - top), false);
    let back_rows = row_at(left, top + 0.75 * (lm.neck - top), true);
    let front_bottom: Vec<u32> = (kl..=kr).map(|k| top_ring[k]).collect();
    let back_bottom: Vec<u32> = (cols - kr..=cols - kl).map(|k| top_ring[k]).collect();
    let lf: Vec<u32> = left[..=front_rows].to_vec();
    let rf: Vec<u32> = right[..=front_rows].to_vec();
    let lb: Vec<u32> = left.iter().rev().take(back_rows + 1).copied().collect();
    let rb: Vec<u32> = right.iter().rev().take(back_rows + 1).copied().collect();
    panel(
        &mut t,
        &keys,
        &front_bottom,
        &lf,
        &rf,
        0.008 * sc,
        lm.shoulder,
    );
    panel(
        &mut t,
        &keys,
        &back_bottom,
        &rb,
        &lb,
        0.008 * sc,
        lm.shoulder,
    );
    Ok(Garment {
        name: "dress".into(),
        mesh: PolyMesh {
            positions: t.positions,
            faces: t.faces,
        },
    })
}

/// Adds quad `q`, flipped if needed so that it faces away from a point inside the torso (below
/// the quad's height, capped at the shoulder so that a strap on the shoulder faces up).
fn push_quad(t: &mut Tube, q: [u32; 4], shoulder: Real) {
    let x = q.map(|v| t.positions[v as usize]);
    let n = (x[2] - x[0]).cross(&(x[3] - x[1]));
    let mid = (x[0] + x[1] + x[2] + x[3]) / 4.0;
    let inside = Vec3::new(0.0, mid.y.min(shoulder) - 0.1, 0.0);
    t.faces.push(Face::Quad(if n.dot(&(mid - inside)) >= 0.0 {
        q
    } else {
        [q[3], q[2], q[1], q[0]]
    }));
}

/// Fills the patch bounded below by `bottom` (left to right), on the left and right by the columns
/// `left` and `right` (bottom to top, same length, starting at `bottom`'s ends), and on top by the
/// straight line between their last points: Coons interpolation, then pushed `clearance` outside
/// the torso's section wherever it fell inside.
fn panel(
    t: &mut Tube,
    keys: &[(Real, [Real; 3])],
    bottom: &[u32],
    left: &[u32],
    right: &[u32],
    clearance: Real,
    shoulder: Real,
) {
    let (cols, rows) = (bottom.len() - 1, left.len() - 1);
    let pos = t.positions.clone();
    let p = |v: u32| pos[v as usize];
    let (l1, r1) = (p(left[rows]), p(right[rows]));
    let (b0, b1) = (p(bottom[0]), p(bottom[cols]));
    let mut grid: Vec<Vec<u32>> = vec![bottom.to_vec()];
    for r in 1..=rows {
        let v = r as Real / rows as Real;
        let mut row = vec![left[r]];
        for c in 1..cols {
            let u = c as Real / cols as Real;
            let top = l1 + (r1 - l1) * u;
            let q = p(bottom[c]) * (1.0 - v) + top * v + p(left[r]) * (1.0 - u) + p(right[r]) * u
                - (b0 * ((1.0 - u) * (1.0 - v))
                    + b1 * (u * (1.0 - v))
                    + l1 * ((1.0 - u) * v)
                    + r1 * (u * v));
            let [a, b, zc] = profile(keys, q.y);
            let (a, b) = (a + clearance, b + clearance);
            let e = ((q.x / a).powi(2) + ((q.z - zc) / b).powi(2)).sqrt();
            let q = if e < 1.0 && e > 0.0 {
                Vec3::new(q.x / e, q.y, zc + (q.z - zc) / e)
            } else {
                q
            };
            t.positions.push(q);
            row.push((t.positions.len() - 1) as u32);
        }
        row.push(right[r]);
        grid.push(row);
    }
    for r in 0..rows {
        for c in 0..cols {
            let q = [
                grid[r][c],
                grid[r][c + 1],
                grid[r + 1][c + 1],
                grid[r + 1][c],
            ];
            push_quad(t, q, shoulder);
        }
    }
}

/// The strap's line from `front` up over the shoulder to `back`, in the vertical plane through
/// both: `clearance` outside the torso's elliptic section at every height.
fn strap_path(
    keys: &[(Real, [Real; 3])],
    front: Vec3,
    back: Vec3,
    x_top: Real,
    y_top: Real,
    clearance: Real,
) -> Vec<Vec3> {
    let x0 = 0.5 * (front.x + back.x);
    // The strap runs from its column on the top ring toward `x_top` by the height `y_top`.
    let x_at = |y: Real| x0 + (x_top - x0) * smoothstep((y - front.y) / (y_top - front.y));
    let mut up: Vec<Vec3> = vec![front];
    let mut down: Vec<Vec3> = vec![back];
    let mut y = front.y.min(back.y);
    let top = keys[keys.len() - 1].0;
    let mut x = x0;
    while y < top {
        let [a, b, c] = profile(keys, y + 0.002);
        let (a, b) = (a + clearance, b + clearance);
        let xn = x_at(y + 0.002);
        if xn.abs() >= a {
            break;
        }
        y += 0.002;
        x = xn;
        let dz = b * (1.0 - (x / a).powi(2)).sqrt();
        if y > front.y {
            up.push(Vec3::new(x, y, c + dz));
        }
        if y > back.y {
            down.push(Vec3::new(x, y, c - dz));
        }
    }
    // Over the top: a clearance above the last section reached.
    let apex = Vec3::new(
        x,
        y + clearance,
        0.5 * (up[up.len() - 1].z + down[down.len() - 1].z),
    );
    up.push(apex);
    up.extend(down.into_iter().rev());
    up
}

fn path_length(p: &[Vec3]) -> Real {
    p.windows(2).map(|w| (w[1] - w[0]).norm()).sum()
}

/// `rows + 1` points at equal arc length along the polyline `p` (ends included).
fn resample(p: &[Vec3], rows: usize) -> Vec<Vec3> {
    let total = path_length(p);
    let mut out = vec![p[0]];
    let (mut seg, mut acc) = (0usize, 0.0);
    for i in 1..rows {
        let want = total * i as Real / rows as Real;
        while seg + 1 < p.len() - 1 && acc + (p[seg + 1] - p[seg]).norm() < want {
            acc += (p[seg + 1] - p[seg]).norm();
            seg += 1;
        }
        let l = (p[seg + 1] - p[seg]).norm().max(1e-12);
        out.push(p[seg] + (p[seg + 1] - p[seg]) * ((want - acc) / l).clamp(0.0, 1.0));
    }
    out.push(p[p.len() - 1]);
    out
}

/// A flared skirt from just above the waist to above the knee.
pub fn skirt(m: &Measurements, p: &SkirtParams) -> Result<Garment, PatternError> {
    m.validate()?;
    check("ease.waist", p.ease[0], 0.0, 0.5)?;
    check("ease.hip", p.ease[1], 0.0, 0.5)?;
    check("flare", p.flare, 0.0, 2.0)?;
    check("hem_above_knee", p.hem_above_knee, -0.3, 0.3)?;
    check("columns", p.columns as Real, 16.0, 192.0)?;
    check("row_spacing", p.row_spacing, 0.005, 0.2)?;
    let lm = m.landmarks();
    let top = lm.waist + 0.02 * m.scale();
    let hem = lm.knee + p.hem_above_knee;
    let ease = |y: Real| {
        profile(&[(lm.hip, [p.ease[1]]), (lm.waist, [p.ease[0]])], y)[0]
            + flare_at(y, lm.hip, hem, p.flare)
    };
    let t = tube(m, top, hem, p.columns / 4 * 4, p.row_spacing, 0.0, ease);
    Ok(Garment {
        name: "skirt".into(),
        mesh: PolyMesh {
            positions: t.positions,
            faces: t.faces,
        },
    })
}

/// Moves every vertex the collider finds inside the body (or closer than its skin) onto the
/// surface plus the skin; returns how many moved.
pub fn place_outside(mesh: &mut PolyMesh, collider: &mut dyn Collider) -> usize {
    let mut contacts = Vec::new();
    collider.resolve(&mut mesh.positions, &mut contacts);
    contacts.len()
}

#[cfg(test)]
mod tests {
    use super::*;
    use tryon_core::topology::Topology;

    #[test]
    fn dress_has_p1_size_and_is_a_valid_open_manifold() {
        let g = dress(&Measurements::default(), &DressParams::default()).unwrap();
        let n = g.mesh.positions.len();
        assert!((300..=400).contains(&n), "{n} particles");
        g.mesh.validate().unwrap();
        let topo = Topology::build(&g.mesh).unwrap();
        assert!(!topo.boundary_edges.is_empty());
    }

    #[test]
    fn ring_girths_are_body_plus_ease() {
        let m = Measurements::default();
        let p = SkirtParams {
            columns: 96,
            ..SkirtParams::default()
        };
        let g = skirt(&m, &p).unwrap();
        let lm = m.landmarks();
        let keys = m.torso_keys(96);
        let mut checked = 0;
        // Rings are consecutive runs of 96 vertices; every ring above the hip (no flare there).
        for ring in g.mesh.positions.chunks(96).filter(|r| r[0].y >= lm.hip) {
            let y = ring[0].y;
            let per: Real = (0..96).map(|k| (ring[k] - ring[(k + 1) % 96]).norm()).sum();
            let [a, b, _] = profile(&keys, y);
            let body: Real = (0..96)
                .map(|k| {
                    let (t0, t1) = (
                        std::f64::consts::TAU * k as Real / 96.0,
                        std::f64::consts::TAU * (k + 1) as Real / 96.0,
                    );
                    (a * (t1.cos() - t0.cos())).hypot(b * (t1.sin() - t0.sin()))
                })
                .sum();
            let ease = profile(&[(lm.hip, [p.ease[1]]), (lm.waist, [p.ease[0]])], y)[0];
            assert!(
                (per / (body + ease) - 1.0).abs() < 0.005,
                "y {y}: {per} vs {body} + {ease}"
            );
            checked += 1;
        }
        assert!(checked >= 2);
    }

    #[test]
    fn skirt_and_bad_parameters() {
        let g = skirt(&Measurements::default(), &SkirtParams::default()).unwrap();
        g.mesh.validate().unwrap();
        assert!(g.mesh.positions.len() >= 150);
        let e = dress(
            &Measurements::default(),
            &DressParams {
                flare: -1.0,
                ..DressParams::default()
            },
        )
        .unwrap_err();
        assert!(e.to_string().contains("flare"), "{e}");
    }
}
