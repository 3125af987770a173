//! The formulas against worked figures of their sources (the numbers below were worked by hand
//! from the sources' formulas and standard tables, in centimetres).

use super::*;

fn cm(x: Real) -> Real {
    x / 100.0
}

fn close(a: Real, b: Real, tol_cm: Real) -> bool {
    (a - b).abs() <= cm(tol_cm)
}

#[test]
fn widths_from_the_hip_follow_kotaro() {
    // [K], hip 90 cm: 後巾 = 22.5 + 6 = 28.5 cm, 前巾 = 28.5 − 1寸5分 (5.682) = 22.818 cm,
    // 衽巾 4寸 = 15.152 cm, 合褄巾 = 4寸 − 3分 = 14.016 cm (akinai's standard table: 3寸5分–3寸8分).
    let d = tailor(&Wearer::new(1.55, 0.84, 0.66, 0.90)).unwrap();
    assert!(close(d.back_width, cm(28.5), 0.001), "{}", d.back_width);
    assert!(close(d.front_width, cm(22.818), 0.001), "{}", d.front_width);
    assert!(close(d.okumi_width, cm(15.152), 0.001));
    assert!(close(d.overlap_width, cm(14.016), 0.001));
    // 抱き巾 = 84/4 + 2 = 23 cm, inside 前巾 ± 3分 (21.682..23.954).
    assert!(close(d.holding_width, cm(23.0), 0.001));
    // Hip 104 cm: 後巾 32 cm, 前巾 = 32 − 1寸 = 28.212 cm, 衽巾 4寸1分 = 15.531 cm, no overlap taken off.
    let d = tailor(&Wearer::new(1.60, 1.00, 0.85, 1.04)).unwrap();
    assert!(close(d.back_width, cm(32.0), 0.001));
    assert!(close(d.front_width, cm(28.212), 0.001));
    assert!(close(d.okumi_width, cm(15.531), 0.001));
    assert_eq!(d.overlap_width, d.okumi_width);
    // Hip 106 cm: 衽巾 4寸2分 = 15.910 cm.
    let d = tailor(&Wearer::new(1.60, 1.00, 0.85, 1.06)).unwrap();
    assert!(close(d.okumi_width, cm(15.910), 0.001));
}

#[test]
fn a_full_bust_is_held_to_the_front_width_plus_three_bu() {
    // Bust 100 cm at hip 90: 100/4 + 2 = 27 cm, held to 22.818 + 1.136 = 23.954 cm.
    let d = tailor(&Wearer::new(1.55, 1.00, 0.80, 0.90)).unwrap();
    assert!(
        close(d.holding_width, cm(23.954), 0.001),
        "{}",
        d.holding_width
    );
}

#[test]
fn lengths_from_the_height_follow_akinai_j_dress_and_kotaro() {
    // 155 cm: 裄 = 62 + 2 = 64 cm [A], 袖丈 = 46.5 cm [A], 着丈 = 128.65 cm [J], 身丈 155 cm,
    // 衿下 = 77.5 cm [K], 袖付 5寸5分 = 20.834 cm [A], 袖口 6寸 = 22.728 cm [A].
    let d = tailor(&Wearer::new(1.55, 0.84, 0.66, 0.90)).unwrap();
    assert!(close(d.yuki, cm(64.0), 0.001));
    assert!(close(d.sleeve_length, cm(46.5), 0.001));
    assert!(close(d.garment_length, cm(128.65), 0.001));
    assert!(close(d.body_length, cm(155.0), 0.001));
    assert!(close(d.below_collar, cm(77.5), 0.001));
    assert!(close(d.sleeve_attach, cm(20.834), 0.001));
    assert!(close(d.sleeve_opening, cm(22.728), 0.001));
    // 180 cm: 衿下 would be 90 cm, held to 83 cm [M]; 袖付 6寸 for a tall figure.
    let d = tailor(&Wearer::new(1.80, 0.90, 0.72, 0.96)).unwrap();
    assert!(close(d.below_collar, cm(83.0), 0.001));
    assert!(close(d.sleeve_attach, cm(22.728), 0.001));
    // 145 cm: 袖付 5寸2分 = 19.698 cm, 衽下がり 5寸5分 = 20.834 cm.
    let d = tailor(&Wearer::new(1.45, 0.80, 0.62, 0.86)).unwrap();
    assert!(close(d.sleeve_attach, cm(19.698), 0.001));
    assert!(close(d.okumi_drop, cm(20.834), 0.001));
}

#[test]
fn shoulder_and_sleeve_share_the_yuki_as_the_standard_size_does() {
    // kimonolife's standard size (155 cm, hip 90 cm) wears 肩巾 31.5 cm and 袖巾 33 cm, a 裄 of
    // 64.5 cm; [D]'s split (裄/2 ± 2.5分) gives 33.197 and 31.303 cm: within 2 mm of it.
    let w = Wearer {
        yuki: Some(0.645),
        ..Wearer::new(1.55, 0.84, 0.66, 0.90)
    };
    let d = tailor(&w).unwrap();
    assert!(close(d.sleeve_width, cm(33.197), 0.001));
    assert!(close(d.shoulder_width, cm(31.303), 0.001));
    assert!(close(d.sleeve_width, cm(33.0), 0.2) && close(d.shoulder_width, cm(31.5), 0.2));
    assert_eq!(d.sleeve_width + d.shoulder_width, 0.645);
}

#[test]
fn out_of_range_measurements_name_themselves() {
    let ok = Wearer::new(1.6, 0.86, 0.68, 0.92);
    for (w, name) in [
        (Wearer { height: 2.3, ..ok }, "height"),
        (
            Wearer {
                height: Real::NAN,
                ..ok
            },
            "height",
        ),
        (Wearer { bust: 0.3, ..ok }, "bust"),
        (Wearer { waist: -1.0, ..ok }, "waist"),
        (Wearer { hip: 1.3, ..ok }, "hip"),
        (
            Wearer {
                yuki: Some(0.8),
                ..ok
            },
            "yuki",
        ),
        (
            Wearer {
                sleeve_length: Some(Real::INFINITY),
                ..ok
            },
            "sleeve_length",
        ),
    ] {
        match tailor(&w) {
            Err(TailorError::OutOfRange { name: n, .. }) => assert_eq!(n, name),
            other => panic!("{name}: {other:?}"),
        }
    }
    let e = tailor(&Wearer { hip: 1.3, ..ok }).unwrap_err().to_string();
    assert!(e.contains("`hip` = 1.3") && e.contains("bolt"), "{e}");
}

#[test]
fn table_1_lists_seventeen_in_the_papers_order() {
    let d = tailor(&Wearer::new(1.6, 0.86, 0.68, 0.92)).unwrap();
    let t = d.table();
    assert_eq!(t[0].0, "right sleeve length");
    assert_eq!(t[16].0, "overlap width");
    assert_eq!(t[9].1, d.shoulder_width);
    assert!(t.iter().all(|(_, v)| v.is_finite() && *v > 0.0));
}
