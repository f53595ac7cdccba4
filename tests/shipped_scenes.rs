//! Every shipped scene is valid: it parses, passes the whole-scene checks (including the CFL
//! check of a fixed time step) and builds a simulation. Running them is for their own tests
//! and the validation runs; this catches a scene broken by a format change.

use regolith::{Regolith, Scene, Simulation};

#[test]
fn every_shipped_scene_loads_and_builds() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let registries = Regolith::default().registries();
    let mut paths: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "ron"))
        .collect();
    paths.sort();
    assert!(paths.len() >= 15, "only {} scenes found", paths.len());
    for path in paths {
        let (scene, _) = Scene::load(&path, &[], &registries).unwrap_or_else(|e| panic!("{e}"));
        let mut sim = Simulation::new(&scene);
        assert!(sim.particle_count() > 0, "{}: no points", path.display());
    }
}
