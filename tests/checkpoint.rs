//! Checkpoint and resume: a resumed run is bitwise identical to an uninterrupted one.

mod common;

use regolith::checkpoint::Checkpoint;
use regolith::plugin::parse_scene;
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
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("checkpoint.bin");
    Checkpoint::capture(&mut first, &scene, "resume.ron", &[])
        .write(&path)
        .unwrap();
    drop(first);

    let mut resumed = Simulation::new(&scene);
    Checkpoint::read(&path)
        .unwrap()
        .restore(&mut resumed, &scene)
        .unwrap();
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
    let other = common::scene("elastic_bar_vibration", &[]);
    let mut wrong = Simulation::new(&other);
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
