//! How an impact's waves move a bed (docs/numerics.md, "The impact bulks the bed"): every
//! `every` seconds, the kinetic energy of each body and, for each granular body, its
//! disconnected fraction and the motion of its far surface (the points in the tenth of its
//! width farthest left, within two cells of their top).
//!
//! ```text
//! cargo run --release --example impact_bulking -- SCENE END EVERY [--set k=v]...
//! cargo run --release --example impact_bulking -- flow_field_coarse 0.03 0.0005
//! ```
//! `SCENE` is a shipped scene's name or a path. The header gives the granular body's p-wave
//! speed and round trip `2 H / c`: the wave the floor reflects lifts the far surface then.

use regolith::body::{Body, Phase, PointStates, Points};
use regolith::{Regolith, Scene, Simulation};

/// The far surface of a granular body: the points with `x < x_far` within `band` of their
/// highest; its height and mean vertical velocity.
fn far_surface(p: &Points, x_far: f64, band: f64) -> (f64, f64) {
    let far: Vec<usize> = (0..p.len()).filter(|&k| p.position[k].x < x_far).collect();
    let top = far
        .iter()
        .map(|&k| p.position[k].y)
        .fold(f64::NEG_INFINITY, f64::max);
    let surface: Vec<usize> = far
        .into_iter()
        .filter(|&k| p.position[k].y > top - band)
        .collect();
    let vy = surface.iter().map(|&k| p.velocity[k].y).sum::<f64>() / surface.len() as f64;
    (top, vy)
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() < 3 {
        eprintln!("usage: impact_bulking SCENE END EVERY [--set k=v]...");
        std::process::exit(2);
    }
    let mut path = std::path::PathBuf::from(&args[0]);
    if !path.exists() {
        path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("scenes")
            .join(format!("{}.ron", args[0]));
    }
    let number = |s: &str| -> f64 { s.parse().unwrap_or_else(|_| panic!("not a number: {s}")) };
    let (end, every) = (number(&args[1]), number(&args[2]));
    let mut sets: Vec<String> = args
        .windows(2)
        .filter(|w| w[0] == "--set")
        .map(|w| w[1].clone())
        .collect();
    sets.push(format!("time.end={end}"));
    let (scene, _) =
        Scene::load(&path, &sets, &Regolith::default().registries()).unwrap_or_else(|e| {
            eprintln!("error: {e}");
            std::process::exit(1);
        });
    let mut sim = Simulation::new(&scene);
    let band = 2.0 * sim.grid().cell_size;
    // Far column and header from the starting state.
    let mut far = Vec::new();
    {
        let mut q = sim.world.query::<(&Body, &Points)>();
        for (b, p) in q.iter(&sim.world) {
            if b.inertial_scale.is_none() {
                continue;
            }
            let (lo, hi) = p
                .position
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |a, x| {
                    (a.0.min(x.x), a.1.max(x.x))
                });
            let depth = p.position.iter().map(|x| x.y).fold(0.0, f64::max);
            println!(
                "{}: p-wave speed {:.1} m/s, 2 H / c = {:.3e} s (H = {depth:.4} m to the highest point)",
                b.name,
                b.wave_speed,
                2.0 * depth / b.wave_speed
            );
            far.push((b.name.clone(), lo + 0.1 * (hi - lo)));
        }
    }
    let mut next = 0.0;
    loop {
        if sim.clock().time >= next - 1e-12 || sim.finished() {
            next += every;
            let mut row = format!("| {:.4} |", sim.clock().time);
            let mut q = sim.world.query::<(&Body, &Points, &PointStates)>();
            for (b, p, s) in q.iter(&sim.world) {
                let ke: f64 = (0..p.len())
                    .map(|k| 0.5 * p.mass[k] * p.velocity[k].length_squared())
                    .sum();
                row += &format!(" {}: KE {ke:.2} J/m", b.name);
                if let Some((_, x_far)) = far.iter().find(|(n, _)| *n == b.name) {
                    let gas = s
                        .phase
                        .iter()
                        .filter(|f| **f == Phase::Disconnected)
                        .count();
                    let (top, vy) = far_surface(p, *x_far, band);
                    row += &format!(
                        ", disconnected {:.3}, far top {top:.4} m, far v_y {vy:+.3} m/s",
                        gas as f64 / p.len() as f64
                    );
                }
                row += " |";
            }
            println!("{row}");
        }
        if sim.finished() {
            break;
        }
        if let Err(e) = sim.step() {
            eprintln!("stopped: {e}");
            std::process::exit(1);
        }
    }
}
