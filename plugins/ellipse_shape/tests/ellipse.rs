//! The example plugin works through the public API alone.

use ellipse_shape::EllipsePlugin;
use regolith::{Regolith, Scene, Simulation};

fn scene_file() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/ellipse_on_block.ron")
}

#[test]
fn the_builtin_registry_does_not_know_ellipses() {
    let err = Scene::load(&scene_file(), &[], &Regolith::default().registries()).unwrap_err();
    assert!(err.message.contains("unknown shape `Ellipse`"), "{err}");
}

#[test]
fn an_ellipse_is_filled_with_its_area_and_falls() {
    let registries = Regolith::default().add_plugin(EllipsePlugin).registries();
    let (scene, _) = Scene::load(&scene_file(), &[], &registries).unwrap();
    let mut sim = Simulation::new(&scene);
    let bodies = sim.bodies();
    let (ellipse, state, points) = &bodies[1];
    assert_eq!(ellipse.name, "ellipse");
    // Lattice spacing 0.005 m: the point count estimates the area pi a b to about 3%.
    let area = std::f64::consts::PI * 0.06 * 0.03;
    let filled = *points as f64 * 0.005 * 0.005;
    assert!((filled / area - 1.0).abs() < 0.03, "{filled} vs {area}");
    // The shape knows its area, so the mass is exact.
    assert!((state.mass - area * 3000.0).abs() < 1e-9 * state.mass);
    let y0 = state.centre_of_mass.y;
    for _ in 0..50 {
        sim.step().unwrap();
    }
    assert!(sim.bodies()[1].1.centre_of_mass.y < y0);
}

#[test]
fn bad_ellipse_parameters_point_at_the_line() {
    let registries = Regolith::default().add_plugin(EllipsePlugin).registries();
    let text = std::fs::read_to_string(scene_file())
        .unwrap()
        .replace("semi_axes: (0.06, 0.03)", "semi_axes: (0.06, -0.03)");
    let err = Scene::parse(&text, "e.ron", &registries).unwrap_err();
    assert!(
        err.message.contains("semi_axes.1 must be a positive"),
        "{err}"
    );
    assert_eq!(err.line, Some(19));
}

/// The plugin's intruder scene: the ellipse has the paper intruder's mass and penetrates the
/// PS-1 bed (first 20 ms of the coarse impact).
#[test]
fn the_ellipse_impact_scene_runs_and_penetrates() {
    let registries = Regolith::default().add_plugin(EllipsePlugin).registries();
    let file =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/impact_ellipse_coarse.ron");
    let (scene, _) = Scene::load(&file, &["time.end=0.02".to_string()], &registries).unwrap();
    let mut sim = Simulation::new(&scene);
    let start = sim.bodies()[1].1;
    assert!(
        (start.mass / 73.0 - 1.0).abs() < 1e-3,
        "mass {}",
        start.mass
    );
    sim.run(|_| {}).unwrap();
    let end = &sim.bodies()[1].1;
    assert!(
        end.centre_of_mass.y < start.centre_of_mass.y - 0.03,
        "no penetration"
    );
    assert!(
        end.velocity.y > start.velocity.y,
        "not decelerated by the bed"
    );
}
