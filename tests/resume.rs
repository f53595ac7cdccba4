//! Every shipped scene, interrupted twice and resumed, leaves the files an uninterrupted run
//! leaves (issue 35: a resumed `PressureFront` restarted its record and reported another
//! front speed, with `"status": "completed"`). The plugins' scenes are checked in their own
//! crates with the same helper.

#[path = "common/resume.rs"]
mod resume;

use regolith::Regolith;

/// Particle-steps each scene runs for (its end time is cut to where they run out), so the
/// suite stays under a minute; `REGOLITH_RESUME_BUDGET` raises it for a longer check.
fn budget() -> f64 {
    std::env::var("REGOLITH_RESUME_BUDGET")
        .ok()
        .and_then(|b| b.parse().ok())
        .unwrap_or(1.5e6)
}

#[test]
fn every_shipped_scene_resumed_twice_leaves_the_files_of_a_straight_run() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let registries = Regolith::default().registries();
    let scenes = resume::check_scenes(&dir, &registries, budget());
    assert!(scenes >= 18, "{scenes} scenes");
}

/// The case of issue 35 in full: the coarse force-propagation scene to its end, where the
/// pressure front crosses every bin, interrupted twice.
#[test]
fn a_pressure_front_resumed_twice_is_the_uninterrupted_front() {
    let scene = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join("force_propagation_coarse.ron");
    let registries = Regolith::default().registries();
    let (steps, _) = resume::check(&scene, &registries, None);
    assert!(steps > 100, "{steps} steps");
}
