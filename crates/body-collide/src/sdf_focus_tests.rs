//! The SDF collider focused on the cloth's surroundings (`Collider::focus`) against the same
//! collider over the whole body.

use crate::SdfCollider;
use crate::tests::{body_strategy, points_near, seeds};
use proptest::prelude::*;
use tryon_core::frames::BodyFrame;
use tryon_core::math::{Real, Vec3};
use tryon_core::stages::Collider;

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// Around the cloth the focused field is the whole field: the same distances in the band and
    /// the same sign everywhere, deep inside a body it cuts through too; and it has fewer nodes.
    #[test]
    fn a_field_focused_on_the_cloth_agrees_with_the_whole_field_around_it(
        m in body_strategy(),
        s in seeds(),
        centre in prop::array::uniform3(-0.3..0.3f64),
        half in prop::array::uniform3(0.0..0.25f64),
        res in 24usize..64,
    ) {
        let mut full = SdfCollider::new(&m, 0.0, res).unwrap();
        let mut focused = full.clone();
        let c: Vec3 = m.positions.iter().sum::<Vec3>() / m.positions.len() as Real;
        let mid = c + Vec3::new(centre[0], centre[1], centre[2]);
        let h = Vec3::new(half[0], half[1], half[2]);
        focused.focus(&(mid - h), &(mid + h));
        let up = Vec3::new(0.0, 0.01, 0.0);
        let frame = BodyFrame {
            time: 0.1,
            positions: m.positions.iter().map(|p| p + up).collect(),
            velocities: vec![],
        };
        full.update(&frame);
        focused.update(&frame);
        let [a, b] = [full.dims(), focused.dims()].map(|d| d[0] * d[1] * d[2]);
        prop_assert!(b <= a, "focused {b} nodes, whole {a}");
        let band = full.band as Real * full.cell_size();
        let slack = Vec3::repeat(SdfCollider::FOCUS_SLACK);
        let (lo, hi) = (mid - h - slack, mid + h + slack);
        let mut pts = points_near(&m, &s);
        // And points through the cloth's box itself.
        pts.extend(s.iter().map(|q| mid + h.component_mul(&Vec3::new(q[0], q[1], q[2]))));
        for p in pts.iter().filter(|p| (0..3).all(|k| p[k] >= lo[k] && p[k] <= hi[k])) {
            let (Some(w), Some(f)) = (full.signed_distance(p), focused.signed_distance(p)) else {
                continue;
            };
            if !w.is_finite() {
                continue; // beyond the whole field too: far from the body
            }
            prop_assert!(f.is_finite(), "{p:?} outside the focused field");
            if w.abs() < band {
                prop_assert!((w - f).abs() < 1e-9, "at {p:?}: whole {w}, focused {f}");
            }
            if w.abs() > 1e-9 {
                prop_assert_eq!(w < 0.0, f < 0.0, "at {:?}: whole {}, focused {}", p, w, f);
            }
        }
    }
}
