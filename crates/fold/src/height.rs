//! How high a fold stands: the paper's open problem is that simulation may drift far from the
//! drawn shape, so the height is measured the same way on the drawn fold and after simulation.
//! Per ridge vertex (its ends aside), the surrounding surface is taken from the sixteen vertices
//! nearest it among those `reach` to `reach + 2` edges from the ridge (outside the smoothed
//! region): a quadratic height field over their mean tangent plane, fitted by least squares, so
//! that a curved garment (a tube skirt) is not mistaken for a fold; the vertex's height above it
//! along the plane's normal is its height (positive out along the normal), over a plane where the
//! quadric cannot be fitted. The fold's height is the median over its vertices.

use tryon_core::math::{Real, Vec3, vertex_normals};

/// Reference vertices per ridge vertex.
const NEAREST: usize = 16;
/// Rings of reference vertices, from `reach` out.
const RINGS: u32 = 3;
/// Largest misfit (root mean square) of the reference points to their quadric, as a share of the
/// drawn height, for a ridge vertex to be measured.
pub const UNSURE: Real = 0.25;
/// Farthest the reference points may lie from a ridge vertex (median), in drawn heights. Found
/// (session 49): the bust dress 2.8 on average (3.3 at most), the 5 cm test sheets under a 4 cm
/// fold 5.5 at most; two 2 cm folds on makehuman-dress-walk's dress 5.8 to 8.2, median 7.
pub const FAR: Real = 6.0;

/// The height over the surrounding surface (m; negative for a valley) of a fold drawn `drawn`
/// high, or `None` when the ridge has fewer than three vertices, no surface lies `reach` edges
/// from it, or that surface lies too far from it (module notes).
pub fn fold_height(
    x: &[Vec3],
    triangles: &[[u32; 3]],
    ridge: &[u32],
    reach: u32,
    drawn: Real,
) -> Option<Real> {
    let n = x.len();
    if ridge.len() < 3 || ridge.iter().any(|&v| v as usize >= n) {
        return None;
    }
    let mut ring = vec![Vec::new(); n];
    for t in triangles {
        if t.iter().any(|&v| v as usize >= n) {
            continue;
        }
        for k in 0..3 {
            ring[t[k] as usize].push(t[(k + 1) % 3]);
            ring[t[(k + 1) % 3] as usize].push(t[k]);
        }
    }
    // Graph distance from the ridge, out to the reference rings.
    let mut dist = vec![u32::MAX; n];
    let mut front: Vec<u32> = ridge.to_vec();
    let mut reference = Vec::new();
    for &v in ridge {
        dist[v as usize] = 0;
    }
    for d in 1..reach + RINGS {
        let mut next = Vec::new();
        for &v in &front {
            for &u in &ring[v as usize] {
                if dist[u as usize] == u32::MAX {
                    dist[u as usize] = d;
                    next.push(u);
                }
            }
        }
        if d >= reach {
            reference.extend_from_slice(&next);
        }
        front = next;
    }
    if reference.len() < 3 {
        return None;
    }
    let mut normals = Vec::new();
    vertex_normals(x, triangles, &mut normals);
    let unsure = UNSURE * drawn.abs();
    let far2 = (FAR * drawn).powi(2);
    let inner = &ridge[1..ridge.len() - 1];
    let mut heights: Vec<Real> = inner
        .iter()
        .filter_map(|&v| {
            let p = x[v as usize];
            let mut near: Vec<(Real, u32)> = reference
                .iter()
                .map(|&u| ((x[u as usize] - p).norm_squared(), u))
                .collect();
            near.sort_by(|a, b| a.0.total_cmp(&b.0));
            near.truncate(NEAREST);
            if !(near[near.len() / 2].0 <= far2) {
                return None;
            }
            let pts: Vec<Vec3> = near.iter().map(|&(_, u)| x[u as usize]).collect();
            let m = near.iter().map(|&(_, u)| normals[u as usize]).sum::<Vec3>();
            let (h, misfit) = height_over(&pts, &m.try_normalize(1e-12)?, &p)?;
            (h.is_finite() && misfit <= unsure).then_some(h)
        })
        .collect();
    if heights.is_empty() || 2 * heights.len() < inner.len() {
        return None;
    }
    heights.sort_by(Real::total_cmp);
    Some(heights[heights.len() / 2])
}

/// A fold's retention: its height now over the drawn height (both signed, so a valley that
/// stayed a valley counts positive).
pub fn fold_retention(height: Real, drawn: Real) -> Real {
    if drawn == 0.0 { 0.0 } else { height / drawn }
}

/// How far `p` lies above the quadratic height field fitted to `pts` over the plane with
/// normal `n` through their centroid (above the plane itself where too few points or too
/// degenerate a layout leave the quadric undetermined), and the points' root-mean-square
/// distance from that field along `n`.
fn height_over(pts: &[Vec3], n: &Vec3, p: &Vec3) -> Option<(Real, Real)> {
    let c = pts.iter().sum::<Vec3>() / pts.len() as Real;
    let t1 = n
        .cross(&Vec3::x())
        .try_normalize(1e-6)
        .or_else(|| n.cross(&Vec3::y()).try_normalize(1e-6))?;
    let t2 = n.cross(&t1);
    let local = |q: &Vec3| {
        let d = q - c;
        (d.dot(&t1), d.dot(&t2), d.dot(n))
    };
    let (pu, pv, pw) = local(p);
    if pts.len() >= 8 {
        let rows: Vec<Real> = pts
            .iter()
            .flat_map(|q| {
                let (u, v, _) = local(q);
                [1.0, u, v, u * u, u * v, v * v]
            })
            .collect();
        let a = nalgebra::DMatrix::from_row_slice(pts.len(), 6, &rows);
        let b = nalgebra::DVector::from_iterator(pts.len(), pts.iter().map(|q| local(q).2));
        let svd = a.clone().svd(true, true);
        let s = &svd.singular_values;
        let (hi, lo) = (s.max(), s.min());
        if hi > 0.0 && lo > 1e-6 * hi {
            let k = svd.solve(&b, 1e-12).ok()?;
            let misfit = ((&a * &k - &b).norm_squared() / pts.len() as Real).sqrt();
            let w = k[0] + k[1] * pu + k[2] * pv + k[3] * pu * pu + k[4] * pu * pv + k[5] * pv * pv;
            return Some((pw - w, misfit));
        }
    }
    let misfit = (pts.iter().map(|q| local(q).2.powi(2)).sum::<Real>() / pts.len() as Real).sqrt();
    Some((pw, misfit))
}
