//! The long validation of the `Nonlocal` material's nodal scheme (issue 49; docs/VALIDATION.md,
//! "Nonlocal granular fluidity"), on PS-1 layers on a rough incline, periodic along the slope,
//! started at rest in their lithostatic state:
//!
//! * **The stopping height bracketed to 3%**: layers of 0.97 and 1.03 times the model's
//!   `H_stop = (pi/2) xi(tan theta)` at 22.5 and 25 degrees, on cells of about `A d / 2.2` and
//!   `A d / 4.4`, at 1 x 1 and 2 x 2 points per cell, each with its top on a cell boundary;
//!   and one pair with its top half way up a cell.
//! * **Against the 1D model**: a layer of 2 `H_stop` at 25 degrees on cells of about
//!   `A d / 1.1`, `/ 2.2` and `/ 4.4`, its steady mean speed against the 1D model on the same
//!   nodes (`verify::nonlocal::nodal_mean_speed`, the discretisation the MPM scheme makes)
//!   and against the converged 1D solution (`NonlocalLayer::solve` on 1600 cells).
//! * **The step and the seed**: the 2 `H_stop` layer with the time step halved, and with a
//!   seed a hundred times smaller (and the 0.97 `H_stop` layer with it).
//!
//! ```text
//! cargo run --release -p regolith-lab --example nonlocal_validation
//! ```
//! prints the tables in markdown; about 20 minutes on 2 cores (the runs share them).

use rayon::prelude::*;
use regolith::material::nonlocal::{DEFAULT_AMPLITUDE, Nonlocal};
use regolith_lab::verify::nonlocal::{
    LayerState, NonlocalLayer, Outcome, nodal_mean_speed, ps1_nonlocal, ps1_nonlocal_ron,
    run_layer, whole_cells,
};

const GRAVITY: f64 = 9.81;

/// One layer run.
#[derive(Clone, Debug)]
struct Case {
    angle: f64,
    /// Depth over the model's stopping height.
    fraction: f64,
    cells: f64,
    points: usize,
    end: f64,
    material: String,
    sets: Vec<String>,
}

impl Case {
    fn new(angle: f64, fraction: f64, cells: f64, points: usize, end: f64) -> Case {
        Case {
            angle,
            fraction,
            cells,
            points,
            end,
            material: ps1_nonlocal_ron(""),
            sets: Vec::new(),
        }
    }

    /// Whole cells of about `A d / per` across the layer (at least two).
    fn cells_for(material: &Nonlocal, angle: f64, fraction: f64, per: f64) -> f64 {
        whole_cells(
            material,
            fraction * material.stopping_height(angle.to_radians()),
            per,
        )
    }

    fn depth(&self, material: &Nonlocal) -> f64 {
        self.fraction * material.stopping_height(self.angle.to_radians())
    }

    fn run(&self, material: &Nonlocal) -> Vec<LayerState> {
        let mut sets = vec![format!("bodies.layer.points_per_cell={}", self.points)];
        sets.extend(self.sets.iter().cloned());
        let mut states = Vec::new();
        run_layer(
            &self.material,
            self.angle,
            self.depth(material),
            self.cells,
            self.end,
            self.end / 40.0,
            &sets,
            None,
            |s| states.push(*s),
        )
        .unwrap_or_else(|e| panic!("{self:?}: {e}"));
        states
    }
}

/// What a run came to (`Outcome`), as the tables print it.
fn verdict(states: &[LayerState]) -> String {
    Outcome::of(states).to_string()
}

fn main() {
    let material = ps1_nonlocal(DEFAULT_AMPLITUDE);
    let ad = material.amplitude * material.base.grain_diameter;
    let mut cases: Vec<(String, Case)> = Vec::new();
    // The bracket.
    for angle in [22.5, 25.0] {
        let end = if angle < 24.0 { 4.0 } else { 3.0 };
        for per in [2.2, 4.4] {
            for points in [1, 2] {
                for fraction in [0.97, 1.03] {
                    let cells = Case::cells_for(&material, angle, fraction, per);
                    let key = format!("bracket {angle} {per} {points} {fraction}");
                    cases.push((key, Case::new(angle, fraction, cells, points, end)));
                }
            }
        }
    }
    // The top half way up a cell.
    for points in [1, 2] {
        for fraction in [0.9, 1.1] {
            let cells = Case::cells_for(&material, 25.0, fraction, 2.2) - 0.5;
            let key = format!("mid {points} {fraction}");
            cases.push((key, Case::new(25.0, fraction, cells, points, 2.0)));
        }
    }
    // Against the 1D model.
    for per in [1.1, 2.2, 4.4] {
        for points in [1, 2] {
            let cells = Case::cells_for(&material, 25.0, 2.0, per);
            let key = format!("thick {per} {points}");
            cases.push((key, Case::new(25.0, 2.0, cells, points, 1.5)));
        }
    }
    // The step and the seed.
    let cells = Case::cells_for(&material, 25.0, 2.0, 2.2);
    let mut half = Case::new(25.0, 2.0, cells, 2, 1.5);
    half.sets.push("time.step=Cfl(0.25)".into());
    cases.push(("half step".into(), half));
    for fraction in [0.97, 2.0] {
        let cells = Case::cells_for(&material, 25.0, fraction, 2.2);
        let mut small = Case::new(25.0, fraction, cells, 2, 3.0);
        small.material = ps1_nonlocal_ron("fluidity_seed: 1e-4");
        cases.push((format!("seed {fraction}"), small));
    }
    eprintln!("{} runs", cases.len());
    let results: Vec<(String, Case, Vec<LayerState>)> = cases
        .into_par_iter()
        .map(|(key, case)| {
            let states = case.run(&material);
            eprintln!("done: {key}: {}", verdict(&states));
            (key, case, states)
        })
        .collect();
    let find = |key: &str| {
        results
            .iter()
            .find(|(k, _, _)| k == key)
            .unwrap_or_else(|| panic!("no run {key}"))
    };

    println!(
        "Command: `cargo run --release -p regolith-lab --example nonlocal_validation`. PS-1, \
         A = {DEFAULT_AMPLITUDE}, t0 = {} s, A d = {:.3} mm.\n",
        material.time_scale,
        1e3 * ad
    );
    println!("**The stopping height bracketed** (top on a cell boundary):\n");
    println!("| angle | H_stop (mm) | cells | points per cell | 0.97 H_stop | 1.03 H_stop |");
    println!("|---|---|---|---|---|---|");
    for angle in [22.5, 25.0] {
        for per in [2.2, 4.4] {
            for points in [1, 2] {
                let below = find(&format!("bracket {angle} {per} {points} 0.97"));
                let above = find(&format!("bracket {angle} {per} {points} 1.03"));
                println!(
                    "| {angle} | {:.3} | A d / {per} ({} and {} deep) | {points} x {points} | {} | {} |",
                    1e3 * material.stopping_height(f64::to_radians(angle)),
                    below.1.cells,
                    above.1.cells,
                    verdict(&below.2),
                    verdict(&above.2)
                );
            }
        }
    }
    println!("\n**The top half way up a cell** (25 degrees, cells of about A d / 2.2):\n");
    println!("| points per cell | 0.9 H_stop | 1.1 H_stop |");
    println!("|---|---|---|");
    for points in [1, 2] {
        let below = find(&format!("mid {points} 0.9"));
        let above = find(&format!("mid {points} 1.1"));
        println!(
            "| {points} x {points} ({} and {} cells deep) | {} | {} |",
            below.1.cells,
            above.1.cells,
            verdict(&below.2),
            verdict(&above.2)
        );
    }
    let th = 25f64.to_radians();
    let depth = 2.0 * material.stopping_height(th);
    let converged = NonlocalLayer::solve(&material, th, depth, GRAVITY, 1600)
        .expect("a flowing 1D layer")
        .mean_speed();
    println!(
        "\n**Against the 1D model**: 2 H_stop = {:.3} mm at 25 degrees, steady mean speed at \
         1.5 s; converged 1D mean speed {converged:.4e} m/s.\n",
        1e3 * depth
    );
    println!(
        "| cells | points per cell | MPM (m/s) | 1D on the same nodes (m/s) | MPM / nodal 1D - 1 | nodal 1D / converged - 1 | MPM / converged - 1 |"
    );
    println!("|---|---|---|---|---|---|---|");
    for per in [1.1, 2.2, 4.4] {
        for points in [1, 2] {
            let (_, case, states) = find(&format!("thick {per} {points}"));
            let mpm = states.last().unwrap().mean_speed;
            let nodal =
                nodal_mean_speed(&material, th, depth, GRAVITY, case.cells as usize, points)
                    .expect("a flowing nodal layer");
            println!(
                "| {} (A d / {per}) | {points} x {points} | {mpm:.4e} ({}) | {nodal:.4e} | {:+.2}% | {:+.2}% | {:+.2}% |",
                case.cells,
                verdict(states).split(',').next().unwrap_or(""),
                100.0 * (mpm / nodal - 1.0),
                100.0 * (nodal / converged - 1.0),
                100.0 * (mpm / converged - 1.0)
            );
        }
    }
    let base = find("thick 2.2 2").2.last().unwrap().mean_speed;
    let halved = find("half step").2.last().unwrap().mean_speed;
    let seeded = find("seed 2").2.last().unwrap().mean_speed;
    println!(
        "\n**The step and the seed** (2 H_stop, cells of about A d / 2.2, 2 x 2 points per \
         cell):\n"
    );
    println!("| run | mean speed (m/s) | against the default |");
    println!("|---|---|---|");
    println!("| default (Cfl(0.5), seed 1e-2), 1.5 s | {base:.5e} | |");
    println!(
        "| time step halved (Cfl(0.25)), 1.5 s | {halved:.5e} | {:+.3}% |",
        100.0 * (halved / base - 1.0)
    );
    println!(
        "| seed 1e-4, 3 s | {seeded:.5e} | {:+.3}% |",
        100.0 * (seeded / base - 1.0)
    );
    println!(
        "| seed 1e-4, 0.97 H_stop, 3 s | {} | |",
        verdict(&find("seed 0.97").2)
    );
}
