//! Where a drawn pixel lands on the garment (P3 Algorithm 1, step 1, lines drawn on a picture):
//! the ray through it, from the camera's eye, meets the garment's nearest triangle, unless the
//! body is in front of it there. The camera itself is the caller's.

use parry3d_f64::math::{Point, Vector};
use parry3d_f64::query::{Ray, RayCast};
use parry3d_f64::shape::Triangle;
use tryon_core::math::{Real, Vec3};

/// Why a drawn pixel gives no point on the garment.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Miss {
    /// The ray through it meets no garment triangle.
    NoGarment,
    /// The body is in front of the garment there.
    Hidden,
}

impl Miss {
    pub fn describe(self) -> &'static str {
        match self {
            Miss::NoGarment => "shows no garment (the ray through it misses the garment)",
            Miss::Hidden => "shows the body in front of the garment",
        }
    }
}

/// The point of `garment` the ray from `eye` along `dir` first meets, unless `body` is nearer.
/// Meshes are given as positions and triangles; either side of a triangle counts.
pub fn land(
    eye: Vec3,
    dir: Vec3,
    body: (&[Vec3], &[[u32; 3]]),
    garment: (&[Vec3], &[[u32; 3]]),
) -> Result<Vec3, Miss> {
    let ray = Ray::new(Point::from(eye), Vector::from(dir));
    let hit = nearest_hit(&ray, garment).ok_or(Miss::NoGarment)?;
    match nearest_hit(&ray, body) {
        Some(b) if b < hit => Err(Miss::Hidden),
        _ => Ok(eye + dir * hit),
    }
}

/// Distance along `ray` to the nearest of the triangles, either side facing.
fn nearest_hit(ray: &Ray, (x, tris): (&[Vec3], &[[u32; 3]])) -> Option<Real> {
    tris.iter()
        .filter_map(|t| {
            let [a, b, c] = t.map(|v| Point::from(x[v as usize]));
            Triangle::new(a, b, c).cast_local_ray(ray, Real::MAX, true)
        })
        .min_by(|a, b| a.total_cmp(b))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One triangle in the plane z = `z`, covering the origin's neighbourhood.
    fn plate(z: Real) -> Vec<Vec3> {
        vec![
            Vec3::new(-1.0, -1.0, z),
            Vec3::new(1.0, -1.0, z),
            Vec3::new(0.0, 1.0, z),
        ]
    }

    #[test]
    fn a_ray_lands_on_the_nearest_garment_point_and_is_refused_behind_the_body_or_past_it() {
        let tri = [[0u32, 1, 2]];
        let (near, far) = (plate(0.0), plate(-0.5));
        let eye = Vec3::new(0.1, 0.2, 2.0);
        let down = Vec3::new(0.0, 0.0, -1.0);
        // The garment alone: the point 2 m along the ray, on the plate.
        let p = land(eye, down, (&far, &[]), (&near, &tri)).unwrap();
        assert!((p - Vec3::new(0.1, 0.2, 0.0)).norm() < 1e-12, "{p:?}");
        // The body behind the garment does not hide it; in front of it, it does.
        assert!(land(eye, down, (&far, &tri), (&near, &tri)).is_ok());
        assert_eq!(
            land(eye, down, (&near, &tri), (&far, &tri)),
            Err(Miss::Hidden)
        );
        // A ray past the plate's side, or pointing away, meets no garment.
        let side = Vec3::new(5.0, 0.0, 2.0);
        assert_eq!(
            land(side, down, (&far, &[]), (&near, &tri)),
            Err(Miss::NoGarment)
        );
        assert_eq!(
            land(eye, -down, (&far, &[]), (&near, &tri)),
            Err(Miss::NoGarment)
        );
    }
}
