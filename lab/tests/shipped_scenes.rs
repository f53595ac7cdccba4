//! Every shipped scene is valid: it parses, passes the whole-scene checks (including the CFL
//! check of a fixed time step) and builds a simulation. Running them is for their own tests
//! and the validation runs; this catches a scene broken by a format change. The same for
//! every run of the shipped sweeps and studies.

use regolith::{Regolith, Scene, Simulation};

#[test]
fn every_shipped_scene_loads_and_builds() {
    let registries = Regolith::default().registries();
    let paths = shipped("scenes");
    assert!(paths.len() >= 15, "only {} scenes found", paths.len());
    for path in paths {
        let (scene, _) = Scene::load(&path, &[], &registries).unwrap_or_else(|e| panic!("{e}"));
        let mut sim = Simulation::new(&scene);
        assert!(sim.particle_count() > 0, "{}: no points", path.display());
    }
}

/// The `.ron` files of a shipped directory, sorted.
fn shipped(dir: &str) -> Vec<std::path::PathBuf> {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join(dir);
    let mut paths: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "ron"))
        .collect();
    paths.sort();
    paths
}

/// Every run of every shipped sweep and study loads: the batch file parses, and its scene
/// accepts each run's overrides (a misspelt key or value would otherwise surface only when
/// that run starts, possibly hours into a batch).
#[test]
fn every_run_of_every_shipped_sweep_and_study_loads() {
    let registries = Regolith::default().registries();
    let mut checked = 0;
    let mut check = |batch: &std::path::Path, scene: &str, sets: &[String]| {
        // Resolved as `regolith sweep` and `regolith study` resolve it.
        let scene = regolith_lab::batch::beside(batch, scene);
        Scene::load(&scene, sets, &registries)
            .unwrap_or_else(|e| panic!("{}: {e}", batch.display()));
        checked += 1;
    };
    for path in shipped("sweeps") {
        let sweep = <regolith_lab::sweep::Sweep as regolith_lab::batch::BatchFile>::load(&path)
            .unwrap_or_else(|e| panic!("{e}"));
        for run in sweep.plan() {
            check(&path, &sweep.scene, &run.sets);
        }
    }
    for path in shipped("studies") {
        let study = <regolith_lab::study::Study as regolith_lab::batch::BatchFile>::load(&path)
            .unwrap_or_else(|e| panic!("{e}"));
        for run in study.plan().0 {
            check(&path, &study.scene, &run.sets);
        }
    }
    assert!(checked >= 30, "only {checked} runs checked");
}
