//! The driven-intruder plugin, through the public API alone: the body keeps its prescribed
//! velocity, the forces on it balance, the grains' resistance grows with depth, and bad
//! parameters are refused at their line.

use driven_intruder::{Drive, DrivenIntruderPlugin};
use regolith::glam::DVec2;
use regolith::{Regolith, Scene, Simulation};

const WEIGHT: f64 = 6500.0 * 0.011231 * 9.81; // the intruder's, N per metre of thickness
const SPEED: f64 = 0.5;

fn scene_file() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/driven_penetration_coarse.ron")
}

fn scene(sets: &[&str]) -> Result<Scene, regolith::error::SceneError> {
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    let registries = Regolith::default()
        .add_plugin(DrivenIntruderPlugin)
        .registries();
    Scene::load(&scene_file(), &sets, &registries).map(|(scene, _)| scene)
}

#[test]
fn the_driven_body_keeps_its_velocity_and_the_forces_on_it_balance() {
    let mut sim = Simulation::new(&scene(&[]).unwrap());
    let bottom = |sim: &mut Simulation| {
        let p = sim.points("intruder").unwrap();
        p.position.iter().map(|x| x.y).fold(f64::INFINITY, f64::min)
    };
    let start = bottom(&mut sim);
    let mut largest_imbalance: f64 = 0.0;
    let mut largest_contact: f64 = 0.0;
    for _ in 0..1500 {
        sim.step().unwrap();
        let drive = sim.world.resource::<Drive>();
        // F + m g + C = 0 for a body at constant velocity, to round-off.
        let imbalance = (drive.force + DVec2::new(0.0, -WEIGHT) + drive.contact).length();
        largest_imbalance = largest_imbalance.max(imbalance);
        largest_contact = largest_contact.max(drive.contact.length());
    }
    assert!(largest_contact > 0.5 * WEIGHT, "the tip reached the grains");
    assert!(
        largest_imbalance < 1e-6 * WEIGHT,
        "force imbalance {largest_imbalance} N/m"
    );
    let time = sim.clock().time;
    let v = DVec2::new(0.0, -SPEED);
    let points = sim.points("intruder").unwrap();
    let off = points
        .velocity
        .iter()
        .map(|u| (*u - v).length())
        .fold(0.0, f64::max);
    assert!(off < 1e-9 * SPEED, "a point's velocity is off by {off} m/s");
    let moved = start - bottom(&mut sim);
    assert!(
        (moved - SPEED * time).abs() < 1e-9,
        "moved {moved} m in {time} s"
    );
}

#[test]
fn the_grains_resist_more_the_deeper_the_tip() {
    // 0.4 s at 0.5 m/s: the tip 0.2 m deep. The static drag of the Poncelet law grows with
    // depth (docs/VALIDATION.md); single steps are noisy (grains stick and slip), so the
    // resistance is averaged over two depth bands.
    let mut sim = Simulation::new(&scene(&["time.end=0.4"]).unwrap());
    let (mut shallow, mut deep) = (Vec::new(), Vec::new());
    while !sim.finished() {
        sim.step().unwrap();
        let depth = SPEED * sim.clock().time;
        let resistance = sim.world.resource::<Drive>().contact.y;
        if (0.025..0.075).contains(&depth) {
            shallow.push(resistance);
        } else if (0.15..0.2).contains(&depth) {
            deep.push(resistance);
        }
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let (shallow, deep) = (mean(&shallow), mean(&deep));
    assert!(shallow > 0.0, "the grains push back: {shallow} N/m");
    assert!(
        deep > 1.5 * shallow,
        "resistance {deep} N/m at 15-20 cm against {shallow} N/m at 2.5-7.5 cm"
    );
}

#[test]
fn a_driven_body_must_exist_and_start_at_its_velocity() {
    let err = scene(&["conditions=[Driven(body: \"ball\", velocity: (0.0, -0.5))]"]).unwrap_err();
    assert!(
        err.message.contains("body \"ball\" is not in the scene"),
        "{}",
        err.message
    );
    let err =
        scene(&["conditions=[Driven(body: \"intruder\", velocity: (0.0, -1.0))]"]).unwrap_err();
    assert!(err.message.contains("give it the driven velocity"), "{err}");
    let err =
        scene(&["conditions=[Driven(body: \"intruder\", velocity: (0.0, NaN))]"]).unwrap_err();
    assert!(err.message.contains("velocity must be finite"), "{err}");
    let err = Scene::load(&scene_file(), &[], &Regolith::default().registries()).unwrap_err();
    assert!(err.message.contains("unknown condition `Driven`"), "{err}");
}
