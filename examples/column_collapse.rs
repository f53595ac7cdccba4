//! Runs the shipped granular column collapses and prints the table of docs/GRANULAR.md.
//!
//! ```text
//! cargo run --release --example column_collapse                 # the scenes as shipped (5 mm)
//! cargo run --release --example column_collapse -- 'domain.cells=(60, 30)' transfer=Flip
//! ```
//! Extra arguments are `--set`-style overrides applied to both scenes.

use regolith::body::{Phase, PointStates, Points};
use regolith::{Regolith, Scene, Simulation};

/// What the table reports about one moment of a run.
struct Measure {
    runout: f64,
    height: f64,
    rms_speed: f64,
    disconnected: f64,
}

fn measure(sim: &mut Simulation) -> Measure {
    let mut q = sim.world.query::<(&Points, &PointStates)>();
    let (p, s) = q.single(&sim.world).expect("one body");
    let mass: f64 = p.mass.iter().sum();
    let ke: f64 = (0..p.len())
        .map(|k| 0.5 * p.mass[k] * p.velocity[k].length_squared())
        .sum();
    Measure {
        runout: p.position.iter().map(|x| x.x).fold(0.0, f64::max),
        height: p.position.iter().map(|x| x.y).fold(0.0, f64::max),
        rms_speed: (2.0 * ke / mass).sqrt(),
        disconnected: s
            .phase
            .iter()
            .filter(|ph| **ph == Phase::Disconnected)
            .count() as f64
            / s.phase.len() as f64,
    }
}

fn main() {
    let sets: Vec<String> = std::env::args().skip(1).collect();
    let registries = Regolith::default().registries();
    println!(
        "| scene | cells | points | runout (m) | final height (m) | rms speed at end (m/s) | peak disconnected | disconnected at end | wall (s) |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    for name in [
        "granular_column_collapse_a05",
        "granular_column_collapse_a2",
    ] {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("scenes")
            .join(format!("{name}.ron"));
        let (scene, _) = match Scene::load(&path, &sets, &registries) {
            Ok(s) => s,
            Err(e) => {
                eprintln!("error: {e}");
                std::process::exit(1);
            }
        };
        let mut sim = Simulation::new(&scene);
        let started = std::time::Instant::now();
        let mut peak: f64 = 0.0;
        let mut next = 0.0;
        while !sim.finished() {
            if let Err(e) = sim.step() {
                eprintln!("{name}: {e}");
                break;
            }
            if sim.clock().time >= next {
                next += 0.01;
                peak = peak.max(measure(&mut sim).disconnected);
            }
        }
        let m = measure(&mut sim);
        println!(
            "| {name} | {} x {} | {} | {:.3} | {:.3} | {:.4} | {:.3} | {:.3} | {:.0} |",
            scene.domain.cells.0,
            scene.domain.cells.1,
            sim.particle_count(),
            m.runout,
            m.height,
            m.rms_speed,
            peak,
            m.disconnected,
            started.elapsed().as_secs_f64()
        );
    }
}
