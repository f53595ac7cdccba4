//! Thickness-dependent NGF profiles (issue 50, item 2): steady `Nonlocal` PS-1 layers on a
//! rough incline at 22.5 and 25 degrees, `H/d` = 10, 20 and 40, each on 5, 10, 20 and 40
//! cells per depth (2 x 2 points per cell, periodic along the slope, 4 cells long), against
//! the converged 1D solution (`verify::nonlocal::NonlocalLayer` on 1600 cells).
//!
//! Each layer starts in its lithostatic state moving with the 1D solution
//! (`run_layer`), so what the run measures is the relaxation onto the MPM scheme's own
//! steady state; it runs for five relaxation times `T = 1.5 u_s/(mu g cos theta)` (the time
//! a Bagnold layer's momentum takes to diffuse across it), at least 0.5 s. Printed for each,
//! at the end: the surface speed's error (the dense points of the top lattice row against the
//! 1D model at their heights, `LayerState::surface_error`), the mean speed's, the rms of the
//! profile's (over the 1D surface speed), the change of the mean speed over the last tenth
//! of the run (steadiness), and the disconnected fraction; then for each layer the order of
//! convergence of the surface speed between resolutions and, where the finest misses 3%, the
//! resolution that rate says would reach it.
//!
//! It also draws `docs/figures/ngf_profiles_22.5.png` and `ngf_profiles_25.png`: each
//! layer's speed by height on the finest grid run (the dense points' row means, markers)
//! over the 1D solution (lines), both in units of the 1D surface speed and the depth.
//!
//! ```text
//! cargo run --release -p regolith-lab --example nonlocal_profiles [MAX_CELLS_PER_DEPTH]
//! ```
//! (default 40; 20 cuts the cost of the finest runs eightfold).

use rayon::prelude::*;
use regolith::material::nonlocal::DEFAULT_AMPLITUDE;
use regolith_lab::figures::plot::{Series, curves, register_font};
use regolith_lab::verify::chute::Steady;
use regolith_lab::verify::nonlocal::{
    LayerState, NonlocalLayer, RowProfile, ps1_nonlocal, ps1_nonlocal_ron, run_layer,
};

const GRAVITY: f64 = 9.81;
const ANGLES: [f64; 2] = [22.5, 25.0];
const DEPTHS_IN_GRAINS: [f64; 3] = [10.0, 20.0, 40.0];
const TOLERANCE: f64 = 0.03;

/// One layer on one grid, and what its run gave.
struct Case {
    angle: f64,
    grains: f64,
    cells: usize,
    end: f64,
    states: Vec<LayerState>,
    rows: RowProfile,
    error: Option<String>,
}

fn main() {
    let max_cells: usize = std::env::args()
        .nth(1)
        .map(|a| a.parse().expect("MAX_CELLS_PER_DEPTH: a whole number"))
        .unwrap_or(40);
    let resolutions: Vec<usize> = [5, 10, 20, 40]
        .into_iter()
        .filter(|&c| c <= max_cells)
        .collect();
    let material = ps1_nonlocal(DEFAULT_AMPLITUDE);
    let d = material.base.grain_diameter;
    let solve = |angle: f64, grains: f64| {
        let th = f64::to_radians(angle);
        NonlocalLayer::solve(&material, th, grains * d, GRAVITY, 1600).expect("a flowing 1D layer")
    };
    let relaxation = |angle: f64, grains: f64| {
        let th = f64::to_radians(angle);
        1.5 * solve(angle, grains).surface_speed() / (th.tan() * GRAVITY * th.cos())
    };
    let mut cases: Vec<Case> = Vec::new();
    for &angle in &ANGLES {
        for &grains in &DEPTHS_IN_GRAINS {
            for &cells in &resolutions {
                cases.push(Case {
                    angle,
                    grains,
                    cells,
                    end: (5.0 * relaxation(angle, grains)).max(0.5),
                    states: Vec::new(),
                    rows: Vec::new(),
                    error: None,
                });
            }
        }
    }
    // The costliest first, so the two cores finish together: steps times points.
    let cost = |c: &Case| c.end * (c.cells * c.cells) as f64 * c.cells as f64 / (c.grains * d);
    cases.sort_by(|a, b| cost(b).total_cmp(&cost(a)));
    let started = std::time::Instant::now();
    cases.par_iter_mut().for_each(|case| {
        let profile = solve(case.angle, case.grains);
        let every = case.end / 40.0;
        let mut states = Vec::new();
        let result = run_layer(
            &ps1_nonlocal_ron(""),
            case.angle,
            case.grains * d,
            case.cells as f64,
            case.end,
            every,
            &[],
            Some(&profile),
            |s| states.push(*s),
        );
        case.states = states;
        match result {
            Ok(rows) => case.rows = rows,
            Err(e) => case.error = Some(e),
        }
        eprintln!(
            "{} degrees, H/d = {}, {} cells: done at {:.0} s",
            case.angle,
            case.grains,
            case.cells,
            started.elapsed().as_secs_f64()
        );
    });
    cases.sort_by(|a, b| {
        (a.angle, a.grains, a.cells)
            .partial_cmp(&(b.angle, b.grains, b.cells))
            .unwrap()
    });

    println!(
        "PS-1 `Nonlocal`, A = {DEFAULT_AMPLITUDE}, d = {} mm, 2 x 2 points per cell; started on the \
         converged 1D profile, run for 5 T (T = 1.5 u_s/(mu g cos theta), at least 0.5 s).\n",
        1e3 * d
    );
    println!(
        "| angle | H/d | H/H_stop | cells per depth | run (s) | 1D surface speed (m/s) | surface speed error | mean speed error | profile rms error | mean speed change over the last tenth | disconnected |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|");
    let error_of = |case: &Case| -> Option<f64> { case.states.last()?.surface_error };
    for case in &cases {
        let steady = solve(case.angle, case.grains);
        let stop = material.stopping_height(case.angle.to_radians());
        let lead = format!(
            "| {} | {} | {:.1} | {} | {:.2} |",
            case.angle,
            case.grains,
            case.grains * d / stop,
            case.cells,
            case.end
        );
        match (case.states.last(), &case.error) {
            (Some(end), None) => {
                let tenth = &case.states[case.states.len() * 9 / 10 - 1];
                println!(
                    "{lead} {:.4e} | {:+.2}% | {:+.2}% | {:.2}% | {:+.2e} | {:.1}% |",
                    steady.surface_speed(),
                    100.0 * error_of(case).unwrap_or(f64::NAN),
                    100.0 * (end.mean_speed / steady.mean_speed() - 1.0),
                    100.0 * end.profile_error.unwrap_or(f64::NAN),
                    end.mean_speed / tenth.mean_speed - 1.0,
                    100.0 * end.disconnected
                );
            }
            (_, Some(e)) => println!("{lead} failed: {e} | | | | | |"),
            (None, None) => println!("{lead} no sample | | | | | |"),
        }
    }

    println!(
        "\n| angle | H/d | errors, coarse to fine | orders | finest within {:.0}%? | cells per depth for {:.0}% at the last order |",
        100.0 * TOLERANCE,
        100.0 * TOLERANCE
    );
    println!("|---|---|---|---|---|---|");
    for &angle in &ANGLES {
        for &grains in &DEPTHS_IN_GRAINS {
            let runs: Vec<&Case> = cases
                .iter()
                .filter(|c| c.angle == angle && c.grains == grains)
                .collect();
            let errors: Vec<Option<f64>> = runs
                .iter()
                .map(|c| if c.error.is_none() { error_of(c) } else { None })
                .collect();
            let orders: Vec<Option<f64>> = errors
                .windows(2)
                .map(|w| match (w[0], w[1]) {
                    (Some(a), Some(b)) if a != 0.0 && b != 0.0 => Some((a.abs() / b.abs()).log2()),
                    _ => None,
                })
                .collect();
            let show = |v: &[Option<f64>], f: &dyn Fn(f64) -> String| {
                v.iter()
                    .map(|x| x.map_or("-".into(), f))
                    .collect::<Vec<_>>()
                    .join(", ")
            };
            let finest = errors.last().copied().flatten();
            let within = finest.map_or("-".to_string(), |e| {
                if e.abs() <= TOLERANCE { "yes" } else { "no" }.to_string()
            });
            let needed = match (finest, orders.last().copied().flatten()) {
                (Some(e), _) if e.abs() <= TOLERANCE => "reached".to_string(),
                (Some(e), Some(p)) if p > 0.0 => format!(
                    "{:.0}",
                    runs.last().unwrap().cells as f64 * (e.abs() / TOLERANCE).powf(1.0 / p)
                ),
                _ => "-".to_string(),
            };
            println!(
                "| {angle} | {grains} | {} | {} | {within} | {needed} |",
                show(&errors, &|e| format!("{:+.2}%", 100.0 * e)),
                show(&orders, &|p| format!("{p:.2}")),
            );
        }
    }
    draw(&cases, &solve);
    println!(
        "\nWall time {:.0} s on {} threads.",
        started.elapsed().as_secs_f64(),
        rayon::current_num_threads()
    );
}

/// The figures: per angle, each depth's rows on the finest grid run over its 1D profile.
fn draw(cases: &[Case], solve: &dyn Fn(f64, f64) -> NonlocalLayer) {
    let folder = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs/figures");
    if let Err(e) = register_font() {
        eprintln!("no figures: {e}");
        return;
    }
    for &angle in &ANGLES {
        let mut series = Vec::new();
        for &grains in &DEPTHS_IN_GRAINS {
            let Some(finest) = cases
                .iter()
                .filter(|c| c.angle == angle && c.grains == grains && c.error.is_none())
                .max_by_key(|c| c.cells)
            else {
                continue;
            };
            let layer = solve(angle, grains);
            let (depth, surface) = (layer.depth(), layer.surface_speed());
            series.push(Series {
                label: format!("H/d = {grains}, 1D"),
                points: (0..=40)
                    .map(|k| {
                        let y = depth * k as f64 / 40.0;
                        (layer.speed(y) / surface, y / depth)
                    })
                    .collect(),
                hollow: false,
                band: None,
            });
            series.push(Series {
                label: format!("H/d = {grains}, MPM {} cells", finest.cells),
                points: finest
                    .rows
                    .iter()
                    .map(|&(y, u)| (u / surface, y / depth))
                    .collect(),
                hollow: true,
                band: None,
            });
        }
        let path = folder.join(format!("ngf_profiles_{angle}.png"));
        let title = format!("NGF layers at {angle} degrees: speed by height against the 1D model");
        match curves(&path, &title, "u / u_s (1D)", "y / H", &series) {
            Ok(()) => eprintln!("wrote {}", path.display()),
            Err(e) => eprintln!("{}: {e}", path.display()),
        }
    }
}
