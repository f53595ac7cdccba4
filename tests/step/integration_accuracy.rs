//! Accuracy of the shape-function schemes on whole runs (issue: integration schemes).
//! The measured tables are in docs/ACCURACY.md (`cargo run --release -p regolith-lab --example accuracy`).

use crate::common::measure::{bar_mode_period, largest_stress};
use crate::common::scene;
use regolith::material::elastic::p_wave_modulus;

fn bar_sets(cells: usize, integration: &str) -> Vec<String> {
    let h = 1.2 / cells as f64;
    vec![
        format!("domain=(size: (1.2, {}), cells: ({cells}, 4))", 4.0 * h),
        format!(
            "bodies.bar.shape=Rectangle(min: (0.0, 0.0), max: (1.0, {}))",
            4.0 * h
        ),
        format!("integration={integration}"),
    ]
}

/// The first-mode period error falls under refinement with each scheme at second order
/// (the central-difference time step and the lumped-mass bilinear space discretisation are
/// both second order, and CFL 0.5 ties dt to h). Measured: 5.1e-4, 1.3e-4, 3.2e-5 for both
/// schemes, order 2.0; the test asks for an order above 1.5 between the two finest grids.
#[test]
fn vibration_period_converges_at_second_order() {
    let exact = 4.0 / (p_wave_modulus(1.0e7, 0.3) / 1000.0).sqrt();
    for integration in ["Linear", "CpdiFixed"] {
        let errors: Vec<f64> = [30, 60, 120]
            .iter()
            .map(|&n| {
                let sets = bar_sets(n, integration);
                let refs: Vec<&str> = sets.iter().map(String::as_str).collect();
                let measured =
                    bar_mode_period(&scene("elastic_bar_vibration", &refs), "bar", 1.0, 0.1)
                        .unwrap()
                        .expect("the bar oscillates");
                (measured / exact - 1.0).abs()
            })
            .collect();
        assert!(
            errors[0] > errors[1] && errors[1] > errors[2],
            "{integration}: {errors:?}"
        );
        let order = (errors[1] / errors[2]).log2();
        assert!(
            order > 1.5,
            "{integration}: observed order {order:.2} ({errors:?})"
        );
    }
}

/// An unstressed block translating at 1 m/s across ten cells of a periodic domain: every
/// node carries the same velocity, so a consistent scheme gives `L = v (outer) sum grad S = 0`
/// and no stress. What remains is round-off, about `E * 1e-16` per step over 760 steps,
/// ~1e-7 Pa; the bound is 1e-6 Pa. (Linear with USL is not stable here: round-off is
/// amplified at nodes of tiny mass and the block blows up; docs/ACCURACY.md.)
#[test]
fn translating_block_gets_no_spurious_stress() {
    for (integration, update) in [
        ("CpdiFixed", "Usl"),
        ("CpdiFixed", "Musl"),
        ("Linear", "Musl"),
    ] {
        let scene = scene(
            "elastic_bar_vibration",
            &[
                "domain=(size: (1.0, 0.5), cells: (20, 10))",
                "walls=(left: Periodic, right: Periodic, bottom: Free, top: Free)",
                "bodies.bar.shape=Rectangle(min: (0.3, 0.15), max: (0.7, 0.35))",
                "bodies.bar.velocity=(1.0, 0.0)",
                "time=(end: 0.5, step: Cfl(0.5), output_every: 0.01)",
                &format!("integration={integration}"),
                &format!("update={update}"),
            ],
        );
        let worst = largest_stress(&scene, "bar").unwrap();
        assert!(
            worst < 1e-6,
            "{integration} {update}: spurious stress {worst:e} Pa"
        );
    }
}
