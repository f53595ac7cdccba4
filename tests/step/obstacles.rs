//! Fixed obstacles (issue 40): a block sliding on an inclined obstacle against Coulomb's law,
//! and grains poured onto a slope and a post never entering them.

use glam::DVec2;
use regolith::geometry::Shape;
use regolith::{Regolith, Scene, Simulation};

/// The shipped inclined obstacle (`scenes/obstacle_incline.ron`, a 30 degree slope) with
/// surface friction `mu`.
fn incline(mu: f64) -> Scene {
    crate::common::scene(
        "obstacle_incline",
        &[&format!(
            "obstacles=[(shape: Polygon(vertices: [(0.0, 0.0), (1.0, 0.0), (1.0, \
             0.5773502691896257)]), wall: Frictional(friction: {mu}))]"
        )],
    )
}

/// The block's displacement along the slope (m, up the slope positive) at each record, and
/// the records' times.
fn along_slope(sim: &Simulation) -> (Vec<f64>, Vec<f64>) {
    let tr = sim.trajectory();
    let (t, x, y) = (
        tr.series(0),
        tr.series(tr.column("block", "x").unwrap()),
        tr.series(tr.column("block", "y").unwrap()),
    );
    let th = 30f64.to_radians();
    let s = x
        .iter()
        .zip(&y)
        .map(|(x, y)| x * th.cos() + y * th.sin())
        .collect::<Vec<_>>();
    (t.to_vec(), s)
}

/// Above the friction angle the block slides down the slope with `g (sin 30 - mu cos 30)`,
/// and without friction with `g sin 30`; the fit skips the first 50 ms, in which the
/// unstressed block settles onto the slope. Tolerance 2%; measured 0.02% (mu 0.3) and 4e-7
/// (frictionless). The obstacle's normal comes from its edge at every node it holds, so a
/// wrong normal or a wrong friction law shows here directly.
#[test]
fn a_block_slides_down_an_inclined_obstacle_at_the_coulomb_rate() {
    for mu in [0.3, 0.0] {
        let mut sim = Simulation::new(&incline(mu));
        sim.run(|_| {}).unwrap();
        let (t, s) = along_slope(&sim);
        // The fit skips the first 50 ms.
        let (t, s): (Vec<f64>, Vec<f64>) = t.iter().zip(&s).filter(|(t, _)| **t >= 0.05).unzip();
        let a = crate::common::fitted_acceleration(&t, &s);
        let th = 30f64.to_radians();
        let expected = -9.81 * (th.sin() - mu * th.cos());
        let err = (a / expected - 1.0).abs();
        assert!(
            err < 0.02,
            "mu {mu}: acceleration {a:.4} vs {expected:.4} m/s^2 (error {err:.5})"
        );
    }
}

/// Below the friction angle (0.7 > tan 30 = 0.577) the block stays: over 0.25 s it creeps
/// by less than 1% of the distance it slides without friction (15.3 cm). Measured 1.1 mm.
#[test]
fn a_block_sticks_on_an_inclined_obstacle_below_the_friction_angle() {
    let mut sim = Simulation::new(&incline(0.7));
    sim.run(|_| {}).unwrap();
    let (_, s) = along_slope(&sim);
    let creep = (s[s.len() - 1] - s[0]).abs();
    let free = 0.5 * 9.81 * 0.5 * 0.25f64.powi(2);
    assert!(
        creep < 0.01 * free,
        "crept {creep:.5} m in 0.25 s (free sliding: {free:.4} m)"
    );
}

/// A layer of PS-1 grains dropped from 10 cm onto a 30 degree slope (a triangle) and a post
/// (a rectangle with two convex corners), through 0.3 s of impact, sliding and heaping.
const POUR: &str = r#"Scene(
    name: "pour_on_obstacles",
    domain: (size: (0.4, 0.4), cells: (40, 40)),
    time: (end: 0.3, step: Cfl(0.5), output_every: 0.01),
    walls: (left: NoSlip, right: NoSlip, bottom: NoSlip, top: Free),
    obstacles: [
        (shape: Polygon(vertices: [(0.0, 0.0), (0.25, 0.0), (0.0, 0.1443)]), wall: Frictional(friction: 0.1)),
        (shape: Rectangle(min: (0.3, 0.0), max: (0.36, 0.1)), wall: Slip),
    ],
    bodies: [
        (
            name: "grains",
            shape: Rectangle(min: (0.02, 0.2), max: (0.38, 0.3)),
            material: MuI(
                youngs_modulus: 2.0e7, poisson_ratio: 0.45,
                grain_density: 1280.0, packing_fraction: 0.79, grain_diameter: 5.0e-3,
                mu_s: 0.320, mu_2: 0.598, i_0: 0.278,
            ),
            points_per_cell: 2,
        ),
    ],
)"#;

/// No point of the poured layer is ever inside an obstacle, after any step: the grid holds
/// the obstacles' nodes, and the move stops a point where its path would enter. The layer
/// does land on both (points end within a cell of the slope, of the post's top and of its
/// corners' neighbourhood), and its mass is all still there.
#[test]
fn grains_poured_on_a_slope_and_a_post_never_enter_them() {
    let scene = Scene::parse(POUR, "pour", &Regolith::default().registries()).unwrap();
    let shapes: Vec<Box<dyn Shape>> = scene.obstacles.iter().map(|o| o.shape.0.clone()).collect();
    let mut sim = Simulation::new(&scene);
    let initial: f64 = sim.points("grains").unwrap().mass.iter().sum();
    let mut steps = 0;
    while !sim.finished() {
        sim.step().unwrap();
        steps += 1;
        let p = sim.points("grains").unwrap();
        for (k, x) in p.position.iter().enumerate() {
            for (o, shape) in shapes.iter().enumerate() {
                assert!(
                    !shape.contains(*x),
                    "step {steps}: point {k} at ({}, {}) is inside obstacle {o}",
                    x.x,
                    x.y
                );
            }
        }
    }
    let p = sim.points("grains").unwrap();
    let h = 0.01;
    let slope_normal = DVec2::new(0.1443, 0.25).normalize();
    let on_slope = p
        .position
        .iter()
        .filter(|x| x.x < 0.25 && (**x - DVec2::new(0.25, 0.0)).dot(slope_normal) < h)
        .count();
    let on_post = p
        .position
        .iter()
        .filter(|x| (0.3..0.36).contains(&x.x) && x.y < 0.1 + h)
        .count();
    assert!(
        on_slope > 20 && on_post > 5,
        "{on_slope} points rest on the slope and {on_post} on the post"
    );
    let mass: f64 = p.mass.iter().sum();
    assert!((mass - initial).abs() < 1e-12 * initial);
}
