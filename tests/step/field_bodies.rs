//! Bodies of field materials side by side (issue 50): two `Nonlocal` bodies of different
//! grain sizes, or `MuI` beside `Nonlocal`, in one scene build without a schedule ambiguity,
//! and a body that shares no node with the other evolves bit for bit as it does alone. Each
//! body's fluidity lives on its own grid and is advanced for its own points; only the time
//! step and contact could couple them, and a fixed step and a gap of ten cells rule both out.

use regolith::{Regolith, Scene, Simulation};

/// PS-1 with a grain diameter of `d` (m), as `Nonlocal` or `MuI`.
fn ps1(kind: &str, d: f64) -> String {
    format!(
        "{kind}(youngs_modulus: 2.0e7, poisson_ratio: 0.45, grain_density: 1280.0, \
         packing_fraction: 0.79, grain_diameter: {d}, mu_s: 0.320, mu_2: 0.598, i_0: 0.278)"
    )
}

/// A 5 cm x 4 cm block on the left of a 20 cm x 10 cm box of 5 mm cells, and, with
/// `other`, a second block of that material 5 cm (ten cells) to its right; a fixed step.
fn run(other: Option<&str>) -> Simulation {
    let left = format!(
        "(name: \"left\", shape: Rectangle(min: (0.0, 0.0), max: (0.05, 0.04)), \
         material: {}, initial_stress: Lithostatic)",
        ps1("Nonlocal", 5.0e-3)
    );
    let bodies = match other {
        None => left,
        Some(material) => format!(
            "{left}, (name: \"right\", shape: Rectangle(min: (0.1, 0.0), max: (0.15, 0.04)), \
             material: {material}, initial_stress: Lithostatic)"
        ),
    };
    let text = format!(
        "Scene(name: \"side_by_side\", domain: (size: (0.2, 0.1), cells: (40, 20)), \
         time: (end: 0.02, step: Fixed(1.0e-5), output_every: 0.02), \
         walls: (left: Slip, right: Slip, bottom: NoSlip, top: Free), bodies: [{bodies}])"
    );
    let scene = Scene::parse(&text, "side_by_side.ron", &Regolith::default().registries())
        .unwrap_or_else(|e| panic!("{e}"));
    let mut sim = Simulation::new(&scene);
    sim.run(|_| {}).unwrap();
    sim
}

#[test]
fn a_field_body_evolves_alone_beside_another_field_body() {
    let mut alone = run(None);
    let moved = alone
        .points("left")
        .unwrap()
        .velocity
        .iter()
        .any(|v| v.length() > 1e-6);
    assert!(
        moved,
        "the block collapses under gravity, so the run tests something"
    );
    let expected = alone.state_hash("left").unwrap();
    for other in [ps1("Nonlocal", 2.5e-3), ps1("MuI", 5.0e-3)] {
        let mut pair = run(Some(&other));
        assert_eq!(
            pair.state_hash("left").unwrap(),
            expected,
            "the left block beside a block of {other}"
        );
        assert_ne!(pair.state_hash("right"), None);
    }
}
