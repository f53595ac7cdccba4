//! The plugin's shipped scenes, interrupted twice and resumed, leave the files an
//! uninterrupted run leaves (the engine's helper: tests/common/resume.rs).

#[path = "../../../tests/common/resume.rs"]
mod resume;

use bingham_material::BinghamPlugin;
use regolith::Regolith;

#[test]
fn every_scene_of_the_plugin_resumed_twice_leaves_the_files_of_a_straight_run() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let registries = Regolith::default().add_plugin(BinghamPlugin).registries();
    assert!(resume::check_scenes(&dir, &registries, 1.5e6) > 0);
}
