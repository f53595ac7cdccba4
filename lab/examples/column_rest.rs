//! Granular columns collapse and come to rest (the dense-flow issue's item 4; docs/GRANULAR.md,
//! "Column collapse"): PS-1 columns of width `L0 = 0.1 m` and aspect ratios `a = H0 / L0`
//! released against a frictionless wall onto a rough floor, from the shipped a = 2 scene with
//! its shape, box and end time changed, at the default numerics unless `--set` says
//! otherwise. Reports when the column came to rest (95% of its points below
//! 1 cm/s from then on) against `5 sqrt(H0 / g)`, the runout `(Lf - L0) / L0` against
//! quasi-2D experiments (Lube et al. 2005: `1.2 a` below a = 1.8, `1.9 a^(2/3)` above) and
//! the disconnected fraction at the end.
//!
//! ```text
//! cargo run --release -p regolith-lab --example column_rest -- ASPECTS CELL [--set k=v]...
//! cargo run --release -p regolith-lab --example column_rest -- 0.5,1,2,4 0.01
//! cargo run --release -p regolith-lab --example column_rest -- 0.5,1,2,4 0.005 --set transfer=Apic
//! ```

use regolith::body::{Phase, PointStates, Points};
use regolith::{Regolith, Scene, Simulation};
use regolith_lab::verify::quantile;

const WIDTH: f64 = 0.1;
const REST_SPEED: f64 = 0.01;

fn lube(a: f64) -> f64 {
    if a < 1.8 {
        1.2 * a
    } else {
        1.9 * a.powf(2.0 / 3.0)
    }
}

/// The 95th percentile of the point speeds.
fn speed_95(p: &Points) -> f64 {
    quantile(p.velocity.iter().map(|v| v.length()).collect(), 0.95)
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() < 2 {
        eprintln!("usage: column_rest ASPECTS CELL [--set k=v]...");
        std::process::exit(2);
    }
    let number = |s: &str| -> f64 { s.parse().unwrap_or_else(|_| panic!("not a number: {s}")) };
    let aspects: Vec<f64> = args[0].split(',').map(number).collect();
    let cell = number(&args[1]);
    let extra: Vec<String> = args
        .windows(2)
        .filter(|w| w[0] == "--set")
        .map(|w| w[1].clone())
        .collect();
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../scenes/granular_column_collapse_a2.ron");
    println!(
        "| a | cells | points | at rest (s) | 5 sqrt(H0/g) (s) | runout (Lf-L0)/L0 | Lube et al. | final height / H0 | disconnected at end | wall (s) |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|");
    for &a in &aspects {
        let height = a * WIDTH;
        let t_scale = 5.0 * (height / 9.81).sqrt();
        let end = (t_scale + 0.5).max(1.0);
        let size = (0.3 + 0.2 * a, height + 0.05);
        let cells = (
            (size.0 / cell).round() as usize,
            (size.1 / cell).round() as usize,
        );
        let size = (cells.0 as f64 * cell, cells.1 as f64 * cell);
        let mut sets = vec![
            format!(
                "domain=(size: ({}, {}), cells: ({}, {}))",
                size.0, size.1, cells.0, cells.1
            ),
            format!("bodies.column.shape=Rectangle(min: (0.0, 0.0), max: ({WIDTH}, {height}))"),
            format!("time.end={end}"),
        ];
        sets.extend(extra.iter().cloned());
        let (scene, _) = Scene::load(&path, &sets, &Regolith::default().registries())
            .unwrap_or_else(|e| {
                eprintln!("error: {e}");
                std::process::exit(1);
            });
        let mut sim = Simulation::new(&scene);
        let started = std::time::Instant::now();
        let (mut next, mut moving_until) = (0.0, 0.0);
        while !sim.finished() {
            if let Err(e) = sim.step() {
                eprintln!("a = {a}: {e}");
                break;
            }
            let t = sim.clock().time;
            if t >= next {
                next += 0.01;
                if speed_95(sim.points("column").unwrap()) >= REST_SPEED {
                    moving_until = t;
                }
            }
        }
        let mut q = sim.world.query::<(&Points, &PointStates)>();
        let (p, s) = q.single(&sim.world).expect("one body");
        let runout = p.position.iter().map(|x| x.x).fold(0.0, f64::max);
        let top = p.position.iter().map(|x| x.y).fold(0.0, f64::max);
        let gas = s
            .phase
            .iter()
            .filter(|f| **f == Phase::Disconnected)
            .count();
        let rest = if speed_95(p) < REST_SPEED {
            format!("{moving_until:.2}")
        } else {
            format!("not by {end:.2}")
        };
        println!(
            "| {a} | {} x {} | {} | {rest} | {t_scale:.2} | {:.2} | {:.2} | {:.3} | {:.3} | {:.0} |",
            cells.0,
            cells.1,
            p.len(),
            (runout - WIDTH) / WIDTH,
            lube(a),
            top / height,
            gas as f64 / p.len() as f64,
            started.elapsed().as_secs_f64()
        );
    }
}
