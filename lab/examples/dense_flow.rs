//! The long dense-flow validation (docs/VALIDATION.md, "Steady chute flow"): the shipped
//! chute scene at several angles and resolutions, started in its lithostatic state and
//! moving with the analytic mu(I) profile where there is one, measured every `every`
//! seconds against that profile (`verify::chute::run`, as lab/tests/dense_flow.rs).
//!
//! ```text
//! cargo run --release -p regolith-lab --example dense_flow -- ANGLES CELLS_PER_DEPTH END [EVERY] [--seed AMPLITUDE,CELLS] [--set k=v]...
//! cargo run --release -p regolith-lab --example dense_flow -- 20,25,28 10,20 25 1
//! ```
//! Prints one row per moment (top, volume ratio, disconnected fractions, mean speed,
//! profile error, rms speed normal to the bed, the box-length and grid-scale modes with the
//! grid-scale one's growth rate since the last row, the spread of volume along a row), the
//! last at the end of the run; every run is at the default numerical settings unless
//! `--set` says otherwise. `--seed 1e-4,2` adds a normal-velocity disturbance of 1e-4 m/s
//! and a wavelength of two cells to the start (`verify::chute::Disturbance`), so that a
//! mode's growth or decay shows in a short run. `--nonlocal` runs the layer with the
//! `Nonlocal` PS-1 material (default fluidity parameters) and measures it against the
//! converged 1D NGF solution (`verify::nonlocal::NonlocalLayer`) instead of Bagnold's, and
//! first prints the 1D model's mean speed on the run's own nodes (`nodal_mean_speed`), the
//! steady state the scheme converges to at that resolution.

use regolith::material::nonlocal::DEFAULT_AMPLITUDE;
use regolith_lab::verify::chute::{Bagnold, ChuteState, DEPTH, Disturbance, Steady, ps1, run};
use regolith_lab::verify::nonlocal::{
    NonlocalLayer, nodal_mean_speed, ps1_nonlocal, ps1_nonlocal_ron,
};

fn list(arg: &str) -> Vec<f64> {
    arg.split(',')
        .map(|s| s.parse().unwrap_or_else(|_| panic!("not a number: {s}")))
        .collect()
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() < 3 {
        eprintln!(
            "usage: dense_flow ANGLES CELLS_PER_DEPTH END [EVERY] [--seed A,CELLS] [--nonlocal] [--set k=v]..."
        );
        std::process::exit(2);
    }
    let (angles, resolutions, end) = (list(&args[0]), list(&args[1]), list(&args[2])[0]);
    let every = args
        .get(3)
        .filter(|a| !a.starts_with("--"))
        .map_or(1.0, |a| list(a)[0]);
    let mut sets: Vec<String> = args
        .windows(2)
        .filter(|w| w[0] == "--set")
        .map(|w| w[1].clone())
        .collect();
    let nonlocal = args.iter().any(|a| a == "--nonlocal");
    if nonlocal {
        sets.insert(0, format!("bodies.layer.material={}", ps1_nonlocal_ron("")));
    }
    let disturbance = args.windows(2).find(|w| w[0] == "--seed").map(|w| {
        let v = list(&w[1]);
        Disturbance {
            amplitude: v[0],
            cells: v[1],
        }
    });
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/chute_flow_mui.ron");
    let material = ps1();
    if nonlocal {
        // The layer's steady state on its own cells: the MPM scheme's discretisation in 1D
        // (`nodal_mean_speed`), which a steady MPM layer matches where it holds.
        let m = ps1_nonlocal(DEFAULT_AMPLITUDE);
        for &deg in &angles {
            for &per_depth in &resolutions {
                let th = deg.to_radians();
                let nodal = nodal_mean_speed(&m, th, DEPTH, 9.81, per_depth as usize, 2);
                println!(
                    "{deg} degrees, {per_depth} cells per depth: the 1D model on these nodes has \
                     a mean speed of {} m/s\n",
                    nodal.map_or("- (none)".into(), |v| format!("{v:.4}"))
                );
            }
        }
    }
    println!(
        "| angle | cells/depth | t (s) | top/H | sum V / area | most in a cell | disconnected (bulk) | mean speed (analytic) m/s | profile rms / u_s | 95% speed (m/s) | rms normal speed (m/s) | box mode (m/s) | grid-scale mode (m/s) [cells] | its rate (1/s) | V spread along a row | wall (s) |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    for &deg in &angles {
        for &per_depth in &resolutions {
            let th = deg.to_radians();
            let profile: Option<Box<dyn Steady>> = if nonlocal {
                let m = ps1_nonlocal(DEFAULT_AMPLITUDE);
                NonlocalLayer::solve(&m, th, DEPTH, 9.81, 1600).map(|l| Box::new(l) as _)
            } else {
                Bagnold::new(&material, th, DEPTH, 9.81).map(|b| Box::new(b) as _)
            };
            let analytic = profile.as_ref().map_or(f64::NAN, |b| mean_speed(&**b));
            let started = std::time::Instant::now();
            let mut last: Option<(f64, f64)> = None;
            let row = |t: f64, m: &ChuteState| {
                let rate = last.map_or("-".into(), |(t0, a0): (f64, f64)| {
                    format!("{:.2}", (m.modes.grid_scale / a0).ln() / (t - t0))
                });
                last = Some((t, m.modes.grid_scale));
                println!(
                    "| {deg} | {per_depth} | {t:.2} | {:.4} | {:.5} | {} | {:.3} ({:.3}) | {:.3} ({analytic:.3}) | {} | {:.4} | {:.1e} | {:.1e} | {:.1e} [{:.2}] | {rate} | {:.1e} | {:.0} |",
                    m.top / DEPTH,
                    m.volume_ratio,
                    m.most_in_a_cell,
                    m.disconnected,
                    m.disconnected_bulk,
                    m.mean_speed,
                    m.profile_error.map_or("-".into(), |e| format!("{e:.3}")),
                    m.speed_95,
                    m.normal_rms,
                    m.modes.box_length,
                    m.modes.grid_scale,
                    m.modes.grid_scale_cells,
                    m.modes.volume_spread,
                    started.elapsed().as_secs_f64()
                );
            };
            let outcome = run(
                &path,
                deg,
                per_depth as usize,
                end,
                &sets,
                profile.as_deref(),
                disturbance,
                every,
                row,
            );
            if let Err(e) = outcome {
                println!("| {deg} | {per_depth} | error: {e} |");
            }
        }
    }
}

/// The depth-averaged speed of a steady profile (m/s), by the midpoint rule on 1000 rows.
fn mean_speed(profile: &dyn Steady) -> f64 {
    let n = 1000;
    let h = profile.depth();
    (0..n)
        .map(|k| profile.speed((k as f64 + 0.5) * h / n as f64))
        .sum::<f64>()
        / n as f64
}
