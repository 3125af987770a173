//! P2's print correction: after the shape changes, the bolt UVs are moved so the fabric's print
//! keeps its scale and aspect on the new shape.
//!
//! 1. For each dimension's edge set, the UVs of its vertices move about the set's centre (per part:
//!    a set along a seam has UVs in both parts) in proportion to the change of its 3D length;
//!    where sets share vertices they are placed together by least squares.
//! 2. The vertices not yet moved are corrected ring by ring outward from the moved ones, each
//!    minimising eq. (2), `w_s E_s + w_r E_r + w_m E_m` over its UV p', against its moved
//!    neighbours a:
//!    - E_s, length: `sum_a ((|p' - p'_a| - l_a) / l_a)^2`, l_a the UV distance before times the
//!      change of the 3D distance between the two vertices;
//!    - E_r, rotation: `sum_a ((p' - p'_a) . perp(e_a) / l_a)^2`, e_a the unit UV direction from a
//!      before;
//!    - E_m, movement with the neighbours: `|p' - p - m|^2 / l^2`, m the neighbours' mean move, l
//!      the mean l_a;
//!
//!    with P2's weights w_s = 2.8, w_r = 1, w_m = 0.5, by Gauss-Newton from p + m.
//!
//! UVs are the bolt's coordinates in metres, so "scale kept" means a UV length equals the 3D
//! length of the cloth it covers.

use crate::mesh::KimonoMesh;
use nalgebra::{Matrix2, Vector2};
use thiserror::Error;
use tryon_core::math::{Real, Vec3};

/// Why the print could not be corrected or measured: a shape or UV set handed in does not belong
/// to the mesh.
#[derive(Debug, Error, PartialEq)]
#[non_exhaustive]
pub enum PrintError {
    #[error("{what} has {found} entries, the kimono mesh has {expected}")]
    Count {
        what: &'static str,
        found: usize,
        expected: usize,
    },
    #[error("{what}, entry {index}: not finite")]
    NonFinite { what: &'static str, index: usize },
}

fn check<T>(
    what: &'static str,
    found: &[T],
    expected: usize,
    finite: impl Fn(&T) -> bool,
) -> Result<(), PrintError> {
    if found.len() != expected {
        return Err(PrintError::Count {
            what,
            found: found.len(),
            expected,
        });
    }
    match found.iter().position(|x| !finite(x)) {
        Some(index) => Err(PrintError::NonFinite { what, index }),
        None => Ok(()),
    }
}

fn check_points(what: &'static str, found: &[Vec3], expected: usize) -> Result<(), PrintError> {
    check(what, found, expected, |p| p.iter().all(|c| c.is_finite()))
}

fn check_uvs(uvs: &[[Real; 2]], expected: usize) -> Result<(), PrintError> {
    check("the UVs", uvs, expected, |u| {
        u.iter().all(|c| c.is_finite())
    })
}

/// The weights of eq. (2).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PrintParams {
    pub w_s: Real,
    pub w_r: Real,
    pub w_m: Real,
    /// Gauss-Newton iterations per vertex.
    pub iterations: usize,
    /// Sweeps of eq. (2) over every corrected vertex against all its neighbours, after spreading.
    pub sweeps: usize,
}

impl Default for PrintParams {
    /// P2's weights.
    fn default() -> Self {
        PrintParams {
            w_s: 2.8,
            w_r: 1.0,
            w_m: 0.5,
            iterations: 8,
            sweeps: 20,
        }
    }
}

/// Neighbours of each UV vertex along the UV triangles' edges.
fn uv_rings(mesh: &KimonoMesh) -> Vec<Vec<u32>> {
    let mut ring = vec![Vec::new(); mesh.uvs.len()];
    for t in &mesh.uv_triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            if !ring[a as usize].contains(&b) {
                ring[a as usize].push(b);
                ring[b as usize].push(a);
            }
        }
    }
    ring
}

/// The UVs of `mesh` corrected for its shape changing from `before` to `after` (each one position
/// per vertex of `mesh`, finite).
pub fn correct_print(
    mesh: &KimonoMesh,
    before: &[Vec3],
    after: &[Vec3],
    p: &PrintParams,
) -> Result<Vec<[Real; 2]>, PrintError> {
    check_points("the shape before", before, mesh.positions.len())?;
    check_points("the shape after", after, mesh.positions.len())?;
    let uv0: Vec<Vector2<Real>> = mesh.uvs.iter().map(|u| Vector2::new(u[0], u[1])).collect();
    let mut uv = uv0.clone();
    let mut moved = vec![false; uv.len()];
    seed(mesh, before, after, &uv0, &mut uv, &mut moved);
    let ring = uv_rings(mesh);
    let x = |i: usize, pos: &[Vec3]| pos[mesh.uv_vertex[i] as usize];
    let neighbour = |q: usize, a: usize, uv: &[Vector2<Real>]| {
        let (d0, d1) = (
            (x(q, before) - x(a, before)).norm(),
            (x(q, after) - x(a, after)).norm(),
        );
        let e = uv0[q] - uv0[a];
        let scale = if d0 > 0.0 { d1 / d0 } else { 1.0 };
        Neighbour {
            at: uv[a],
            moved: uv[a] - uv0[a],
            length: e.norm() * scale,
            perp: Vector2::new(-e.y, e.x) / e.norm().max(1e-12),
        }
    };
    let seeded = moved.clone();
    let mut front: Vec<usize> = (0..uv.len()).filter(|&i| moved[i]).collect();
    loop {
        let mut next: Vec<usize> = front
            .iter()
            .flat_map(|&i| ring[i].iter().map(|&j| j as usize))
            .filter(|&j| !moved[j])
            .collect();
        next.sort_unstable();
        next.dedup();
        if next.is_empty() {
            break;
        }
        let solved: Vec<Vector2<Real>> = next
            .iter()
            .map(|&q| {
                let nb: Vec<Neighbour> = ring[q]
                    .iter()
                    .map(|&a| a as usize)
                    .filter(|&a| moved[a])
                    .map(|a| neighbour(q, a, &uv))
                    .collect();
                minimise(uv0[q], &nb, p)
            })
            .collect();
        for (&q, s) in next.iter().zip(solved) {
            uv[q] = s;
            moved[q] = true;
        }
        front = next;
    }
    // Then the same energy against all neighbours, sweep after sweep, so where two fronts of the
    // spreading met the cloth settles between them.
    let sweep = PrintParams {
        iterations: 2,
        ..*p
    };
    for _ in 0..p.sweeps {
        for q in 0..uv.len() {
            if seeded[q] {
                continue;
            }
            let nb: Vec<Neighbour> = ring[q]
                .iter()
                .map(|&a| neighbour(q, a as usize, &uv))
                .collect();
            if !nb.is_empty() {
                uv[q] = minimise(uv0[q], &nb, &sweep);
            }
        }
    }
    Ok(uv.iter().map(|u| [u.x, u.y]).collect())
}

/// Step 1: each dimension set's UV edges scaled by the change of the set's 3D length, which is
/// each set scaled about its centre; where sets meet (a hem row and the back centre share a
/// corner), the sets' UVs are placed together by least squares over their scaled edges, each
/// connected group keeping its UV centroid.
fn seed(
    mesh: &KimonoMesh,
    before: &[Vec3],
    after: &[Vec3],
    uv0: &[Vector2<Real>],
    uv: &mut [Vector2<Real>],
    moved: &mut [bool],
) {
    // Scaled UV edges: (uv vertex a, uv vertex b, the ratio).
    // The UV edges of each mesh edge, one per triangle side it lies on.
    let mut uv_of: std::collections::HashMap<(u32, u32), Vec<(usize, usize)>> = Default::default();
    for (t, tri) in mesh.triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            let ut = mesh.uv_triangles[t];
            let (ua, ub) = (ut[k] as usize, ut[(k + 1) % 3] as usize);
            let (key, uv) = if a < b {
                ((a, b), (ua, ub))
            } else {
                ((b, a), (ub, ua))
            };
            let list = uv_of.entry(key).or_default();
            if !list.contains(&uv) {
                list.push(uv);
            }
        }
    }
    let mut edges: Vec<(usize, usize, Real)> = Vec::new();
    for (k, set) in mesh.dimensions.iter().enumerate() {
        let (l0, l1) = (mesh.measure(k, before), mesh.measure(k, after));
        if !(l0 > 0.0 && l1.is_finite()) {
            continue;
        }
        let ratio = l1 / l0;
        for e in &set.edges {
            let key = (e[0].min(e[1]), e[0].max(e[1]));
            for &(a, b) in uv_of.get(&key).into_iter().flatten() {
                if !edges
                    .iter()
                    .any(|&(x, y, _)| (x, y) == (a, b) || (x, y) == (b, a))
                {
                    edges.push((a, b, ratio));
                }
            }
        }
    }
    // Connected groups of the scaled edges.
    let mut root: Vec<usize> = (0..uv.len()).collect();
    fn find(r: &mut [usize], mut i: usize) -> usize {
        while r[i] != i {
            r[i] = r[r[i]];
            i = r[i];
        }
        i
    }
    for &(a, b, _) in &edges {
        let (ra, rb) = (find(&mut root, a), find(&mut root, b));
        root[ra.max(rb)] = ra.min(rb);
    }
    let mut groups: std::collections::BTreeMap<usize, Vec<usize>> = Default::default();
    for &(a, b, _) in &edges {
        for i in [a, b] {
            let r = find(&mut root, i);
            let g = groups.entry(r).or_default();
            if !g.contains(&i) {
                g.push(i);
            }
        }
    }
    // One group per UV island, the largest: the rest of the island follows it by eq. (2) (two
    // groups each held at its own centre would pull the cloth between them apart).
    let island = islands(mesh, uv.len());
    let mut best: std::collections::BTreeMap<usize, &Vec<usize>> = Default::default();
    for g in groups.values() {
        let e = best.entry(island[g[0]]).or_insert(g);
        if g.len() > e.len() {
            *e = g;
        }
    }
    for g in best.values() {
        let local: std::collections::HashMap<usize, usize> =
            g.iter().enumerate().map(|(i, &u)| (u, i)).collect();
        let n = g.len();
        // Normal equations of sum |(x_b - x_a) - ratio (u_b - u_a)|^2 + |mean x - mean u|^2 n.
        let mut a = nalgebra::DMatrix::<Real>::from_element(n, n, 1.0 / n as Real);
        let mut rhs = nalgebra::DMatrix::<Real>::zeros(n, 2);
        let centroid = g.iter().map(|&u| uv0[u]).sum::<Vector2<Real>>() / n as Real;
        for i in 0..n {
            rhs[(i, 0)] += centroid.x;
            rhs[(i, 1)] += centroid.y;
        }
        for &(ea, eb, ratio) in edges.iter().filter(|e| local.contains_key(&e.0)) {
            let (i, j) = (local[&ea], local[&eb]);
            let d = (uv0[eb] - uv0[ea]) * ratio;
            a[(i, i)] += 1.0;
            a[(j, j)] += 1.0;
            a[(i, j)] -= 1.0;
            a[(j, i)] -= 1.0;
            for c in 0..2 {
                rhs[(j, c)] += d[c];
                rhs[(i, c)] -= d[c];
            }
        }
        let Some(ch) = a.cholesky() else {
            continue;
        };
        let x = ch.solve(&rhs);
        for (i, &u) in g.iter().enumerate() {
            uv[u] = Vector2::new(x[(i, 0)], x[(i, 1)]);
            moved[u] = true;
        }
    }
}

/// The connected UV island of each UV vertex (a label).
fn islands(mesh: &KimonoMesh, n: usize) -> Vec<usize> {
    let mut root: Vec<usize> = (0..n).collect();
    fn find(r: &mut [usize], mut i: usize) -> usize {
        while r[i] != i {
            r[i] = r[r[i]];
            i = r[i];
        }
        i
    }
    for t in &mesh.uv_triangles {
        for k in 0..3 {
            let (a, b) = (
                find(&mut root, t[k] as usize),
                find(&mut root, t[(k + 1) % 3] as usize),
            );
            root[a.max(b)] = a.min(b);
        }
    }
    (0..n).map(|i| find(&mut root, i)).collect()
}

/// A moved neighbour of the vertex being corrected.
struct Neighbour {
    at: Vector2<Real>,
    moved: Vector2<Real>,
    length: Real,
    perp: Vector2<Real>,
}

/// Eq. (2) for one vertex whose UV was `p0`.
fn minimise(p0: Vector2<Real>, nb: &[Neighbour], p: &PrintParams) -> Vector2<Real> {
    let m = nb.iter().map(|a| a.moved).sum::<Vector2<Real>>() / nb.len() as Real;
    let l = (nb.iter().map(|a| a.length).sum::<Real>() / nb.len() as Real).max(1e-9);
    let mut q = p0 + m;
    for _ in 0..p.iterations {
        let mut h = Matrix2::identity() * (p.w_m / (l * l));
        let mut g = (q - p0 - m) * (p.w_m / (l * l));
        for a in nb {
            let la = a.length.max(1e-9);
            let d = q - a.at;
            let dn = d.norm();
            if dn > 1e-12 {
                let dir = d / dn;
                let r = (dn - la) / la;
                h += dir * dir.transpose() * (p.w_s / (la * la));
                g += dir * (p.w_s * r / la);
            }
            let rr = d.dot(&a.perp) / la;
            h += a.perp * a.perp.transpose() * (p.w_r / (la * la));
            g += a.perp * (p.w_r * rr / la);
        }
        let Some(inv) = h.try_inverse() else {
            break;
        };
        let step = inv * g;
        q -= step;
        if step.norm() < 1e-12 {
            break;
        }
    }
    q
}

/// How square the print's squares look on `positions` with `uvs`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PrintAspect {
    /// Area-weighted mean over triangles of the aspect ratio of a print square's image, taken as
    /// at least 1 (1 = square).
    pub mean: Real,
    /// Area-weighted mean of the image's side over the square's (1 = the print's own scale).
    pub scale: Real,
}

/// The print's aspect on `positions` (3D, one per vertex of `mesh`) with `uvs` (bolt coordinates,
/// one per UV vertex of `mesh`).
pub fn print_aspect(
    mesh: &KimonoMesh,
    positions: &[Vec3],
    uvs: &[[Real; 2]],
) -> Result<PrintAspect, PrintError> {
    check_points("the positions", positions, mesh.positions.len())?;
    check_uvs(uvs, mesh.uvs.len())?;
    let (mut sum, mut scale, mut area) = (0.0, 0.0, 0.0);
    for (t, ut) in mesh.triangles.iter().zip(&mesh.uv_triangles) {
        let x = t.map(|v| positions[v as usize]);
        let u = ut.map(|i| Vector2::new(uvs[i as usize][0], uvs[i as usize][1]));
        let m = Matrix2::from_columns(&[u[1] - u[0], u[2] - u[0]]);
        let Some(inv) = m.try_inverse() else {
            continue;
        };
        let (e1, e2) = (x[1] - x[0], x[2] - x[0]);
        let ju: Vec3 = e1 * inv[(0, 0)] + e2 * inv[(1, 0)];
        let jv: Vec3 = e1 * inv[(0, 1)] + e2 * inv[(1, 1)];
        let (a, b) = (ju.norm(), jv.norm());
        let w = 0.5 * e1.cross(&e2).norm();
        if !(a > 0.0 && b > 0.0 && w > 0.0) {
            continue;
        }
        sum += w * (a / b).max(b / a);
        scale += w * 0.5 * (a + b);
        area += w;
    }
    Ok(PrintAspect {
        mean: sum / area,
        scale: scale / area,
    })
}
