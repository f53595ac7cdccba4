//! A recording read back with rerun's own reader: the entity paths, the number of points per
//! frame, and logged values checked against the simulation that wrote them.

use std::collections::BTreeSet;
use std::path::Path;

use regolith::{Regolith, Scene, Simulation};
use regolith_rerun::RerunPlugin;
use rerun::log::Chunk;
use rerun::{ChunkStore, ChunkStoreConfig, StoreKind};

/// An intruder falling onto a small granular bed, recorded (with snapshots beside the
/// recording: outputs must be able to share the Output set).
fn scene(file: &Path, extra: &str) -> Scene {
    let text = format!(
        r#"(
        name: "recorded",
        domain: (size: (0.2, 0.2), cells: (20, 20)),
        time: (end: 0.01, step: Cfl(0.5), output_every: 0.002),
        walls: (left: Slip, right: Slip, bottom: NoSlip, top: Open),
        contact: Frictional(friction: 0.1, normal: Body("intruder")),
        bodies: [
            (name: "bed", shape: Rectangle(min: (0.0, 0.0), max: (0.2, 0.1)),
             material: MuI(youngs_modulus: 2.0e7, poisson_ratio: 0.45, grain_density: 1280.0,
                           packing_fraction: 0.79, grain_diameter: 5.0e-3,
                           mu_s: 0.320, mu_2: 0.598, i_0: 0.278),
             initial_stress: Lithostatic),
            (name: "intruder", shape: Disc(centre: (0.1, 0.13), radius: 0.02),
             material: LinearElastic(density: 6500.0, youngs_modulus: 4.0e7, poisson_ratio: 0.45),
             velocity: (0.0, -2.0), tracked: true),
        ],
        outputs: [Snapshots(every: 0.005), Rerun(file: {:?}{extra})],
    )"#,
        file.display().to_string()
    );
    Scene::parse(
        &text,
        "<test>",
        &Regolith::default().add_plugin(RerunPlugin).registries(),
    )
    .unwrap_or_else(|e| panic!("{e}"))
}

/// The chunks of the recording (not of its blueprint).
fn chunks(file: &Path) -> Vec<std::sync::Arc<Chunk>> {
    let mut reader = std::fs::File::open(file).unwrap();
    let stores = ChunkStore::from_rrd_reader(&ChunkStoreConfig::DEFAULT, &mut reader).unwrap();
    let (_, store) = stores
        .into_iter()
        .find(|(id, _)| id.kind() == StoreKind::Recording)
        .expect("a recording store");
    store.iter_physical_chunks().cloned().collect()
}

/// Every (sim_time, value) of the scalar series at `path`, in time order.
fn series(chunks: &[std::sync::Arc<Chunk>], path: &str) -> Vec<(f64, f64)> {
    let id = rerun::Scalars::descriptor_scalars().component;
    let mut out = Vec::new();
    for c in chunks
        .iter()
        .filter(|c| c.entity_path().to_string() == path)
    {
        let times = c.timelines()[&"sim_time".into()].times_raw().to_vec();
        for (t, v) in times
            .iter()
            .zip(c.iter_component::<rerun::components::Scalar>(id))
        {
            out.push((*t as f64 * 1e-9, v[0].0.0));
        }
    }
    out.sort_by(|a, b| a.0.total_cmp(&b.0));
    out
}

#[test]
fn a_recording_reads_back_with_its_entities_points_and_values() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("run.rrd");
    let scene = scene(&file, ", every: 20");
    let mut sim = Simulation::new(&scene);
    let counts: Vec<usize> = sim.bodies().iter().map(|b| b.2).collect();
    let start = sim.bodies()[1].1.centre_of_mass;
    sim.run(|_| {}).unwrap();
    let end = sim.bodies()[1].1.centre_of_mass;
    let steps = sim.clock().step;
    drop(sim);

    let chunks = chunks(&file);
    let paths: BTreeSet<String> = chunks.iter().map(|c| c.entity_path().to_string()).collect();
    for p in [
        "/world/bed/points",
        "/world/intruder/points",
        "/world/domain",
        "/plots/intruder/depth",
        "/plots/intruder/velocity/y",
        "/plots/intruder/contact_force/y",
        "/plots/bed/kinetic_energy",
        "/plots/time_step",
        "/scene",
    ] {
        assert!(paths.contains(p), "{p} missing from {paths:?}");
    }
    assert!(
        !paths.iter().any(|p| p.starts_with("/grid")),
        "grid recorded unasked"
    );

    // Every frame of each body has all its points, and a pressure per point.
    let positions = rerun::Points2D::descriptor_positions().component;
    for (name, n) in [("bed", counts[0]), ("intruder", counts[1])] {
        let path = format!("/world/{name}/points");
        let (mut frames, mut valued) = (0, 0);
        for c in chunks
            .iter()
            .filter(|c| c.entity_path().to_string() == path)
        {
            for batch in c.iter_component::<rerun::components::Position2D>(positions) {
                if !batch.is_empty() {
                    assert_eq!(batch.len(), n, "{name}: points per frame");
                    frames += 1;
                }
            }
            for batch in c.iter_component::<rerun::components::Scalar>("pressure".into()) {
                if !batch.is_empty() {
                    assert_eq!(batch.len(), n, "{name}: pressure values per frame");
                    valued += 1;
                }
            }
        }
        // t = 0, every 20th step, and the last step.
        let expected = 1 + steps / 20 + u64::from(!steps.is_multiple_of(20));
        assert_eq!(frames as u64, expected, "{name}: frames");
        assert_eq!(valued, frames, "{name}: frames with a pressure per point");
    }

    // The depth series starts at 0 and ends at the simulation's own displacement.
    let depth = series(&chunks, "/plots/intruder/depth");
    assert_eq!(depth.first().unwrap(), &(0.0, 0.0));
    let (t_end, last) = *depth.last().unwrap();
    assert!((t_end - 0.01).abs() < 1e-9, "last frame at {t_end}");
    assert!(
        (last - (start.y - end.y)).abs() < 1e-12,
        "recorded depth {last} vs {}",
        start.y - end.y
    );
    assert!(last > 0.0, "the intruder fell");
}

#[test]
fn grid_fields_are_recorded_when_asked() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("grid.rrd");
    let mut sim = Simulation::new(&scene(&file, ", grid: true, color: Phase"));
    sim.run(|_| {}).unwrap();
    drop(sim);
    let chunks = chunks(&file);
    let paths: BTreeSet<String> = chunks.iter().map(|c| c.entity_path().to_string()).collect();
    for p in [
        "/grid/bed/velocity",
        "/grid/bed/mass",
        "/grid/intruder/mass",
    ] {
        assert!(paths.contains(p), "{p} missing from {paths:?}");
    }
}

#[test]
fn an_unwritable_recording_stops_the_run_with_a_message() {
    let mut sim = Simulation::new(&scene(Path::new("/nonexistent/dir/run.rrd"), ""));
    let fault = sim.run(|_| {}).unwrap_err();
    assert!(
        fault.message.contains("cannot write the recording"),
        "{}",
        fault.message
    );
}
