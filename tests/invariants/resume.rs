//! Every shipped scene, interrupted twice and resumed, leaves the files an uninterrupted run
//! leaves (issue 35: a resumed `PressureFront` restarted its record and reported another
//! front speed, with `"status": "completed"`). The plugins' scenes are checked in their own
//! crates with the same helper.

use crate::resume_check as resume;

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

/// A nonlocal-fluidity run (the chute with `Nonlocal` for `MuI`) resumed twice is bitwise the
/// run never interrupted, on one thread and on two: the fluidity is carried in the body's
/// field columns (`fluidity`, `fluidity_seeded`), which the checkpoint saves by name, and the
/// nodal field is rebuilt from them every step (issues 49 and 50).
#[test]
fn a_nonlocal_fluidity_run_resumed_twice_is_the_uninterrupted_run() {
    let scenes = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let text = std::fs::read_to_string(scenes.join("chute_flow_mui.ron")).unwrap();
    assert!(text.contains("material: MuI("));
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("chute_nonlocal.ron");
    std::fs::write(&file, text.replace("material: MuI(", "material: Nonlocal(")).unwrap();
    let registries = Regolith::default().registries();
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let (steps, files) = pool.install(|| resume::check(&file, &registries, Some(budget())));
        assert!(
            steps > 100 && files > 2,
            "{threads} threads: {steps} steps, {files} files"
        );
    }
}
