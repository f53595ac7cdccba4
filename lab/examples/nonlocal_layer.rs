//! A layer of the `Nonlocal` PS-1 material on a rough incline, started at rest from its
//! lithostatic state, against the model's stopping height and its 1D steady solution
//! (`verify::nonlocal`): the measurement behind docs/VALIDATION.md, "Nonlocal granular
//! fluidity".
//!
//! `cargo run --release -p regolith-lab --example nonlocal_layer -- ANGLE H/H_STOP CELLS END [SET...]`
//! runs a layer `H/H_STOP` times the analytic stopping height at `ANGLE` degrees, `CELLS` cells
//! deep (4 long; `CELLS` may be fractional, `5.5` puts the top half way up a cell), to `END` seconds, with scene overrides `SET` (`key=value`, as `--set`), and
//! prints the layer's mean and largest speed and its flowing fraction ten times.

use regolith_lab::verify::chute::Steady;
use regolith_lab::verify::nonlocal::{NonlocalLayer, ps1_nonlocal, ps1_nonlocal_ron, run_layer};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let number = |k: usize, what: &str| -> f64 {
        args.get(k)
            .and_then(|a| a.parse().ok())
            .unwrap_or_else(|| {
                eprintln!("usage: nonlocal_layer ANGLE H/H_STOP CELLS END [SET...]: {what} missing or not a number");
                std::process::exit(2)
            })
    };
    let (angle, fraction, cells, end) = (
        number(0, "ANGLE"),
        number(1, "H/H_STOP"),
        number(2, "CELLS"),
        number(3, "END"),
    );
    let sets = args.get(4..).unwrap_or_default().to_vec();
    let material = ps1_nonlocal(regolith::material::nonlocal::DEFAULT_AMPLITUDE);
    let stop = material.stopping_height(angle.to_radians());
    let depth = fraction * stop;
    let steady = NonlocalLayer::solve(&material, angle.to_radians(), depth, 9.81, 1600);
    println!(
        "{angle} degrees: H_stop {:.3} mm, layer {:.3} mm on {cells} cells of {:.3} mm \
         (A d / h = {:.2}); 1D steady mean speed {}, surface speed {}",
        1e3 * stop,
        1e3 * depth,
        1e3 * depth / cells,
        material.amplitude * material.base.grain_diameter * cells / depth,
        steady.as_ref().map_or("- (at rest)".into(), |l| format!(
            "{:.3e} m/s",
            l.mean_speed()
        )),
        steady
            .as_ref()
            .map_or("-".into(), |l| format!("{:.3e} m/s", l.surface_speed())),
    );
    println!("| t (s) | mean speed (m/s) | max speed (m/s) | flowing | disconnected |");
    println!("|---|---|---|---|---|");
    let result = run_layer(
        &ps1_nonlocal_ron(""),
        angle,
        depth,
        cells,
        end,
        end / 10.0,
        &sets,
        None,
        |s| {
            println!(
                "| {:.3} | {:.3e} | {:.3e} | {:.3} | {:.3} |",
                s.time, s.mean_speed, s.max_speed, s.flowing, s.disconnected
            )
        },
    );
    if let Err(e) = result {
        eprintln!("{e}");
        std::process::exit(1);
    }
}
