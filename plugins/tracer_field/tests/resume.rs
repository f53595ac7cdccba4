//! The plugin's shipped scenes, interrupted twice and resumed, leave the files an
//! uninterrupted run leaves (the engine's helper: tests/common/resume.rs): the tracer's
//! column is carried by the checkpoint, and the VTK frames written after the resume show it.

#[path = "../../../tests/common/resume.rs"]
mod resume;

use regolith::Regolith;
use tracer_field::TracerPlugin;

#[test]
fn every_scene_of_the_plugin_resumed_twice_leaves_the_files_of_a_straight_run() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let registries = Regolith::default().add_plugin(TracerPlugin).registries();
    assert!(resume::check_scenes(&dir, &registries, 1.5e6) > 0);
}

/// The same with a VTK frame every 2 ms, so that frames written after each resume show the
/// tracer carried through the checkpoint (it fails if the checkpoint drops the column: the
/// resumed run's tracer would start again from its marked shape).
#[test]
fn the_tracer_comes_back_from_a_checkpoint_bit_for_bit() {
    let shipped =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/dye_in_collapse.ron");
    let text = std::fs::read_to_string(&shipped).unwrap();
    assert!(text.contains("Vtk(every: 0.05)"));
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("dye_often.ron");
    std::fs::write(&file, text.replace("Vtk(every: 0.05)", "Vtk(every: 0.002)")).unwrap();
    let registries = Regolith::default().add_plugin(TracerPlugin).registries();
    let (steps, files) = resume::check(&file, &registries, Some(1.5e6));
    assert!(steps > 100 && files > 4, "{steps} steps, {files} files");
}
