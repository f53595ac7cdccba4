//! The `Vtk` output across an interruption: a resumed run lists each frame once, with the
//! frames the first part wrote, and writes the same files as a run never interrupted.
//! (The files' contents are checked against an independent reader, the `vtk` Python
//! package, in python/tests.)

use std::path::Path;

use regolith::Simulation;
use regolith::checkpoint::Checkpoint;
use regolith::output::vtk::{FOLDER, POINTS_COLLECTION, read_collection};

fn collection(dir: &Path) -> Vec<regolith::output::vtk::Entry> {
    let text = std::fs::read_to_string(dir.join(FOLDER).join(POINTS_COLLECTION)).unwrap();
    read_collection(&text)
}

#[test]
fn a_resumed_run_lists_every_frame_once_and_writes_the_same_files() {
    let scene = crate::common::scene(
        "impact_tipped_coarse",
        &["time.end=0.01", "outputs=[Vtk(every: 0.002)]"],
    );
    let straight = tempfile::tempdir().unwrap();
    let mut sim = Simulation::with_output(&scene, straight.path()).unwrap();
    sim.run(|_| {}).unwrap();
    let expected = collection(straight.path());
    // t = 0, 0.002, ..., 0.01 for two bodies
    assert_eq!(expected.len(), 12, "{expected:?}");

    let split = tempfile::tempdir().unwrap();
    let mut first = Simulation::with_output(&scene, split.path()).unwrap();
    while first.clock().time < 0.005 {
        first.step().unwrap();
    }
    let checkpoint = Checkpoint::capture(&mut first, &scene, "impact.ron", &[]);
    drop(first);
    assert_eq!(
        collection(split.path()).len(),
        6,
        "frames at 0, 0.002, 0.004"
    );
    // in the order `regolith resume` takes: restore, then reopen the run's files
    let mut resumed = Simulation::unobserved(&scene);
    checkpoint.restore(&mut resumed, &scene).unwrap();
    resumed.write_to(split.path()).unwrap();
    resumed.run(|_| {}).unwrap();

    assert_eq!(collection(split.path()), expected);
    for entry in &expected {
        let read = |dir: &Path| std::fs::read(dir.join(FOLDER).join(&entry.file)).unwrap();
        assert!(
            read(split.path()) == read(straight.path()),
            "{} differs",
            entry.file
        );
    }
}
