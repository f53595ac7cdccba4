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

/// The chunks of the recording's store of `kind` (the recording or its blueprint).
fn store_chunks(file: &Path, kind: StoreKind) -> Vec<std::sync::Arc<Chunk>> {
    let mut reader = std::fs::File::open(file).unwrap();
    let stores = ChunkStore::from_rrd_reader(&ChunkStoreConfig::DEFAULT, &mut reader).unwrap();
    let (_, store) = stores
        .into_iter()
        .find(|(id, _)| id.kind() == kind)
        .unwrap_or_else(|| panic!("no {kind:?} store"));
    store.iter_physical_chunks().cloned().collect()
}

/// The chunks of the recording (not of its blueprint).
fn chunks(file: &Path) -> Vec<std::sync::Arc<Chunk>> {
    store_chunks(file, StoreKind::Recording)
}

/// Every value of the float column `component` logged at `path`, one list per frame.
fn columns(chunks: &[std::sync::Arc<Chunk>], path: &str, component: &'static str) -> Vec<Vec<f64>> {
    let mut out = Vec::new();
    for c in chunks
        .iter()
        .filter(|c| c.entity_path().to_string() == path)
    {
        for batch in c.iter_component::<rerun::components::Scalar>(component.into()) {
            if !batch.is_empty() {
                out.push(batch.iter().map(|v| v.0.0).collect());
            }
        }
    }
    out
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

/// Runs the test scene with the recorder's extra parameters `extra` and returns the file
/// (with the directory that holds it) and the recording's chunks.
fn record(
    extra: &str,
) -> (
    tempfile::TempDir,
    std::path::PathBuf,
    Vec<std::sync::Arc<Chunk>>,
) {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("run.rrd");
    let mut sim = Simulation::new(&scene(&file, extra));
    sim.run(|_| {}).unwrap();
    drop(sim);
    let chunks = chunks(&file);
    (dir, file, chunks)
}

#[test]
fn grid_fields_are_recorded_when_asked() {
    let (_dir, _, chunks) = record(", grid: true, color: Phase");
    let paths: BTreeSet<String> = chunks.iter().map(|c| c.entity_path().to_string()).collect();
    for p in [
        "/grid/bed/velocity",
        "/grid/bed/mass",
        "/grid/intruder/mass",
    ] {
        assert!(paths.contains(p), "{p} missing from {paths:?}");
    }
    assert_eq!(
        scales(&chunks, "/grid"),
        vec![[1.0, -1.0, 1.0]],
        "the grid's y mirror"
    );
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

/// The scales of the `Transform3D`s logged at `path`.
fn scales(chunks: &[std::sync::Arc<Chunk>], path: &str) -> Vec<[f32; 3]> {
    let scale = rerun::Transform3D::descriptor_scale().component;
    chunks
        .iter()
        .filter(|c| c.entity_path().to_string() == path)
        .flat_map(|c| {
            c.iter_component::<rerun::components::Scale3D>(scale)
                .flat_map(|b| b.iter().map(|s| s.0.0).collect::<Vec<_>>())
                .collect::<Vec<_>>()
        })
        .collect()
}

/// The view must show the bed at the bottom: Rerun's 2D space has y down, so the spatial
/// roots carry a mirror in y; the layout is sent as the active blueprint; and each body's
/// colours are scaled by its own values, with the legend saying the scale.
#[test]
fn the_world_view_is_y_up_with_an_active_layout_and_a_scale_per_body() {
    let (_dir, file, chunks) = record(", every: 20");

    assert_eq!(
        scales(&chunks, "/world"),
        vec![[1.0, -1.0, 1.0]],
        "the y mirror"
    );
    let layout = store_chunks(&file, StoreKind::Blueprint);
    assert!(!layout.is_empty(), "the layout is sent with the recording");
    // The viewer opens on simulated seconds, paused, so the plots show the whole run (left
    // to follow the newest data on the `step` timeline they showed its last frames only).
    let panel: Vec<String> = layout
        .iter()
        .filter(|c| c.entity_path().to_string().contains("time_panel"))
        .map(|c| format!("{c}"))
        .collect();
    let paused = format!(
        "[{}]",
        regolith_rerun::rerun::blueprint::components::PlayState::Paused as u8
    );
    assert!(
        panel.len() == 1 && panel[0].contains("[sim_time]") && panel[0].contains(&paused),
        "time panel: {panel:?}"
    );

    // Each legend bar's top is its own body's 99th percentile of the recorded pressures.
    let bed = columns(&chunks, "/world/bed/points", "pressure");
    let disc = columns(&chunks, "/world/intruder/points", "pressure");
    let bed_top = columns(&chunks, "/world/legend/bed/bar", "scale_top");
    let disc_top = columns(&chunks, "/world/legend/intruder/bar", "scale_top");
    assert_eq!(bed_top.len(), bed.len(), "a bed legend per frame");
    assert_eq!(disc_top.len(), disc.len(), "an intruder legend per frame");
    let percentile =
        |v: &[f64]| regolith_rerun::upper_percentile(v.iter().copied(), &mut Vec::new());
    for (values, top) in bed.iter().zip(&bed_top) {
        assert_eq!(top, &vec![percentile(values)], "bed scale");
    }
    let last = bed.len() - 1;
    assert_ne!(
        bed_top[last], disc_top[last],
        "the intruder's pressures set their own scale"
    );
}

/// Issue 35: a recording interrupted twice and resumed reads back as the uninterrupted one,
/// one recording with every frame once: the same series (the depth and acceleration
/// included, which difference against the first and the last frame) and the same points.
#[test]
fn a_recording_resumed_twice_reads_back_as_the_uninterrupted_one() {
    use regolith::checkpoint::Checkpoint;
    let dir = tempfile::tempdir().unwrap();
    let (straight, resumed) = (
        dir.path().join("straight.rrd"),
        dir.path().join("resumed.rrd"),
    );
    let mut sim = Simulation::new(&scene(&straight, ", every: 7"));
    sim.run(|_| {}).unwrap();
    let steps = sim.clock().step;
    drop(sim);

    let scene = scene(&resumed, ", every: 7");
    let saved = dir.path().join("checkpoint.bin");
    let mut sim = Simulation::new(&scene);
    for stop in [steps / 3, 2 * steps / 3] {
        while sim.clock().step < stop {
            sim.step().unwrap();
        }
        // A few frames logged after the checkpoint, as by a run killed later: the resumed
        // run drops them from the file and logs them again.
        Checkpoint::capture(&mut sim, &scene, "<test>", &[])
            .write(&saved)
            .unwrap();
        for _ in 0..9 {
            sim.step().unwrap();
        }
        drop(sim);
        sim = Simulation::unobserved(&scene);
        Checkpoint::read(&saved)
            .unwrap()
            .restore(&mut sim, &scene)
            .unwrap();
    }
    sim.run(|_| {}).unwrap();
    drop(sim);

    let (a, b) = (chunks(&straight), chunks(&resumed));
    for path in [
        "/plots/intruder/depth",
        "/plots/intruder/velocity/y",
        "/plots/intruder/acceleration/y",
        "/plots/intruder/contact_force/y",
        "/plots/bed/kinetic_energy",
        "/plots/time_step",
    ] {
        let (x, y) = (series(&a, path), series(&b, path));
        assert!(x.len() > 5, "{path}: {} values", x.len());
        assert_eq!(x, y, "{path} differs after two resumes");
    }
    for path in ["/world/bed/points", "/world/intruder/points"] {
        assert_eq!(
            columns(&a, path, "pressure"),
            columns(&b, path, "pressure"),
            "{path}: the pressures per frame differ"
        );
    }
}
