//! Small garment pieces that are not sewn to the rest (a pocket or a patch modelled as its own
//! piece, as MakeHuman garments often are) would fall off a simulated garment. Each vertex of such a
//! piece is attached to the nearest triangle of another piece: it keeps its barycentric place and
//! its distance along the triangle's normal, and is set there after every cloth step. Where the
//! cloth must not pass through itself, the piece is instead set whole and rigid where those
//! anchors best say (a least-squares rotation and shift): set vertex by vertex on a bending
//! host, the casual suit's waist patch of millimetre triangles folded into itself (227 crossing
//! pairs within it in the first frame).

use crate::find_root as find;
use tryon_core::math::{Mat3, Real, Vec3, closest_point_on_triangle};
use tryon_core::mesh::PolyMesh;

/// One attached vertex.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Attachment {
    pub vertex: u32,
    pub triangle: [u32; 3],
    pub bary: [Real; 3],
    /// Signed distance along the triangle's unit normal.
    pub offset: Real,
    /// The piece the vertex belongs to (attachments of one piece are consecutive), and where the
    /// vertex was when attached.
    pub piece: u32,
    pub rest: Vec3,
}

/// Connected components of a mesh: the component id of every vertex, ids dense from 0.
pub fn components(mesh: &PolyMesh) -> Vec<usize> {
    let n = mesh.positions.len();
    let mut parent: Vec<usize> = (0..n).collect();
    for f in &mesh.faces {
        let v = f.vertices();
        for w in &v[1..] {
            let (a, b) = (
                find(&mut parent, v[0] as usize),
                find(&mut parent, *w as usize),
            );
            parent[a] = b;
        }
    }
    let mut id = vec![usize::MAX; n];
    let mut next = 0;
    (0..n)
        .map(|v| {
            let r = find(&mut parent, v);
            if id[r] == usize::MAX {
                id[r] = next;
                next += 1;
            }
            id[r]
        })
        .collect()
}

/// Attachments for every piece with fewer than `max_share` of the vertices, to the nearest
/// triangle of the other pieces within `max_gap` (m). Pieces farther away stay free.
pub fn attach_small_pieces(mesh: &PolyMesh, max_share: Real, max_gap: Real) -> Vec<Attachment> {
    let comp = components(mesh);
    let pieces = comp.iter().copied().max().map_or(0, |m| m + 1);
    if pieces < 2 {
        return Vec::new();
    }
    let mut size = vec![0usize; pieces];
    for c in &comp {
        size[*c] += 1;
    }
    let (tris, _) = mesh.triangulate();
    let p = &mesh.positions;
    let mut out = Vec::new();
    for piece in (0..pieces).filter(|c| (size[*c] as Real) < max_share * p.len() as Real) {
        // The whole piece rides on one host piece: the one nearest to most of its vertices.
        let verts: Vec<usize> = (0..p.len()).filter(|v| comp[*v] == piece).collect();
        let nearest = |v: usize, host: Option<usize>| -> Option<(Real, Attachment, usize)> {
            let mut best: Option<(Real, Attachment, usize)> = None;
            for t in tris.iter().filter(|t| {
                let c = comp[t[0] as usize];
                c != piece && host.is_none_or(|h| h == c)
            }) {
                let [a, b, c] = t.map(|i| p[i as usize]);
                let (q, bary) = closest_point_on_triangle(&p[v], &a, &b, &c);
                let d = (p[v] - q).norm();
                if best.as_ref().is_none_or(|(bd, _, _)| d < *bd) {
                    let n = (b - a)
                        .cross(&(c - a))
                        .try_normalize(1e-15)
                        .unwrap_or(Vec3::y());
                    let att = Attachment {
                        vertex: v as u32,
                        triangle: *t,
                        bary,
                        offset: (p[v] - q).dot(&n),
                        piece: piece as u32,
                        rest: p[v],
                    };
                    best = Some((d, att, comp[t[0] as usize]));
                }
            }
            best
        };
        let mut votes = vec![0usize; pieces];
        for &v in &verts {
            if let Some((_, _, h)) = nearest(v, None) {
                votes[h] += 1;
            }
        }
        let host = (0..pieces).max_by_key(|h| votes[*h]);
        let mut found = Vec::new();
        for &v in &verts {
            match nearest(v, host) {
                Some((d, a, _)) if d <= max_gap => found.push(a),
                _ => {
                    found.clear();
                    break;
                }
            }
        }
        out.extend(found);
    }
    out
}

/// Where attachment `a`'s anchor on its triangle is at `x`, and the triangle's velocity there.
fn anchor(a: &Attachment, x: &[Vec3], v: &[Vec3]) -> (Vec3, Vec3) {
    let [i, j, k] = a.triangle.map(|t| t as usize);
    let [wa, wb, wc] = a.bary;
    let n = (x[j] - x[i])
        .cross(&(x[k] - x[i]))
        .try_normalize(1e-15)
        .unwrap_or(Vec3::y());
    let p = x[i] * wa + x[j] * wb + x[k] * wc + n * a.offset;
    (p, v[i] * wa + v[j] * wb + v[k] * wc)
}

/// The rotation taking the points `from` (about their mean) nearest, in least squares, to the
/// points `to` (about theirs): Kabsch's, a proper rotation. The identity where it is undecided.
fn best_rotation(from: &[Vec3], to: &[Vec3]) -> Mat3 {
    let n = from.len().max(1) as Real;
    let (cf, ct) = (from.iter().sum::<Vec3>() / n, to.iter().sum::<Vec3>() / n);
    let mut h = Mat3::zeros();
    for (f, t) in from.iter().zip(to) {
        h += (f - cf) * (t - ct).transpose();
    }
    let svd = h.svd(true, true);
    let (Some(u), Some(vt)) = (svd.u, svd.v_t) else {
        return Mat3::identity();
    };
    let mut d = Mat3::identity();
    if (vt.transpose() * u.transpose()).determinant() < 0.0 {
        d[(2, 2)] = -1.0;
    }
    let r = vt.transpose() * d * u.transpose();
    if r.iter().all(|c| c.is_finite()) {
        r
    } else {
        Mat3::identity()
    }
}

/// How an attached piece rides on its host.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Riding {
    /// Each vertex at its own anchor: exact on the host, but a patch folds with it.
    PerVertex,
    /// The piece whole, where its anchors best say: it keeps its shape (for cloth that must not
    /// pass through itself).
    Whole,
}

/// Sets every attached piece where its anchors say (see [`Riding`] and the module's text), and
/// gives each vertex its anchor's velocity.
pub fn apply_attachments(att: &[Attachment], riding: Riding, x: &mut [Vec3], v: &mut [Vec3]) {
    let (mut rest, mut now) = (Vec::new(), Vec::new());
    for group in att.chunk_by(|a, b| a.piece == b.piece) {
        rest.clear();
        now.clear();
        for a in group {
            let (p, vel) = anchor(a, x, v);
            rest.push(a.rest);
            now.push(p);
            v[a.vertex as usize] = vel;
        }
        if riding == Riding::PerVertex {
            for (a, p) in group.iter().zip(&now) {
                x[a.vertex as usize] = *p;
            }
            continue;
        }
        let r = best_rotation(&rest, &now);
        let n = group.len() as Real;
        let (cr, cn) = (rest.iter().sum::<Vec3>() / n, now.iter().sum::<Vec3>() / n);
        for (a, p) in group.iter().zip(&rest) {
            x[a.vertex as usize] = cn + r * (p - cr);
        }
    }
}
#[cfg(test)]
mod tests {
    use super::*;
    use tryon_core::mesh::{Face, grid_xz};

    #[test]
    fn a_patch_above_a_sheet_rides_with_it() {
        let mut mesh = grid_xz(4, 4, 1.0, 1.0, 0.0);
        let base = mesh.positions.len() as u32;
        for (x, z) in [(0.1, 0.1), (0.3, 0.1), (0.3, 0.3), (0.1, 0.3)] {
            mesh.positions.push(Vec3::new(x, 0.01, z));
        }
        mesh.faces
            .push(Face::Quad([base, base + 3, base + 2, base + 1]));
        assert_eq!(components(&mesh).iter().max(), Some(&1));
        let att = attach_small_pieces(&mesh, 0.3, 0.05);
        assert_eq!(att.len(), 4);
        let mut x = mesh.positions.clone();
        let mut v = vec![Vec3::zeros(); x.len()];
        for p in x.iter_mut().take(base as usize) {
            p.y += 1.0;
        }
        apply_attachments(&att, Riding::PerVertex, &mut x, &mut v);
        for k in 0..4 {
            let moved = x[base as usize + k] - mesh.positions[base as usize + k];
            assert!(
                (moved - Vec3::new(0.0, 1.0, 0.0)).norm() < 1e-12,
                "{moved:?}"
            );
        }
        // A patch too far away stays free.
        assert!(attach_small_pieces(&mesh, 0.3, 0.001).is_empty());
    }

    #[test]
    fn a_patch_on_a_bending_sheet_keeps_its_shape_and_turns_with_it() {
        let mut mesh = grid_xz(8, 8, 1.0, 1.0, 0.0);
        let base = mesh.positions.len() as u32;
        let patch = grid_xz(2, 2, 0.2, 0.2, 0.01);
        mesh.positions.extend_from_slice(&patch.positions);
        mesh.faces.extend(patch.faces.iter().map(|f| match f {
            Face::Tri(t) => Face::Tri(t.map(|v| v + base)),
            Face::Quad(q) => Face::Quad(q.map(|v| v + base)),
        }));
        let att = attach_small_pieces(&mesh, 0.3, 0.05);
        assert_eq!(att.len(), patch.positions.len());
        // The sheet bends into a trough and turns a quarter about z.
        let turn = tryon_core::math::UnitQuat::from_axis_angle(&Vec3::z_axis(), 1.0);
        let mut x: Vec<Vec3> = mesh.positions.clone();
        for p in x.iter_mut().take(base as usize) {
            *p = turn * Vec3::new(p.x, p.y + 2.0 * p.x * p.x, p.z);
        }
        let mut v = vec![Vec3::zeros(); x.len()];
        apply_attachments(&att, Riding::Whole, &mut x, &mut v);
        let m = patch.positions.len();
        for i in 0..m {
            for j in 0..m {
                let (a, b) = (base as usize + i, base as usize + j);
                let rest = (mesh.positions[a] - mesh.positions[b]).norm();
                assert!(((x[a] - x[b]).norm() - rest).abs() < 1e-12, "{i} {j}");
            }
        }
        // Over the sheet's turned side: a rigid patch over a trough stands on the trough's
        // rims, so its centre (over the trough's floor) rises, never sinks into the sheet.
        let up = turn * Vec3::y();
        let h = x[base as usize + 4].dot(&up);
        assert!((0.01..0.03).contains(&h), "{h}");
    }
}
