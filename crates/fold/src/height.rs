//! How high a fold stands: the paper's open problem is that simulation may drift far from the
//! drawn shape, so the height is measured the same way on the drawn fold and after simulation.
//! Per ridge vertex (its ends aside), the surrounding surface is the six vertices nearest it among
//! those `reach` edges from the ridge (outside the smoothed region): their centroid and mean
//! normal give a local plane, and the vertex's signed distance from it is its height (positive
//! out along the normal). The fold's height is the median over its vertices.

use tryon_core::math::{Real, Vec3, vertex_normals};

/// Reference vertices per ridge vertex.
const NEAREST: usize = 6;

/// The fold's height over the surrounding surface (m; negative for a valley), or `None` when
/// the ridge has fewer than three vertices or no surface lies `reach` edges from it.
pub fn fold_height(x: &[Vec3], triangles: &[[u32; 3]], ridge: &[u32], reach: u32) -> Option<Real> {
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
    // Graph distance from the ridge, out to `reach`.
    let mut dist = vec![u32::MAX; n];
    let mut front: Vec<u32> = ridge.to_vec();
    for &v in ridge {
        dist[v as usize] = 0;
    }
    for d in 1..=reach {
        let mut next = Vec::new();
        for &v in &front {
            for &u in &ring[v as usize] {
                if dist[u as usize] == u32::MAX {
                    dist[u as usize] = d;
                    next.push(u);
                }
            }
        }
        front = next;
    }
    if front.is_empty() {
        return None;
    }
    let mut normals = Vec::new();
    vertex_normals(x, triangles, &mut normals);
    let mut heights: Vec<Real> = ridge[1..ridge.len() - 1]
        .iter()
        .filter_map(|&v| {
            let p = x[v as usize];
            let mut near: Vec<(Real, u32)> = front
                .iter()
                .map(|&u| ((x[u as usize] - p).norm_squared(), u))
                .collect();
            near.sort_by(|a, b| a.0.total_cmp(&b.0));
            near.truncate(NEAREST);
            let k = near.len() as Real;
            let c = near.iter().map(|&(_, u)| x[u as usize]).sum::<Vec3>() / k;
            let m = near.iter().map(|&(_, u)| normals[u as usize]).sum::<Vec3>();
            let m = m.try_normalize(1e-12)?;
            let h = (p - c).dot(&m);
            h.is_finite().then_some(h)
        })
        .collect();
    if heights.is_empty() {
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
