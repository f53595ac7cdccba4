//! The integration-scheme study of docs/ACCURACY.md: cost, errors under refinement,
//! spurious stress of a translating block, and the largest stable CFL number.
//!
//! ```text
//! cargo run --release -p regolith-lab --example accuracy
//! ```

use std::path::Path;
use std::time::Instant;

use regolith::material::elastic::p_wave_modulus;
use regolith::{Regolith, Scene, Simulation};
#[path = "../../tests/common/measure.rs"]
mod measure;

use measure::{bar_mode_period, front_speed, largest_stress};

/// The variants compared: (integration, update).
const VARIANTS: [(&str, &str); 4] = [
    ("Linear", "Usl"),
    ("Linear", "Musl"),
    ("CpdiFixed", "Usl"),
    ("CpdiFixed", "Musl"),
];

fn load(name: &str, sets: &[String]) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../scenes")
        .join(format!("{name}.ron"));
    match Scene::load(&path, sets, &Regolith::default().registries()) {
        Ok((scene, _)) => scene,
        Err(e) => panic!("{e}"),
    }
}

fn wave_speed() -> f64 {
    (p_wave_modulus(1.0e7, 0.3) / 1000.0).sqrt()
}

/// Overrides for the bar at `cells` cells along its 1.2 m domain, four cells high.
fn bar(cells: usize, variant: (&str, &str), extra: &[String]) -> Vec<String> {
    let h = 1.2 / cells as f64;
    let mut sets = vec![
        format!("domain=(size: (1.2, {}), cells: ({cells}, 4))", 4.0 * h),
        format!(
            "bodies.bar.shape=Rectangle(min: (0.0, 0.0), max: (1.0, {}))",
            4.0 * h
        ),
        format!("integration={}", variant.0),
        format!("update={}", variant.1),
    ];
    sets.extend_from_slice(extra);
    sets
}

fn fmt_err(v: Option<f64>, exact: f64) -> String {
    match v {
        Some(v) => format!("{:.2e}", (v / exact - 1.0).abs()),
        None => "failed".into(),
    }
}

fn main() {
    let c = wave_speed();
    let period = 4.0 / c;
    let resolutions = [30, 60, 120];

    println!("## First-mode period of the fixed-free bar (relative error; CFL 0.5)\n");
    println!(
        "| variant | 30 cells (h = 40 mm) | 60 cells (20 mm) | 120 cells (10 mm) | observed order |"
    );
    println!("|---|---|---|---|---|");
    for v in VARIANTS {
        let errs: Vec<Option<f64>> = resolutions
            .iter()
            .map(|&n| {
                let scene = load("elastic_bar_vibration", &bar(n, v, &[]));
                bar_mode_period(&scene, "bar", 1.0, 0.1)
                    .ok()
                    .flatten()
                    .map(|p| (p / period - 1.0).abs())
            })
            .collect();
        let order = match (errs[1], errs[2]) {
            (Some(a), Some(b)) if b > 0.0 => format!("{:.2}", (a / b).log2()),
            _ => "-".into(),
        };
        let cells: Vec<String> = errs
            .iter()
            .map(|e| e.map_or("failed".into(), |e| format!("{e:.2e}")))
            .collect();
        println!(
            "| {} {} | {} | {} | {} | {order} |",
            v.0, v.1, cells[0], cells[1], cells[2]
        );
    }

    println!(
        "\n## Compression front speed in the bar (relative error against sqrt(M/rho) = {c:.2} m/s)\n"
    );
    println!("| variant | 30 cells | 60 cells | 120 cells |");
    println!("|---|---|---|---|");
    for v in VARIANTS {
        let errs: Vec<String> = resolutions
            .iter()
            .map(|&n| {
                let extra = [
                    "bodies.bar.velocity=(-1.0, 0.0)".to_string(),
                    "time.end=0.0085".to_string(),
                ];
                let scene = load("elastic_bar_vibration", &bar(n, v, &extra));
                let h = 1.2 / n as f64;
                fmt_err(
                    front_speed(&scene, "bar", &[0.2, 0.4, 0.6, 0.8], 0.55 * h, 1.0)
                        .ok()
                        .flatten(),
                    c,
                )
            })
            .collect();
        println!(
            "| {} {} | {} | {} | {} |",
            v.0, v.1, errs[0], errs[1], errs[2]
        );
    }

    println!("\n## Unstressed block translating at 1 m/s across 10 cells (largest stress, Pa)\n");
    println!("| variant | largest stress component |");
    println!("|---|---|");
    for v in VARIANTS {
        let sets = translating_block(v);
        let scene = load("elastic_bar_vibration", &sets);
        let s = match largest_stress(&scene, "bar") {
            Ok(s) => format!("{s:.2e}"),
            Err(e) => format!("blew up: {}", e.message),
        };
        println!("| {} {} | {s} |", v.0, v.1);
    }

    println!("\n## Largest stable CFL number (bar at 60 cells, 0.1 s, bisection to 0.01)\n");
    println!("| variant | largest stable C = c dt / h |");
    println!("|---|---|");
    for v in VARIANTS {
        println!("| {} {} | {} |", v.0, v.1, largest_stable_cfl(v, c));
    }

    println!("\n## Cost on scenes/bench_elastic_block.ron (30 k points, 300 steps)\n");
    println!("| variant | particle-steps/s |");
    println!("|---|---|");
    for v in VARIANTS {
        let sets = vec![format!("integration={}", v.0), format!("update={}", v.1)];
        let scene = load("bench_elastic_block", &sets);
        let mut sim = Simulation::new(&scene);
        let n = sim.particle_count() as f64;
        let start = Instant::now();
        let result = sim.run(|_| {});
        let rate = n * sim.clock().step as f64 / start.elapsed().as_secs_f64();
        match result {
            Ok(()) => println!("| {} {} | {:.2e} |", v.0, v.1, rate),
            Err(e) => println!("| {} {} | failed: {} |", v.0, v.1, e.message),
        }
    }
}

/// Overrides turning the bar scene into a 0.4 m x 0.2 m block moving at 1 m/s through a
/// domain periodic in x, without gravity, for 0.5 s.
fn translating_block(v: (&str, &str)) -> Vec<String> {
    vec![
        "domain=(size: (1.0, 0.5), cells: (20, 10))".into(),
        "walls=(left: Periodic, right: Periodic, bottom: Free, top: Free)".into(),
        "bodies.bar.shape=Rectangle(min: (0.3, 0.15), max: (0.7, 0.35))".into(),
        "bodies.bar.velocity=(1.0, 0.0)".into(),
        "time=(end: 0.5, step: Cfl(0.5), output_every: 0.01)".into(),
        format!("integration={}", v.0),
        format!("update={}", v.1),
    ]
}

/// Stable: the run finishes (no fault: non-finite state, escaped point, kinetic energy past
/// its bound) and no point ever moves faster than ten times the mode's amplitude.
fn stable(v: (&str, &str), cfl: f64, c: f64) -> bool {
    let h = 1.2 / 60.0;
    let dt = cfl * h / c;
    let extra = [
        format!("time.step=Fixed({dt:e})"),
        "time.allow_unstable=true".to_string(),
    ];
    let scene = load("elastic_bar_vibration", &bar(60, v, &extra));
    let mut sim = Simulation::new(&scene);
    if let Some(mut p) = sim.points_mut("bar") {
        for k in 0..p.len() {
            p.velocity[k].x = 0.1 * (std::f64::consts::FRAC_PI_2 * p.position[k].x).sin();
        }
    }
    while !sim.finished() {
        if sim.step().is_err() || sim.bodies()[0].1.max_speed > 1.0 {
            return false;
        }
    }
    true
}

fn largest_stable_cfl(v: (&str, &str), c: f64) -> String {
    let (mut lo, mut hi) = (0.1, 4.0);
    if !stable(v, lo, c) {
        return "< 0.1".into();
    }
    if stable(v, hi, c) {
        return ">= 4".into();
    }
    while hi - lo > 0.01 {
        let mid = 0.5 * (lo + hi);
        if stable(v, mid, c) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    format!("{lo:.2}")
}
