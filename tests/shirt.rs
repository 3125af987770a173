//! The shirt pattern (issue 22's shirt with sleeves): cut from the mannequin's own surface, it is
//! one piece with four openings (neck, hem, two sleeves), about 14,000 triangles at one split, clear
//! of the body with no short edges left where the crease under the arm was (the gusset), and it
//! stays on the standing body held by its neckline.

use tryon_core::math::{Real, Vec3};
use tryon_core::mesh::PolyMesh;
use tryon_core::stages::Collider;
use tryon_pipeline::scene::BodySection;
use tryon_pipeline::{Pipeline, Scene};

const SCENE: &str = r#"
[scene]
name = "shirt"
fps = 30
duration = 0.5
[body]
kind = "mannequin"
[garment]
kind = "shirt"
subdivisions = 1
[motion]
kind = "still"
[cloth]
solver = "xpbd"
[effects]
body_collision = "sdf"
"#;

fn pipeline() -> Pipeline {
    let scene = Scene::parse(SCENE, std::path::Path::new("shirt.toml")).expect("scene");
    Pipeline::new(scene).expect("pipeline")
}

fn edges(mesh: &PolyMesh) -> Vec<[u32; 2]> {
    let (tris, _) = mesh.triangulate();
    let mut e: Vec<[u32; 2]> = tris
        .iter()
        .flat_map(|t| (0..3).map(move |k| [t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3])]))
        .collect();
    e.sort_unstable();
    e.dedup();
    e
}

#[test]
fn the_shirt_is_one_piece_with_four_openings_clear_of_the_body() {
    let p = pipeline();
    let g = &p.garment;
    let (tris, _) = g.triangulate();
    assert!(
        (12_000..17_000).contains(&tris.len()),
        "{} triangles",
        tris.len()
    );
    assert_eq!(garment_fit::boundary_loops(g).expect("manifold").len(), 4);
    let crossing = body_collide::crossings::crossings(&g.positions, &tris);
    for [a, b] in crossing.iter().take(8) {
        eprintln!(
            "{:?} x {:?}",
            tris[*a as usize].map(|v| g.positions[v as usize]),
            tris[*b as usize].map(|v| g.positions[v as usize])
        );
    }
    assert!(crossing.is_empty(), "{} crossing pairs", crossing.len());
    assert!(
        garment_fit::components(g).iter().all(|&c| c == 0),
        "one piece"
    );
    let (worst, at) = g
        .positions
        .iter()
        .filter_map(|x| Some((p.referee.signed_distance(x)?, *x)))
        .fold((Real::INFINITY, Vec3::zeros()), |w, d| {
            if d.0 < w.0 { d } else { w }
        });
    assert!(
        worst >= -1e-6,
        "a vertex at {at:?} {worst} m inside the body"
    );
    // Cut straight from the skin, the crease under each arm left edges of 0.2-1.5 mm once the
    // vertices there were pushed out of the body; the gusset leaves none under 2 mm (median 1 cm).
    let shortest = edges(g)
        .iter()
        .map(|&[a, b]| (g.positions[a as usize] - g.positions[b as usize]).norm())
        .fold(Real::INFINITY, Real::min);
    assert!(shortest > 0.002, "an edge of {shortest} m");
    // Looser than the body: at the waist the shirt's girth is the body's and most of the ease.
    let BodySection::Mannequin(body) = &p.scene.body else {
        panic!("a mannequin scene")
    };
    let lm = body.measurements().landmarks();
    let near_waist: Vec<Vec3> = g
        .positions
        .iter()
        .filter(|x| (x.y - lm.waist).abs() < 0.006)
        .copied()
        .collect();
    let reach = near_waist
        .iter()
        .map(|x| x.x.hypot(x.z))
        .fold(0.0, Real::max);
    assert!(reach > 0.12, "waist ring reaches {reach} m from the axis");
}

#[test]
fn the_shirt_stays_on_the_standing_body_unstretched() {
    let mut p = pipeline();
    let rest: Vec<Vec3> = p.cloth.positions.clone();
    let run = p.run(Some(15), |_, _| {});
    let m = &run.stats.metrics;
    assert_eq!(m.non_finite_events, 0);
    assert_eq!(m.detached_share, 0.0);
    assert!(m.max_penetration_m < 0.01, "{}", m.max_penetration_m);
    let x = &p.cloth.positions;
    let (worst, at) = edges(&p.garment)
        .iter()
        .map(|&[a, b]| {
            let (a, b) = (a as usize, b as usize);
            ((x[a] - x[b]).norm() / (rest[a] - rest[b]).norm(), rest[a])
        })
        .fold((1.0 as Real, Vec3::zeros()), |w, r| {
            if (r.0 - 1.0).abs() > (w.0 - 1.0).abs() {
                r
            } else {
                w
            }
        });
    // Not yet the dress's 0.97..1.03 on the same stand: where the arm's back and front meet the
    // torso (a crease the gusset does not cover) the contact strains the cloth to about 1.9
    // (docs/decisions, *shirt*). This bounds it; a shirt cut straight from the skin went to
    // 4-16 after one frame.
    assert!(
        (0.3..2.5).contains(&worst),
        "an edge at {at:?} went to {worst} of its length"
    );
    let drop = rest
        .iter()
        .zip(x)
        .map(|(a, b)| a.y - b.y)
        .fold(0.0, Real::max);
    assert!(drop < 0.05, "a vertex fell {drop} m");
}

/// A heavy figure's mannequin has its arms through its sides (the body itself crosses itself in the
/// A-pose); a shirt cut from it would too, and tears at the first frame. It is refused, saying why.
#[test]
fn a_shirt_for_a_mannequin_whose_arms_pass_into_its_sides_is_refused() {
    let text = SCENE.replace(
        "kind = \"mannequin\"",
        "kind = \"mannequin\"\nheight = 1.75\nbust = 1.2\nwaist = 1.1\nhip = 1.2",
    );
    let scene = Scene::parse(&text, std::path::Path::new("shirt.toml")).expect("scene");
    let Err(e) = Pipeline::new(scene) else {
        panic!("a shirt for this figure was made")
    };
    let e = e.to_string();
    assert!(e.contains("crosses itself") && e.contains("arms"), "{e}");
}
