//! The stress suite: each extreme case either runs to completion with bounded, finite
//! results or stops with a clear message; never a panic, a hang or a NaN in the output.

use regolith::defaults::parse_scene;
use regolith::{Scene, Simulation};

/// A PS-1 bed with an elastic disc intruder; `{..}` placeholders are filled per case.
const BASE: &str = r#"(
    name: "stress",
    domain: (size: (0.3, 0.3), cells: (30, 30)),
    time: (end: {end}, step: {step}, output_every: 0.002, allow_unstable: {unstable}),
    walls: (left: Slip, right: Slip, bottom: NoSlip, top: Free),
    contact: Frictional(friction: 0.1),
    bodies: [
        (name: "bed", shape: Rectangle(min: (0.0, 0.0), max: (0.3, {depth})), points_per_cell: {ppc},
         material: MuI(youngs_modulus: 2.0e7, poisson_ratio: 0.45, grain_density: 1280.0,
             packing_fraction: 0.79, grain_diameter: 5.0e-3, mu_s: {mu_s}, mu_2: {mu_2}, i_0: 0.278),
         initial_stress: Lithostatic),
        (name: "intruder", shape: Disc(centre: ({cx}, {centre}), radius: {radius}), velocity: (0.0, -{speed}),
         material: LinearElastic(density: 6500.0, youngs_modulus: {e}, poisson_ratio: 0.45),
         tracked: true),
    ],
)"#;

struct Case<'a> {
    name: &'a str,
    sets: &'a [(&'a str, &'a str)],
    /// Must the run stop with a fault?
    must_fail: bool,
}

fn scene(sets: &[(&str, &str)]) -> Result<Scene, String> {
    let defaults = [
        ("end", "0.01"),
        ("step", "Cfl(0.5)"),
        ("unstable", "false"),
        ("depth", "0.15"),
        ("ppc", "2"),
        ("mu_s", "0.32"),
        ("mu_2", "0.598"),
        ("cx", "0.15"),
        ("centre", "0.185"),
        ("radius", "0.03"),
        ("speed", "3.0"),
        ("e", "4e7"),
    ];
    let mut text = BASE.to_string();
    for (key, default) in defaults {
        let value = sets
            .iter()
            .find(|(k, _)| *k == key)
            .map_or(default, |(_, v)| v);
        text = text.replace(&format!("{{{key}}}"), value);
    }
    parse_scene(&text).map_err(|e| e.to_string())
}

/// Messages a stopped run may give: each names what went wrong.
const KNOWN: [&str; 4] = [
    "diverging",
    "not finite",
    "left the domain",
    "above the CFL limit",
];

fn run_case(case: &Case) {
    let scene = scene(case.sets).unwrap_or_else(|e| panic!("{}: {e}", case.name));
    let mut sim = Simulation::new(&scene);
    let result = sim.run(|_| {});
    match result {
        Ok(()) => {
            eprintln!("{}: completed, {} steps", case.name, sim.clock().step);
            assert!(!case.must_fail, "{}: should have stopped", case.name);
            for name in ["bed", "intruder"] {
                let p = sim.points(name).unwrap();
                assert!(
                    p.position.iter().all(|x| x.is_finite()),
                    "{}: non-finite position",
                    case.name
                );
                assert!(
                    p.stress.iter().all(|s| s.is_finite()),
                    "{}: non-finite stress",
                    case.name
                );
            }
            assert!(
                sim.trajectory()
                    .rows
                    .iter()
                    .flatten()
                    .all(|v| v.is_finite())
            );
        }
        Err(fault) => {
            eprintln!("{}: {fault}", case.name);
            assert!(
                KNOWN.iter().any(|k| fault.message.contains(k)),
                "{}: unexpected message: {fault}",
                case.name
            );
            assert!(!fault.to_string().contains("NaN") || fault.message.contains("not finite"));
            // Everything recorded before the fault is finite.
            assert!(
                sim.trajectory()
                    .rows
                    .iter()
                    .flatten()
                    .all(|v| v.is_finite()),
                "{}",
                case.name
            );
        }
    }
}

#[test]
fn time_step_from_tiny_to_past_the_stability_limit() {
    for (name, step, unstable, must_fail) in [
        ("CFL 0.05", "Cfl(0.05)", "false", false),
        ("CFL 0.5", "Cfl(0.5)", "false", false),
        ("CFL 1.0", "Cfl(1.0)", "false", false),
        (
            "fixed step at CFL 3, allowed",
            "Fixed(1.05e-4)",
            "true",
            true,
        ),
    ] {
        let end = if step == "Cfl(0.05)" { "0.002" } else { "0.01" };
        run_case(&Case {
            name,
            sets: &[("step", step), ("unstable", unstable), ("end", end)],
            must_fail,
        });
    }
    // Not allowed: refused before the run, with the limit in the message.
    let err = scene(&[("step", "Fixed(1.05e-4)")]).err().unwrap();
    assert!(
        err.contains("above the CFL limit") && err.contains("largest stable fixed step"),
        "{err}"
    );
}

#[test]
fn impact_speeds_from_slow_to_fast() {
    for speed in ["0.1", "1.0", "10.0", "50.0"] {
        run_case(&Case {
            name: &format!("impact at {speed} m/s"),
            sets: &[("speed", speed)],
            must_fail: false,
        });
    }
}

#[test]
fn stiff_intruders_and_friction_extremes() {
    run_case(&Case {
        name: "intruder E = 1 GPa",
        sets: &[("e", "1e9"), ("end", "0.003")],
        must_fail: false,
    });
    run_case(&Case {
        name: "mu_s = 0",
        sets: &[("mu_s", "0.0"), ("mu_2", "0.278")],
        must_fail: false,
    });
    run_case(&Case {
        name: "mu_s = 1",
        sets: &[("mu_s", "1.0"), ("mu_2", "1.278")],
        must_fail: false,
    });
}

#[test]
fn resolution_and_geometry_extremes() {
    run_case(&Case {
        name: "1 point per cell",
        sets: &[("ppc", "1")],
        must_fail: false,
    });
    run_case(&Case {
        name: "16 points per cell",
        sets: &[("ppc", "4"), ("end", "0.004")],
        must_fail: false,
    });
    run_case(&Case {
        name: "intruder touching the top edge",
        sets: &[("centre", "0.27"), ("speed", "0.0")],
        must_fail: false,
    });
    run_case(&Case {
        name: "intruder reaching the floor",
        sets: &[
            ("depth", "0.02"),
            ("centre", "0.055"),
            ("speed", "10.0"),
            ("end", "0.02"),
        ],
        must_fail: false,
    });
    // The lattice point (0.1525, 0.1875) is the only one within 3 mm of that centre.
    run_case(&Case {
        name: "a single-point intruder",
        sets: &[("cx", "0.1525"), ("centre", "0.1875"), ("radius", "0.003")],
        must_fail: false,
    });
    let err = scene(&[("radius", "0.001")]).err().unwrap();
    assert!(err.contains("holds no material point"), "{err}");
}
