//! The flow field of silos and hoppers (issue 40): each scene run to time `T`, its granular
//! points drawn by speed class, one panel per scene, and the numbers that tell mass flow from
//! funnel flow printed.
//!
//! ```text
//! cargo run --release -p regolith-lab --example silo_flow -- T Y OUT.png SCENE...
//! cargo run --release -p regolith-lab --example silo_flow -- 0.3 0.05 docs/figures/silo_flow.png \
//!     scenes/silo_flat_coarse.ron scenes/hopper_shallow_coarse.ron scenes/hopper_coarse.ron
//! ```
//!
//! Speed classes: below 1 cm/s (at rest: the stagnant zones of funnel flow), 1-10 cm/s,
//! 10-50 cm/s, above 50 cm/s (the jet at the orifice). Printed per scene: the fraction of
//! the material in the bin at rest, and in the band of one cell around height `Y` (in the
//! hoppers' converging part for `Y` below their walls' top), the mean downward speed of the points within two cells of the
//! bin's side against that of the points within two cells of the axis. In mass flow the
//! material moves everywhere, next to the walls too; in funnel flow it moves in a channel
//! above the orifice while the material beside it rests.

use std::sync::Arc;

use glam::DVec2;
use regolith::{Regolith, Scene, Simulation};
use regolith_lab::figures::plot::{self, Cloud};

/// The classes' upper bounds (m/s) and names.
const CLASSES: [(f64, &str); 4] = [
    (0.01, "< 1 cm/s"),
    (0.1, "1-10 cm/s"),
    (0.5, "10-50 cm/s"),
    (f64::INFINITY, "> 50 cm/s"),
];

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() < 4 {
        eprintln!("usage: silo_flow T Y OUT.png SCENE...");
        std::process::exit(2);
    }
    let t: f64 = args[0].parse().expect("T: a time in seconds");
    let y: f64 = args[1].parse().expect("Y: a height in metres");
    let out = std::path::Path::new(&args[2]);
    let registries: Arc<_> = Regolith::default().registries();
    let mut panels = Vec::new();
    let mut window = (DVec2::INFINITY, DVec2::NEG_INFINITY);
    for path in &args[3..] {
        let end = format!("time.end={t}");
        let (scene, _) =
            Scene::load(path.as_ref(), &[end], &registries).unwrap_or_else(|e| panic!("{e}"));
        let body = scene
            .bodies
            .iter()
            .find(|b| b.material.granular())
            .expect("a granular body")
            .name
            .clone();
        let mut sim = Simulation::new(&scene);
        sim.run(|_| {}).unwrap_or_else(|e| panic!("{path}: {e}"));
        let h = sim.grid().cell_size;
        let (lo, hi) = (sim.grid().origin, sim.grid().max());
        window = (window.0.min(lo), window.1.max(hi));
        let p = sim.points(&body).unwrap();
        let live: Vec<usize> = (0..p.len()).filter(|&k| p.mass[k] > 0.0).collect();
        let mut clouds: Vec<Cloud> = vec![Vec::new(); CLASSES.len()];
        for &k in &live {
            let speed = p.velocity[k].length();
            let class = CLASSES.iter().position(|c| speed < c.0).unwrap_or(3);
            clouds[class].push((p.position[k].x, p.position[k].y));
        }
        let resting = clouds[0].len() as f64 / live.len() as f64;
        let centre = 0.5 * (lo.x + hi.x);
        let band = |k: &usize| (p.position[*k].y - y).abs() < 0.5 * h;
        let in_band: Vec<usize> = live.iter().copied().filter(band).collect();
        let mean_down = |pick: &dyn Fn(f64) -> bool| {
            let v: Vec<f64> = in_band
                .iter()
                .filter(|&&k| pick(p.position[k].x))
                .map(|&k| -p.velocity[k].y)
                .collect();
            (v.iter().sum::<f64>() / v.len().max(1) as f64, v.len())
        };
        // Beside the walls: the band's outermost points on each side, within two cells.
        let (left, right) = in_band
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |m, &k| {
                (m.0.min(p.position[k].x), m.1.max(p.position[k].x))
            });
        let (wall, n_wall) = mean_down(&|x| x < left + 2.0 * h || x > right - 2.0 * h);
        let (axis, n_axis) = mean_down(&|x| (x - centre).abs() < 2.0 * h);
        println!(
            "{}: at t = {t} s, {:.1}% of the material in the bin at rest (< 1 cm/s); at y = {y} m \
             the material spans x = {left:.3}-{right:.3} m and moves down at {wall:.4} m/s beside \
             the walls ({n_wall} points) against {axis:.4} m/s on the axis ({n_axis} points): \
             ratio {:.3}",
            scene.name,
            100.0 * resting,
            wall / axis
        );
        panels.push((scene.name.clone(), clouds));
    }
    plot::register_font().unwrap();
    // The clouds take the palette's first colours in order.
    let names: Vec<String> = ["blue", "red", "green", "purple"]
        .iter()
        .zip(CLASSES)
        .map(|(colour, c)| format!("{colour} {}", c.1))
        .collect();
    plot::clouds(
        out,
        &format!("Speed at t = {t} s: {}", names.join(", ")),
        &panels,
        ((window.0.x, window.1.x), (window.0.y, window.1.y)),
    )
    .unwrap();
    println!("wrote {}", out.display());
}
