//! Tests of pressing parts apart: two meshed balls of different parts, overlapping or apart.

use super::*;
use tryon_core::shapes::icosphere;

/// Two balls of radius 0.1 (parts 0 and 1) whose centres are `apart` along x, as one mesh.
fn balls(apart: Real) -> (Vec<Vec3>, Vec<[u32; 3]>, Vec<u8>) {
    let a = icosphere(0.1, 4, Vec3::zeros());
    let b = icosphere(0.1, 4, Vec3::new(apart, 0.0, 0.0));
    let (ta, _) = a.triangulate();
    let (tb, _) = b.triangulate();
    let na = a.positions.len() as u32;
    let mut x = a.positions.clone();
    x.extend(&b.positions);
    let mut t = ta;
    t.extend(tb.iter().map(|f| f.map(|v| v + na)));
    let parts = (0..x.len()).map(|v| u8::from(v as u32 >= na)).collect();
    (x, t, parts)
}

/// The x coordinates of part `part`'s vertices.
fn xs<'a>(x: &'a [Vec3], parts: &'a [u8], part: u8) -> impl Iterator<Item = Real> + 'a {
    x.iter()
        .zip(parts)
        .filter(move |(_, p)| **p == part)
        .map(|(v, _)| v.x)
}

/// The x extent where the balls meet: ball 0's rightmost point and ball 1's leftmost.
fn facing_sides(x: &[Vec3], parts: &[u8]) -> (Real, Real) {
    let right = xs(x, parts, 0).fold(Real::MIN, Real::max);
    let left = xs(x, parts, 1).fold(Real::MAX, Real::min);
    (right, left)
}

#[test]
fn overlapping_parts_are_pressed_apart_to_the_gap() {
    // Centres 0.19 apart: the balls overlap by 1 cm.
    let (mut x, t, parts) = balls(0.19);
    let press = Press {
        parts: parts.clone(),
        gap: 0.004,
    };
    let r = press.apply(&mut x, &t);
    assert!(r.moved > 0);
    // The deepest overlap is the 1 cm between the poles (to within the mesh's facets).
    assert!((r.deepest - 0.01).abs() < 0.002, "deepest {}", r.deepest);
    let (right, left) = facing_sides(&x, &parts);
    // The poles met half-way and now stand the gap apart (the poles' own normals are exact).
    assert!(
        (left - right - 0.004).abs() < 0.0015,
        "gap {}",
        left - right
    );
    assert!((right - 0.093).abs() < 0.0015, "right pole at {right}");
    // Only the facing caps moved: the far poles stay where they were.
    let far = xs(&x, &parts, 1).fold(Real::MIN, Real::max);
    assert!((far - 0.29).abs() < 1e-12);
}

#[test]
fn parts_apart_or_one_part_alone_are_left_as_they_are() {
    for (apart, parts_differ) in [(0.25, true), (0.19, false)] {
        let (mut x, t, mut parts) = balls(apart);
        if !parts_differ {
            parts.iter_mut().for_each(|p| *p = 0);
        }
        let before = x.clone();
        let r = Press { parts, gap: 0.004 }.apply(&mut x, &t);
        assert_eq!(r, Pressed::default());
        assert_eq!(x, before);
    }
}

#[test]
fn a_part_deeper_than_the_limit_is_not_pushed_through() {
    // A 5 cm overlap is past DEEPEST: the facing vertex is taken for the far side, nothing moves.
    let (mut x, t, parts) = balls(0.15);
    let before = x.clone();
    Press { parts, gap: 0.004 }.apply(&mut x, &t);
    let moved = x.iter().zip(&before).filter(|(a, b)| a != b).count();
    // Only the rim where the overlap is shallow moves (well under a tenth of the vertices).
    assert!(moved < x.len() / 10, "{moved} of {} moved", x.len());
}

#[test]
fn non_finite_positions_and_short_part_lists_do_not_panic() {
    let (mut x, t, parts) = balls(0.19);
    x[3] = Vec3::new(Real::NAN, 0.0, 0.0);
    let press = Press {
        parts: parts[..100].to_vec(),
        gap: 0.004,
    };
    press.apply(&mut x, &t);
    let press = Press { parts, gap: 0.004 };
    press.apply(&mut x, &t);
    assert!(
        x.iter()
            .enumerate()
            .all(|(v, p)| v == 3 || p.iter().all(|c| c.is_finite()))
    );
}

#[test]
fn the_parts_around_a_cell_are_those_of_its_27_cells() {
    // Scattered points of five parts, in a grid several cells wide each way.
    let x: Vec<Vec3> = (0..400)
        .map(|i| {
            let f = i as Real;
            Vec3::new(
                (f * 0.37).sin() * 0.1,
                (f * 0.71).cos() * 0.08,
                (f * 0.13).sin() * 0.12,
            )
        })
        .collect();
    let parts: Vec<u8> = (0..x.len()).map(|i| (i % 5) as u8).collect();
    let grid = Grid::new(&x, &parts).expect("finite points");
    assert!(grid.dims.iter().all(|&d| d >= 3), "{:?}", grid.dims);
    let fast = grid.masks_around();
    let d = grid.dims;
    for (c, m) in fast.iter().enumerate() {
        let at = [
            c as i64 % d[0],
            (c as i64 / d[0]) % d[1],
            c as i64 / (d[0] * d[1]),
        ];
        let slow = grid.around(at).fold(0u32, |m, k| m | grid.mask[k]);
        assert_eq!(*m, slow, "cell {at:?}");
    }
}

#[test]
fn a_vertex_takes_the_part_of_its_strongest_joint_from_the_root_down() {
    // root 0 -> spine 1 -> arm 2 -> hand 3; root 0 -> leg 4. Roots: the arm (part 1), the leg (2).
    let skeleton = Skeleton {
        names: ["root", "spine", "arm", "hand", "leg"]
            .map(String::from)
            .to_vec(),
        parents: vec![None, Some(0), Some(1), Some(2), Some(0)],
        rest_offsets: vec![Vec3::zeros(); 5],
    };
    let joints = [
        [3, 1, 0, 0],
        [1, 2, 0, 0],
        [2, 4, 0, 0],
        [4, 0, 0, 0],
        [9, 0, 0, 0],
    ];
    let weights = [
        [0.6, 0.4, 0.0, 0.0],
        [0.7, 0.3, 0.0, 0.0],
        [0.2, 0.8, 0.0, 0.0],
        [1.0, 0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0, 0.0],
    ];
    let parts = Press::parts_from_roots(&skeleton, &joints, &weights, &[Some(2), Some(4)]);
    // The hand is below the arm; the spine is torso; a joint the skeleton lacks is torso too.
    assert_eq!(parts, vec![1, 0, 2, 2, 0]);
}
