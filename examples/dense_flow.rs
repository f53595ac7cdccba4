//! The long dense-flow validation (docs/VALIDATION.md, "Steady chute flow"): the shipped
//! chute scene at several angles and resolutions, started in its lithostatic state and
//! moving with the analytic mu(I) profile where there is one, measured every `every`
//! seconds against that profile.
//!
//! ```text
//! cargo run --release --example dense_flow -- ANGLES CELLS_PER_DEPTH END [EVERY] [--set k=v]...
//! cargo run --release --example dense_flow -- 20,25,28 10,20 25 1
//! ```
//! Prints one row per moment (top, volume ratio, disconnected fractions, mean speed,
//! profile error) and a last row per run; every run is at the default numerical settings
//! unless `--set` says otherwise.

use regolith::body::{PointStates, Points};
use regolith::verify::chute::{Bagnold, ChuteState, measure, ps1, start_steady};
use regolith::{Regolith, Scene, Simulation};

const DEPTH: f64 = 0.1;

fn list(arg: &str) -> Vec<f64> {
    arg.split(',')
        .map(|s| s.parse().unwrap_or_else(|_| panic!("not a number: {s}")))
        .collect()
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() < 3 {
        eprintln!("usage: dense_flow ANGLES CELLS_PER_DEPTH END [EVERY] [--set k=v]...");
        std::process::exit(2);
    }
    let (angles, resolutions, end) = (list(&args[0]), list(&args[1]), list(&args[2])[0]);
    let every = args
        .get(3)
        .filter(|a| !a.starts_with("--"))
        .map_or(1.0, |a| list(a)[0]);
    let extra: Vec<String> = args
        .windows(2)
        .filter(|w| w[0] == "--set")
        .map(|w| w[1].clone())
        .collect();
    let material = ps1();
    println!(
        "| angle | cells/depth | t (s) | top/H | sum V / area | disconnected (bulk) | mean speed (analytic) m/s | profile rms / u_s | 95% speed (m/s) | wall (s) |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|");
    for &deg in &angles {
        for &per_depth in &resolutions {
            let th = deg.to_radians();
            let gravity = regolith::glam::DVec2::new(9.81 * th.sin(), -9.81 * th.cos());
            let across = (per_depth / 2.0).round() as usize;
            let mut sets = vec![
                format!("gravity=({}, {})", gravity.x, gravity.y),
                format!("domain.cells=({across}, {})", 3 * across),
                format!("time.end={end}"),
            ];
            sets.extend(extra.iter().cloned());
            let path =
                std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/chute_flow.ron");
            let scene = match Scene::load(&path, &sets, &Regolith::default().registries()) {
                Ok((s, _)) => s,
                Err(e) => {
                    eprintln!("error: {e}");
                    std::process::exit(1);
                }
            };
            let profile = Bagnold::new(&material, th, DEPTH, 9.81);
            let mut sim = Simulation::new(&scene);
            let cell = sim.grid().cell_size;
            start_steady(
                &mut sim.points_mut("layer").unwrap(),
                &material,
                gravity,
                DEPTH,
                profile.as_ref(),
            );
            let started = std::time::Instant::now();
            let mut next = 0.0;
            let row = |sim: &mut Simulation, last: bool| {
                let mut q = sim.world.query::<(&Points, &PointStates)>();
                let (p, s) = q.single(&sim.world).expect("one body");
                let m: ChuteState = measure(p, s, scene.domain.size.x, cell, profile.as_ref());
                let analytic = profile.as_ref().map_or(f64::NAN, |b| b.mean_speed());
                println!(
                    "| {deg}{} | {per_depth} | {:.2} | {:.4} | {:.5} | {:.3} ({:.3}) | {:.3} ({:.3}) | {} | {:.4} | {:.0} |",
                    if last { " (end)" } else { "" },
                    sim.clock().time,
                    m.top / DEPTH,
                    m.volume_ratio,
                    m.disconnected,
                    m.disconnected_bulk,
                    m.mean_speed,
                    analytic,
                    m.profile_error.map_or("-".into(), |e| format!("{:.3}", e)),
                    m.speed_95,
                    started.elapsed().as_secs_f64()
                );
            };
            while !sim.finished() {
                if sim.clock().time >= next - 1e-9 {
                    next += every;
                    row(&mut sim, false);
                }
                if let Err(e) = sim.step() {
                    println!("| {deg} | {per_depth} | fault: {e} |");
                    break;
                }
            }
            row(&mut sim, true);
        }
    }
}
