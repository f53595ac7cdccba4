//! Frictional contact between bodies (docs/model.md §5).

use proptest::prelude::*;
use regolith::Simulation;
use regolith::contact::{NodeBody, frictional_impulses};
use regolith::defaults::parse_scene;
use regolith::glam::DVec2;

fn vec2() -> impl Strategy<Value = DVec2> {
    (-10.0f64..10.0, -10.0f64..10.0).prop_map(|(x, y)| DVec2::new(x, y))
}

proptest! {
    #![proptest_config(crate::property::config(5000, file!()))]

    /// On random two-body node states, with the common normal or either body's: the
    /// impulses cancel to round-off (momentum is conserved), an approaching pair leaves with
    /// zero normal relative velocity, friction never exceeds mu times the normal impulse,
    /// mu = 0 gives no tangential impulse, and a separating pair gets nothing.
    #[test]
    fn contact_impulses_conserve_momentum(
        ma in 0.01f64..10.0, mb in 0.01f64..10.0,
        va in vec2(), vb in vec2(), ga in vec2(), gb in vec2(),
        mu in prop_oneof![Just(0.0), 0.0f64..2.0],
        reference in prop_oneof![Just(None), Just(Some(0usize)), Just(Some(1usize))],
    ) {
        let a = NodeBody { mass: ma, momentum: ma * va, mass_gradient: ga };
        let b = NodeBody { mass: mb, momentum: mb * vb, mass_gradient: gb };
        // outward normals: from A towards B
        let towards = match reference { None => ga - gb, Some(0) => ga, _ => -gb };
        prop_assume!(towards.length() > 1e-6);
        let n = towards.normalize();
        let mut dp = [DVec2::ZERO; 2];
        frictional_impulses(&[a, b], mu, reference, 1e-9, &mut dp);
        let scale = a.momentum.length() + b.momentum.length() + 1e-300;
        prop_assert!((dp[0] + dp[1]).length() <= 1e-12 * scale);
        let w = va - vb;
        if w.dot(n) > 0.0 {
            let wa = (a.momentum + dp[0]) / ma - (b.momentum + dp[1]) / mb;
            prop_assert!(wa.dot(n).abs() <= 1e-9 * (w.length() + 1.0));
            let normal = dp[0].dot(n).abs();
            let tangential = (dp[0] - dp[0].dot(n) * n).length();
            prop_assert!(tangential <= mu * normal * (1.0 + 1e-9) + 1e-12 * scale);
            // Still slipping afterwards: Coulomb's law holds with equality.
            let slip_after = (wa - wa.dot(n) * n).length();
            if slip_after > 1e-9 * (w.length() + 1.0) {
                prop_assert!((tangential - mu * normal).abs() <= 1e-9 * (normal + 1e-300) + 1e-12 * scale);
            }
            if mu == 0.0 {
                prop_assert!(tangential <= 1e-12 * scale);
            }
        } else {
            prop_assert_eq!(dp[0], DVec2::ZERO);
            prop_assert_eq!(dp[1], DVec2::ZERO);
        }
    }
}

/// The shipped incline (stiff block on a stiff slab, the slab's normal) with gravity tilted
/// by `theta` and contact friction `mu`.
fn incline(theta_deg: f64, mu: f64) -> regolith::Scene {
    let th = theta_deg.to_radians();
    crate::common::scene(
        "contact_incline",
        &[
            &format!("gravity=({}, {})", 9.81 * th.sin(), -9.81 * th.cos()),
            &format!("contact=Frictional(friction: {mu}, normal: Body(\"slab\"))"),
        ],
    )
}

/// Above the friction angle the block slides with `g (sin theta - mu cos theta)`; the fit
/// skips the first 50 ms, in which the unstressed bodies settle elastically under the normal
/// load. Tolerance 2% (the issue's); measured 0.002%. Frictionless sliding must give
/// `g sin theta` the same way.
#[test]
fn block_slides_with_the_coulomb_acceleration() {
    for (theta, mu) in [(30.0f64, 0.3), (30.0, 0.0)] {
        check_sliding(theta, mu);
    }
}

fn check_sliding(theta: f64, mu: f64) {
    let mut sim = Simulation::new(&incline(theta, mu));
    sim.run(|_| {}).unwrap();
    let tr = sim.trajectory();
    let t = tr.series(0);
    let x = tr.series(tr.column("block", "x").unwrap());
    let keep: Vec<usize> = (0..t.len()).filter(|&k| t[k] >= 0.05).collect();
    let a = crate::common::fitted_acceleration(
        &keep.iter().map(|&k| t[k]).collect::<Vec<_>>(),
        &keep.iter().map(|&k| x[k]).collect::<Vec<_>>(),
    );
    let th = theta.to_radians();
    let expected = 9.81 * (th.sin() - mu * th.cos());
    let err = (a / expected - 1.0).abs();
    assert!(
        err < 0.02,
        "acceleration {a:.4} vs {expected:.4} m/s^2 (error {err:.4})"
    );
}

/// Below the friction angle the block stays stuck: over 0.25 s it creeps by less than 1% of
/// the distance it would slide without friction (`g sin theta t^2 / 2` = 8.2 cm).
#[test]
fn block_sticks_below_the_friction_angle() {
    let (theta, mu) = (25.0f64, 0.6);
    let mut sim = Simulation::new(&incline(theta, mu));
    sim.run(|_| {}).unwrap();
    let tr = sim.trajectory();
    let x = tr.series(tr.column("block", "x").unwrap());
    let creep = (x[x.len() - 1] - x[0]).abs();
    let free = 0.5 * 9.81 * theta.to_radians().sin() * 0.25f64.powi(2);
    assert!(
        creep < 0.01 * free,
        "the block moved {creep:.5} m (free slide {free:.4} m)"
    );
}

/// Two elastic discs collide head-on without friction and rebound: they end up moving
/// apart, and once separated no force acts between them (their velocities stop changing).
#[test]
fn colliding_discs_separate_without_sticking() {
    let scene = parse_scene(
        r#"(
        name: "collision",
        domain: (size: (1.0, 0.5), cells: (50, 25)),
        time: (end: 0.2, step: Cfl(0.5), output_every: 0.002),
        gravity: (0.0, 0.0),
        walls: (left: Free, right: Free, bottom: Free, top: Free),
        contact: Frictional(friction: 0.0),
        bodies: [
            (name: "left", shape: Disc(centre: (0.3, 0.25), radius: 0.08), velocity: (1.0, 0.0),
             material: LinearElastic(density: 1000.0, youngs_modulus: 1e6, poisson_ratio: 0.3), tracked: true),
            (name: "right", shape: Disc(centre: (0.7, 0.25), radius: 0.08), velocity: (-1.0, 0.0),
             material: LinearElastic(density: 1000.0, youngs_modulus: 1e6, poisson_ratio: 0.3), tracked: true),
        ],
    )"#,
    )
    .unwrap();
    let mut sim = Simulation::new(&scene);
    sim.run(|_| {}).unwrap();
    let tr = sim.trajectory();
    let vl = tr.series(tr.column("left", "vx").unwrap());
    let vr = tr.series(tr.column("right", "vx").unwrap());
    let xl = tr.series(tr.column("left", "x").unwrap());
    let xr = tr.series(tr.column("right", "x").unwrap());
    let n = vl.len();
    assert!(
        vl[n - 1] < -0.1 && vr[n - 1] > 0.1,
        "no rebound: {} {}",
        vl[n - 1],
        vr[n - 1]
    );
    assert!(
        xr[n - 1] - xl[n - 1] > xr[n - 2] - xl[n - 2],
        "not separating"
    );
    // Momentum: the pair's total x momentum stays zero.
    assert!((vl[n - 1] + vr[n - 1]).abs() < 1e-9);
    // Separated for the last 20 ms: velocities constant up to the discs' own vibration,
    // which moves the centre-of-mass velocity by nothing (no external force).
    let k = n - 11;
    assert!(
        (vl[n - 1] - vl[k]).abs() < 1e-9 && (vr[n - 1] - vr[k]).abs() < 1e-9,
        "a force acted after separation: {} -> {}",
        vl[k],
        vl[n - 1]
    );
}

/// A stiff intruder placed on an elastic bed with frictional contact settles under gravity:
/// it neither sinks into the bed (its base stays within one cell of the bed surface, the
/// grid contact's resolution) nor bounces off; after 0.5 s its speed is below 1 cm/s. Over
/// the last 0.2 s the contact force the bed exerts on it carries its weight on average (the
/// instantaneous force rings with the elastic bodies), and at every step it is equal and
/// opposite on the bed. Linear elasticity dissipates nothing, so the test damps the ringing
/// with a FLIP/PIC blend (its choice, stated here; pure FLIP or APIC keeps it ringing).
#[test]
fn intruder_settles_on_an_elastic_bed() {
    let scene = parse_scene(
        r#"(
        name: "settle",
        domain: (size: (0.4, 0.3), cells: (40, 30)),
        time: (end: 0.5, step: Cfl(0.5), output_every: 0.005),
        walls: (left: Slip, right: Slip, bottom: NoSlip, top: Free),
        contact: Frictional(friction: 0.1),
        transfer: Flip,
        flip: 0.95,
        bodies: [
            (name: "bed", shape: Rectangle(min: (0.0, 0.0), max: (0.4, 0.1)),
             material: LinearElastic(density: 1500.0, youngs_modulus: 2e6, poisson_ratio: 0.3),
             initial_stress: Lithostatic),
            (name: "intruder", shape: Rectangle(min: (0.15, 0.1), max: (0.25, 0.15)),
             material: LinearElastic(density: 3000.0, youngs_modulus: 2e7, poisson_ratio: 0.3),
             tracked: true),
        ],
    )"#,
    )
    .unwrap();
    let mut sim = Simulation::new(&scene);
    let (mut impulse, mut duration) = (DVec2::ZERO, 0.0);
    while !sim.finished() {
        sim.step().unwrap();
        let on_intruder = sim.grid_field("intruder").unwrap().contact_force;
        let on_bed = sim.grid_field("bed").unwrap().contact_force;
        assert!(
            (on_intruder + on_bed).length() <= 1e-9 * on_intruder.length().max(1.0),
            "contact forces {on_intruder} and {on_bed} are not equal and opposite"
        );
        if sim.clock().time > 0.3 {
            impulse += on_intruder * sim.clock().dt;
            duration += sim.clock().dt;
        }
    }
    let base = sim
        .points("intruder")
        .unwrap()
        .position
        .iter()
        .map(|p| p.y)
        .fold(f64::MAX, f64::min);
    let surface = sim
        .points("bed")
        .unwrap()
        .position
        .iter()
        .map(|p| p.y)
        .fold(f64::MIN, f64::max);
    let speed = sim.bodies()[1].1.velocity.length();
    let weight = sim.bodies()[1].1.mass * 9.81;
    let mean = impulse / duration;
    assert!(
        (mean.y / weight - 1.0).abs() < 0.02 && mean.x.abs() < 0.02 * weight,
        "mean contact force {mean} on an intruder of weight {weight:.3} N/m"
    );
    assert!(
        (base - surface).abs() < 0.01,
        "intruder base {base:.4} vs bed surface {surface:.4}"
    );
    assert!(speed < 0.01, "intruder still moving at {speed} m/s");
}

/// Both contact laws run a multi-body scene (the plugin example's ellipse on a block).
#[test]
fn both_contact_laws_run_multi_body_scenes() {
    for law in ["NoSlip", "Frictional(friction: 0.1)"] {
        let scene = crate::common::scene(
            "bench_elastic_block",
            &[
                "time.end=3e-4",
                &format!("contact={law}"),
                "bodies.bed.shape=Rectangle(min: (0.0, 0.0), max: (0.91, 0.5))",
            ],
        );
        let mut text_bodies = scene.clone();
        let intruder = crate::common::scene(
            "granular_bed_at_rest",
            &[
                "bodies.bed.shape=Disc(centre: (0.455, 0.56), radius: 0.05)",
                "bodies.bed.initial_stress=None",
            ],
        )
        .bodies
        .remove(0);
        let mut intruder = intruder;
        intruder.name = "intruder".into();
        intruder.velocity = DVec2::new(0.0, -3.0);
        text_bodies.bodies.push(intruder);
        let mut sim = Simulation::new(&text_bodies);
        sim.run(|_| {}).unwrap_or_else(|e| panic!("{law}: {e}"));
    }
}

/// With two bodies and a named normal, only the named body's mass gradient is scattered
/// (`Contact::needs_normal_of`): the run must be bitwise the one that keeps every body's.
#[test]
fn leaving_out_unused_gradients_changes_nothing() {
    use regolith::grid::GridField;

    let scene = crate::common::full_model_coarse_with(&[
        "contact=Frictional(friction: 0.1, normal: Body(\"disc\"))",
    ]);
    let mut lean = Simulation::new(&scene);
    let mut full = Simulation::new(&scene);
    assert!(lean.grid_field("bed").unwrap().mass_gradient.is_empty());
    assert!(!lean.grid_field("disc").unwrap().mass_gradient.is_empty());
    let mut fields = full.world.query::<&mut GridField>();
    for mut field in fields.iter_mut(&mut full.world) {
        let nodes = field.mass.len();
        *field = GridField::new(nodes, field.mass_tolerance, true);
    }
    let mut steps_in_contact = 0;
    for _ in 0..300 {
        lean.step().unwrap();
        full.step().unwrap();
        if full.grid_field("disc").unwrap().contact_force != DVec2::ZERO {
            steps_in_contact += 1;
        }
    }
    assert!(
        steps_in_contact > 100,
        "the disc must be in contact for the comparison to mean anything ({steps_in_contact} steps)"
    );
    assert_eq!(
        crate::common::bed_and_disc_fingerprints(&mut lean),
        crate::common::bed_and_disc_fingerprints(&mut full)
    );
}

/// A `NoSlip` seam between two bodies of the same material must be invisible: the block
/// split into two bodies along a cell line moves as the one body does, point for point, up
/// to round-off (the sums at the shared nodes are taken in another order). An elastic block
/// falls onto the floor at 2 m/s and rings for 40 ms, so the points near the seam carry
/// velocities their nodes do not (FLIP keeps them). This failed while the law gave each
/// body the acceleration of its own velocity change at a shared node, which removes the
/// points' velocity relative to the common one at every step, a damping one body does not
/// have: with FLIP, 3.3e-4 m and 0.25 m/s apart after 40 ms; now 8e-17 m and 5e-15 m/s
/// (docs/VALIDATION.md, "Against the authors' code").
#[test]
fn a_no_slip_seam_between_identical_bodies_is_invisible() {
    let run = |bodies: &str, transfer: &str| {
        let text = format!(
            r#"(
            name: "seam",
            domain: (size: (0.2, 0.2), cells: (20, 20)),
            time: (end: 0.04, step: Cfl(0.4), output_every: 0.04),
            walls: (left: Slip, right: Slip, bottom: NoSlip, top: Free),
            dilatation: PerPoint,
            transfer: {transfer},
            bodies: [{bodies}],
        )"#
        );
        let mut sim = Simulation::new(&parse_scene(&text).unwrap());
        sim.run(|_| {}).unwrap();
        let names: Vec<String> = sim.bodies().iter().map(|b| b.0.name.clone()).collect();
        let mut state = Vec::new();
        for name in names {
            let p = sim.points(&name).unwrap();
            state.extend(p.position.iter().copied().zip(p.velocity.iter().copied()));
        }
        state
    };
    let body = |name: &str, min: f64, max: f64| {
        format!(
            r#"(name: "{name}", shape: Rectangle(min: (0.05, {min}), max: (0.15, {max})),
               material: LinearElastic(density: 2000.0, youngs_modulus: 1e6, poisson_ratio: 0.3),
               velocity: (0.3, -2.0)),"#
        )
    };
    for transfer in ["Flip", "AffineFlip(relaxation: 25)"] {
        let one = run(&body("block", 0.02, 0.08), transfer);
        let two = run(
            &format!("{}{}", body("lower", 0.02, 0.05), body("upper", 0.05, 0.08)),
            transfer,
        );
        assert_eq!(one.len(), two.len());
        let (mut dx, mut dv) = (0.0f64, 0.0f64);
        for ((x1, v1), (x2, v2)) in one.iter().zip(&two) {
            dx = dx.max((*x1 - *x2).length());
            dv = dv.max((*v1 - *v2).length());
        }
        assert!(
            dx < 1e-10 && dv < 1e-8,
            "{transfer}: the split block is {dx:.3e} m and {dv:.3e} m/s away from the whole one"
        );
    }
}
