//! The stopping height against the slope (issue 50, item 6; docs/VALIDATION.md, "NGF stage
//! 2"): stage 1's bracket (docs/VALIDATION.md, "Nonlocal granular fluidity") at angles from
//! just above atan(mu_s) to just below atan(mu_2). At each angle two layers of the PS-1
//! `Nonlocal` material, `LOW` and `HIGH` times the model's `H_stop = (pi/2) xi(tan theta)`,
//! start at rest in their lithostatic state on a rough incline (periodic, 4 cells long,
//! 2 x 2 points per cell, whole cells of about `A d / 2.2` so the top lies on a cell
//! boundary) and run 6 s (4 s above 22 degrees, where the fluidity relaxes faster). The
//! bracket holds where the low one stops and the high one flows.
//!
//! ```text
//! cargo run --release -p regolith-lab --example nonlocal_stopping -- [ANGLES] [LOW,HIGH]
//! cargo run --release -p regolith-lab --example nonlocal_stopping -- 19,20,21,22.5,25,27,29 0.97,1.03
//! ```
//! (the second line is the default; about 20 minutes on 2 cores). Prints the table in
//! markdown and draws `docs/figures/ngf_stopping_height.png`: the model's `H_stop / d`
//! against the angle (line) and the measured bracket (shaded, from the deepest layer that
//! stopped to the shallowest that flowed).

use std::path::Path;

use rayon::prelude::*;
use regolith::material::nonlocal::DEFAULT_AMPLITUDE;
use regolith_lab::figures::plot::{Series, curves_over, register_font};
use regolith_lab::verify::nonlocal::{
    LayerState, Outcome, ps1_nonlocal, ps1_nonlocal_ron, run_layer, whole_cells,
};

fn list(arg: Option<&String>, default: &[f64]) -> Vec<f64> {
    arg.map_or_else(
        || default.to_vec(),
        |a| {
            a.split(',')
                .map(|s| {
                    s.parse().unwrap_or_else(|_| {
                        eprintln!(
                            "usage: nonlocal_stopping [ANGLES] [LOW,HIGH]: not a number: {s}"
                        );
                        std::process::exit(2)
                    })
                })
                .collect()
        },
    )
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let angles = list(args.first(), &[19.0, 20.0, 21.0, 22.5, 25.0, 27.0, 29.0]);
    let fractions = list(args.get(1), &[0.97, 1.03]);
    let [low, high] = fractions[..] else {
        eprintln!("usage: nonlocal_stopping [ANGLES] [LOW,HIGH]: two fractions of H_stop");
        std::process::exit(2)
    };
    let material = ps1_nonlocal(DEFAULT_AMPLITUDE);
    let d = material.base.grain_diameter;
    let (mu_s, mu_2) = (material.base.mu_s, material.base.mu_2);
    if let Some(a) = angles
        .iter()
        .find(|a| !(mu_s..mu_2).contains(&a.to_radians().tan()))
    {
        eprintln!(
            "{a} degrees: H_stop is finite and nonzero only between atan(mu_s) = {:.2} and \
             atan(mu_2) = {:.2} degrees",
            mu_s.atan().to_degrees(),
            mu_2.atan().to_degrees()
        );
        std::process::exit(2)
    }
    let runs: Vec<(f64, f64)> = angles.iter().flat_map(|&a| [(a, low), (a, high)]).collect();
    let started = std::time::Instant::now();
    let results: Vec<(f64, f64, f64, Outcome)> = runs
        .into_par_iter()
        .map(|(angle, fraction)| {
            let depth = fraction * material.stopping_height(angle.to_radians());
            let cells = whole_cells(&material, depth, 2.2);
            let end = if angle < 22.0 { 6.0 } else { 4.0 };
            let mut states: Vec<LayerState> = Vec::new();
            run_layer(
                &ps1_nonlocal_ron(""),
                angle,
                depth,
                cells,
                end,
                end / 40.0,
                &[],
                None,
                |s| states.push(*s),
            )
            .unwrap_or_else(|e| panic!("{angle} degrees, {fraction} H_stop: {e}"));
            let outcome = Outcome::of(&states);
            eprintln!(
                "{angle} degrees, {fraction} H_stop, {cells} cells: {outcome} ({:.0} s)",
                started.elapsed().as_secs_f64()
            );
            (angle, fraction, cells, outcome)
        })
        .collect();

    println!(
        "Command: `cargo run --release -p regolith-lab --example nonlocal_stopping -- {} \
         {low},{high}`. PS-1 `Nonlocal`, A = {DEFAULT_AMPLITUDE}, t0 = {} s, d = {} mm; {:.0} s \
         on {} threads.\n",
        angles
            .iter()
            .map(f64::to_string)
            .collect::<Vec<_>>()
            .join(","),
        material.time_scale,
        1e3 * d,
        started.elapsed().as_secs_f64(),
        rayon::current_num_threads()
    );
    println!(
        "| angle | H_stop (mm) | H_stop / d | {low} H_stop: cells, outcome | {high} H_stop: cells, outcome | bracket holds |"
    );
    println!("|---|---|---|---|---|---|");
    let mut band = Vec::new();
    for &angle in &angles {
        let stop = material.stopping_height(angle.to_radians());
        let at = |f: f64| {
            results
                .iter()
                .find(|r| r.0 == angle && r.1 == f)
                .expect("every run is in the results")
        };
        let (below, above) = (at(low), at(high));
        let holds = below.3.stops() && !above.3.stops();
        println!(
            "| {angle} | {:.3} | {:.3} | {}, {} | {}, {} | {} |",
            1e3 * stop,
            stop / d,
            below.2,
            below.3,
            above.2,
            above.3,
            if holds { "yes" } else { "no" }
        );
        if holds {
            band.push((angle, low * stop / d, high * stop / d));
        }
    }
    figure(&material, band, (low, high));
}

/// The model's curve from 18.5 to 30.5 degrees (it grows without bound towards atan(mu_s) and
/// falls to zero at atan(mu_2)) and the measured brackets (`low` and `high` times H_stop) as a
/// band.
fn figure(
    material: &regolith::material::nonlocal::Nonlocal,
    band: Vec<(f64, f64, f64)>,
    (low, high): (f64, f64),
) {
    let d = material.base.grain_diameter;
    let model = Series {
        label: "(pi/2) xi(tan theta), the model".into(),
        points: (0..=24)
            .map(|k| {
                let a = 18.5 + 0.5 * k as f64;
                (a, material.stopping_height(a.to_radians()) / d)
            })
            .collect(),
        hollow: false,
        band: None,
    };
    let measured = Series {
        label: format!("MPM: stopped at {low}, flowed at {high} H_stop"),
        points: band
            .iter()
            .map(|&(a, lo, hi)| (a, 0.5 * (lo + hi)))
            .collect(),
        hollow: true,
        band: Some(("MPM: the bracket".into(), band.clone())),
    };
    let folder = Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs/figures");
    let path = folder.join("ngf_stopping_height.png");
    let drawn = register_font().and_then(|()| {
        curves_over(
            &path,
            "NGF stopping height against the slope (PS-1, A = 0.48)",
            ("slope angle (degrees)", Some((18.0, 31.0))),
            "H_stop / d",
            &[model, measured],
        )
    });
    match drawn {
        Ok(()) => eprintln!("wrote {}", path.display()),
        Err(e) => eprintln!("{}: {e}", path.display()),
    }
}
