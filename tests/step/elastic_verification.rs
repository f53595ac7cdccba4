//! Verification of the step on elastic problems with analytic answers (issue: foundation).

use crate::common::measure::{bar_mode_period, front_speed};
use crate::common::scene;
use regolith::Simulation;
use regolith::material::elastic::p_wave_modulus;

const RHO: f64 = 1000.0;
const E: f64 = 1.0e7;
const NU: f64 = 0.3;

fn wave_speed() -> f64 {
    (p_wave_modulus(E, NU) / RHO).sqrt()
}

/// Measured and analytic first-mode period of the shipped bar with overrides.
fn bar_period(sets: &[&str]) -> (f64, f64) {
    let scene = scene("elastic_bar_vibration", sets);
    let measured = bar_mode_period(&scene, "bar", 1.0, 0.1)
        .unwrap()
        .expect("the bar oscillates");
    (measured, 4.0 / wave_speed())
}

/// Tolerance 1% (the issue's): at 50 cells along the bar the spatial error of mode 1 is
/// O((k h)^2) ~ 1e-3 and the time error O((w dt)^2) ~ 3e-4, so a larger miss is a bug.
#[test]
fn first_mode_period_within_one_percent_linear() {
    let (measured, exact) = bar_period(&["integration=Linear"]);
    let err = (measured / exact - 1.0).abs();
    assert!(err < 0.01, "period {measured} vs {exact} (error {err:.4})");
}

#[test]
fn first_mode_period_within_one_percent_bspline() {
    let (measured, exact) = bar_period(&["integration=QuadraticBspline"]);
    let err = (measured / exact - 1.0).abs();
    assert!(err < 0.01, "period {measured} vs {exact} (error {err:.4})");
}

#[test]
fn first_mode_period_within_one_percent_cpdi() {
    let (measured, exact) = bar_period(&["integration=CpdiFixed"]);
    let err = (measured / exact - 1.0).abs();
    assert!(err < 0.01, "period {measured} vs {exact} (error {err:.4})");
}

/// A stress-free column sags under gravity into `T_yy = -rho g (H - y)`; pure PIC damps the
/// oscillation. Tolerance 2% of `rho g H` (the issue's): after 6 s the remaining oscillation
/// carries about 0.5% of it and the discrete equilibrium of 24 cells differs from the
/// continuum by much less.
#[test]
fn column_settles_to_lithostatic_stress() {
    let scene = scene("elastic_column_gravity", &[]);
    let mut sim = Simulation::new(&scene);
    let y0: Vec<f64> = sim
        .points("column")
        .unwrap()
        .position
        .iter()
        .map(|p| p.y)
        .collect();
    sim.run(|_| {}).unwrap();
    let (rho, g, height) = (1000.0, 9.81, 1.0);
    let pts = sim.points("column").unwrap();
    let worst = pts
        .stress
        .iter()
        .zip(&y0)
        .map(|(s, y)| (s.yy + rho * g * (height - y)).abs())
        .fold(0.0, f64::max);
    let rel = worst / (rho * g * height);
    assert!(rel < 0.02, "largest T_yy misfit is {rel:.4} of rho g H");
}

/// Free fall is exact for the discrete scheme: with FLIP and uniform nodal acceleration g the
/// update is semi-implicit Euler, `y_n = y_0 - g dt^2 n(n+1)/2`, which the centre of mass
/// must follow to round-off. (It differs from the continuous `g t^2/2` by `g t dt/2`.)
/// Linear with USL is left out on purpose: round-off stress is amplified at nodes of tiny
/// mass and the body blows up (docs/numerics.md), which is why MUSL exists.
#[test]
fn free_fall_follows_the_discrete_parabola_to_round_off() {
    for (integration, update) in [
        ("Linear", "Musl"),
        ("CpdiFixed", "Usl"),
        ("CpdiFixed", "Musl"),
    ] {
        let scene = scene(
            "elastic_bar_vibration",
            &[
                "gravity=(0.0, -9.81)",
                "walls=(left: Free, right: Free, bottom: Free, top: Free)",
                "domain=(size: (1.0, 1.0), cells: (25, 25))",
                "bodies.bar.shape=Rectangle(min: (0.3, 0.6), max: (0.7, 0.9))",
                "time=(end: 0.2, step: Fixed(1e-4), output_every: 1e-2)",
                &format!("integration={integration}"),
                &format!("update={update}"),
            ],
        );
        let mut sim = Simulation::new(&scene);
        let y0 = sim.bodies()[0].1.centre_of_mass.y;
        let dt = 1e-4;
        let mut worst: f64 = 0.0;
        while !sim.finished() {
            sim.step()
                .unwrap_or_else(|e| panic!("{integration} {update}: {e}"));
            let n = sim.clock().step as f64;
            let y = sim.bodies()[0].1.centre_of_mass.y;
            let exact = y0 - 9.81 * dt * dt * n * (n + 1.0) / 2.0;
            worst = worst.max((y - exact).abs());
        }
        assert!(
            worst < 1e-12,
            "{integration}: centre of mass off by {worst:e} m"
        );
        let t = sim.clock().time;
        let continuous = y0 - 9.81 * t * t / 2.0;
        let y = sim.bodies()[0].1.centre_of_mass.y;
        assert!((y - continuous).abs() - 9.81 * t * dt / 2.0 < 1e-9);
        let stress = sim
            .points("bar")
            .unwrap()
            .stress
            .iter()
            .map(|s| s.pressure().abs())
            .fold(0.0, f64::max);
        assert!(
            stress < 1e-6,
            "{integration}: a falling body got stress {stress} Pa"
        );
    }
}

/// A bar moving at -v0 meets its fixed end: a compression front travels at
/// c = sqrt(M/rho). Arrival times at four stations (when the slab's mean velocity has
/// risen through -v0/2) are fitted by a line; tolerance 3% (the issue's); measured 1.5% at
/// this resolution (docs/ACCURACY.md). Linear runs with Musl: with Usl it blows up as the
/// front reaches the free end (docs/numerics.md).
#[test]
fn pulse_crosses_the_bar_at_the_p_wave_speed() {
    for (integration, update) in [("Linear", "Musl"), ("CpdiFixed", "Usl")] {
        let scene = scene(
            "elastic_bar_vibration",
            &[
                "bodies.bar.velocity=(-1.0, 0.0)",
                "time.end=0.0085",
                "domain.cells=(120, 4)",
                "domain.size=(1.2, 0.04)",
                "bodies.bar.shape=Rectangle(min: (0.0, 0.0), max: (1.0, 0.04))",
                &format!("integration={integration}"),
                &format!("update={update}"),
            ],
        );
        let slope = front_speed(&scene, "bar", &[0.2, 0.4, 0.6, 0.8], 0.011, 1.0)
            .unwrap()
            .expect("the front reaches every station");
        let err = (slope / wave_speed() - 1.0).abs();
        assert!(
            err < 0.03,
            "{integration}: front speed {slope:.2} m/s vs {:.2} (error {err:.4})",
            wave_speed()
        );
    }
}
