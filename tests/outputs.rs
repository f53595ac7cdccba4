//! Every built-in output can run in one scene: outputs share the Output set without an
//! ordering between them, so none may take exclusive access to a shared resource (this
//! once stopped a scene with two file-writing outputs before its first step).

mod common;

use regolith::Simulation;

#[test]
fn all_built_in_outputs_run_together_and_write_their_files() {
    let dir = tempfile::tempdir().unwrap();
    let scene = common::scene(
        "flow_field_coarse",
        &[
            "time.end=0.01",
            "outputs=[Impact(body: \"disc\", surface: 0.6825), \
             FlowField(body: \"bed\", intruder: \"disc\", scale: 0.127, at: [0.005]), \
             FreeSurface(body: \"bed\", every: 0.005), Snapshots(every: 0.005), \
             PressureFront(body: \"bed\", centre: (0.455, 0.6825), radius: 0.2, bins: 4, every: 0.002)]",
        ],
    );
    let mut sim = Simulation::with_output(&scene, dir.path()).unwrap();
    sim.run(|_| {}).unwrap();
    for f in [
        "flow_field_0.csv",
        "free_surface.csv",
        "pressure_front.csv",
        "snapshots/snapshot_00000.csv",
    ] {
        assert!(dir.path().join(f).exists(), "{f} not written");
    }
}

/// An output that cannot write stops the run with the reason, whichever output it is.
#[test]
fn an_output_that_cannot_write_stops_the_run() {
    let dir = tempfile::tempdir().unwrap();
    let scene = common::scene(
        "flow_field_coarse",
        &[
            "time.end=0.01",
            "outputs=[FreeSurface(body: \"bed\", every: 0.005)]",
        ],
    );
    std::fs::create_dir(dir.path().join("free_surface.csv")).unwrap();
    let mut sim = Simulation::with_output(&scene, dir.path()).unwrap();
    let fault = sim.run(|_| {}).unwrap_err();
    assert!(
        fault.message.contains("free_surface.csv"),
        "{}",
        fault.message
    );
}

/// The free surface is the bed's top at rest (to the one-cell resolution of the measure) and
/// drops under the disc as it enters.
#[test]
fn the_free_surface_starts_flat_and_opens_under_the_disc() {
    use regolith::free_surface::SurfaceRecord;
    let scene = common::scene(
        "flow_field_coarse",
        &[
            "time.end=0.02",
            "outputs=[FreeSurface(body: \"bed\", every: 0.01)]",
        ],
    );
    let mut sim = Simulation::new(&scene);
    let h = sim.grid().cell_size;
    sim.run(|_| {}).unwrap();
    let record = sim.world.get_resource::<SurfaceRecord>().unwrap();
    assert_eq!(record.times.len(), 3);
    for z in &record.heights[0] {
        assert!((z - 0.6825).abs() <= h, "surface at {z} m at rest");
    }
    let last = &record.heights[2];
    let centre = last[last.len() / 2];
    assert!(
        centre < 0.6825 - 2.0 * h,
        "surface under the disc at {centre} m"
    );
    assert!(
        (last[0] - 0.6825).abs() <= h,
        "far surface moved to {} m",
        last[0]
    );
}
