//! Checkpoint and resume: a resumed run is bitwise identical to an uninterrupted one.

use regolith::checkpoint::Checkpoint;
use regolith::defaults::parse_scene;
use regolith::{Scene, Simulation};

/// A granular bed with an elastic disc falling into it, frictional contact: every kind of
/// state a step carries (points, phases, plastic strain, contact, two bodies).
fn scene() -> Scene {
    parse_scene(
        r#"(
        name: "resume",
        domain: (size: (0.3, 0.3), cells: (30, 30)),
        time: (end: 0.03, step: Cfl(0.5), output_every: 0.002),
        walls: (left: Slip, right: Slip, bottom: NoSlip, top: Free),
        contact: Frictional(friction: 0.1),
        outputs: [Snapshots(every: 0.01)],
        bodies: [
            (name: "bed", shape: Rectangle(min: (0.0, 0.0), max: (0.3, 0.15)),
             material: MuI(youngs_modulus: 2.0e7, poisson_ratio: 0.45, grain_density: 1280.0,
                 packing_fraction: 0.79, grain_diameter: 5.0e-3, mu_s: 0.32, mu_2: 0.598, i_0: 0.278),
             initial_stress: Lithostatic),
            (name: "disc", shape: Disc(centre: (0.15, 0.185), radius: 0.03), velocity: (0.0, -3.0),
             material: LinearElastic(density: 6500.0, youngs_modulus: 4e7, poisson_ratio: 0.45),
             tracked: true),
        ],
    )"#,
    )
    .unwrap()
}

fn bits(sim: &mut Simulation) -> Vec<u64> {
    let mut out = Vec::new();
    for name in ["bed", "disc"] {
        let p = sim.points(name).unwrap();
        for k in 0..p.len() {
            out.extend([
                p.position[k].x,
                p.position[k].y,
                p.velocity[k].x,
                p.velocity[k].y,
            ]);
            out.extend([
                p.volume[k],
                p.stress[k].xx,
                p.stress[k].yy,
                p.stress[k].xy,
                p.stress[k].zz,
            ]);
        }
    }
    out.iter().map(|v| v.to_bits()).collect()
}

#[test]
fn a_resumed_run_is_bitwise_identical() {
    let scene = scene();
    let mut straight = Simulation::new(&scene);
    straight.run(|_| {}).unwrap();

    let mut first = Simulation::new(&scene);
    for _ in 0..60 {
        first.step().unwrap();
    }
    let mut resumed = crate::common::checkpoint_and_restore(&mut first, &scene);
    drop(first);
    assert_eq!(resumed.clock().step, 60);
    resumed.run(|_| {}).unwrap();

    assert_eq!(resumed.clock().step, straight.clock().step);
    assert_eq!(bits(&mut resumed), bits(&mut straight), "the states differ");
    assert_eq!(resumed.trajectory().rows, straight.trajectory().rows);
}

#[test]
fn a_checkpoint_of_another_scene_is_refused() {
    let scene = scene();
    let mut sim = Simulation::new(&scene);
    sim.step().unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("checkpoint.bin");
    Checkpoint::capture(&mut sim, &scene, "resume.ron", &[])
        .write(&path)
        .unwrap();
    let other = crate::common::scene("elastic_bar_vibration", &[]);
    let mut wrong = Simulation::unobserved(&other);
    assert!(
        Checkpoint::read(&path)
            .unwrap()
            .restore(&mut wrong, &other)
            .is_err()
    );
    std::fs::write(&path, b"garbage").unwrap();
    let err = Checkpoint::read(&path).err().expect("garbage is refused");
    assert!(err.contains("not a regolith checkpoint"), "{err}");
}

/// A plugin's output that counts its records and does not say how to carry them.
#[derive(Clone, Debug, serde::Deserialize)]
struct Tally {}

#[derive(regolith::bevy_ecs::prelude::Resource, Default)]
struct Count(u64);

fn count(mut c: regolith::bevy_ecs::prelude::ResMut<Count>) {
    c.0 += 1;
}

impl regolith::registry::Item for Tally {
    const NAME: &'static str = "Tally";
}

impl regolith::output::Output for Tally {
    fn install(&self, sim: &mut regolith::plugin::Install) {
        sim.insert_resource(Count::default());
        sim.add_systems(regolith::step::StepSet::Output, count);
    }
}

struct TallyPlugin;

impl regolith::Plugin for TallyPlugin {
    fn build(&self, app: &mut regolith::Regolith) {
        app.register::<dyn regolith::output::Output, Tally>();
    }
}

/// Nothing silent (issue 35): an output that cannot carry its state over a resume, and one
/// first asked for at the resume, make the resumed run's summary say it is partial and why;
/// a run never interrupted is not.
#[test]
fn a_resume_past_an_output_without_state_is_marked_partial() {
    use regolith::run::{CheckpointEvery, Provenance, resume_run, run_scene};
    let registries = regolith::Regolith::default()
        .add_plugin(TallyPlugin)
        .registries();
    let text = r#"(
        name: "tally",
        domain: (size: (0.1, 0.1), cells: (10, 10)),
        time: (end: 2e-4, step: Fixed(2e-5), output_every: 1e-4),
        walls: (left: Slip, right: Slip, bottom: NoSlip, top: Free),
        bodies: [(name: "block", shape: Rectangle(min: (0.02, 0.02), max: (0.08, 0.08)),
                  material: LinearElastic(density: 1000.0, youngs_modulus: 1e6, poisson_ratio: 0.3))],
        outputs: [Tally()],
    )"#;
    let scene = Scene::parse(text, "tally.ron", &registries).unwrap();
    let from = Provenance {
        file: "tally.ron",
        text,
        overrides: &[],
    };
    let dir = tempfile::tempdir().unwrap();
    let summary = |d: &std::path::Path| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(d.join("summary.json")).unwrap()).unwrap()
    };
    let straight = dir.path().join("straight");
    run_scene(
        &scene,
        &from,
        &straight,
        CheckpointEvery(None),
        &mut |_: &regolith::resources::Clock| {},
    )
    .unwrap();
    assert_eq!(summary(&straight)["partial"], false);

    let cut = dir.path().join("cut");
    let stopped = run_scene(
        &scene,
        &from,
        &cut,
        CheckpointEvery(None),
        &mut regolith::run::StopAfter(4),
    );
    assert!(matches!(
        stopped,
        Err(regolith::error::Error::Interrupted { .. })
    ));
    let added = |scene: &mut Scene| {
        let more = Scene::parse(
            &text.replace(
                "outputs: [Tally()]",
                "outputs: [Tally(), Snapshots(every: 1e-4)]",
            ),
            "tally.ron",
            &registries,
        )?;
        scene.outputs = more.outputs;
        Ok(())
    };
    let mut quiet = |_: &regolith::resources::Clock| {};
    let resumed = resume_run(&registries, &cut, CheckpointEvery(None), added, &mut quiet).unwrap();
    let s = summary(&cut);
    assert_eq!(s["status"], "completed");
    assert_eq!(s["partial"], true);
    let why = s["partial_because"].as_array().unwrap();
    assert_eq!(why.len(), 2, "{why:?}");
    assert!(
        why[0]
            .as_str()
            .unwrap()
            .contains("the Tally output does not save its state"),
        "{why:?}"
    );
    assert!(
        why[1]
            .as_str()
            .unwrap()
            .contains("the Snapshots output was added when the run resumed"),
        "{why:?}"
    );
    assert!(
        resumed
            .headlines
            .iter()
            .any(|h| h.starts_with("PARTIAL: the Tally output"))
    );
}
