//! `regolith figures`: runs the coarse versions of the paper's experiments and draws the
//! paper's figures from them (PNG), so every committed figure can be regenerated.
//!
//! Runs go to `--runs` (default `out/figures`) and are reused when already complete (the
//! sweeps skip finished runs, the single scenes are skipped when their `summary.json` says
//! completed); figures go to `--out` (default `docs/figures`). Each figure's title says
//! what it shows; its caption, beside it as `NAME.txt`, names the paper's panel, the
//! resolution (COARSE: these are the CI-sized scenes, not the paper's) and the run cost.
//! The figures: final depth and stopping time against impact energy per tip slope (Fig. 3),
//! the Poncelet terms f(z) and h(z) (Fig. 4), mu(I) against the rate-independent bed
//! (Fig. 10), the pressure space-time diagram with the p-wave line (Fig. 5), the normalised
//! flow field ahead of the disc (Fig. 6) and splash snapshots (Fig. 7).

pub mod plot;
mod read;

use std::path::{Path, PathBuf};
use std::sync::Arc;

use crate::batch::BatchFile;
use crate::poncelet::{DEFAULT_CELLS, Derivatives, fit, load_run};
use crate::sweep::Sweep;
use crate::workers::run_local;
use regolith::error::{Error, SceneError};
use regolith::registry::Registries;
use regolith::run::{CheckpointEvery, Provenance, run_scene};
use regolith::scene::Scene;

use plot::Series;
use read::{
    FLOW_ARROW, Impact, read_cloud, read_flow, read_impacts, read_space_time, with_standard_error,
};

/// The experiment thickness (m) that turns 2D energies (J/m) into the paper's joules.
const THICKNESS: f64 = 0.003;
/// Tip slopes and impact speeds of the depth-energy sweep.
const SLOPES: [f64; 3] = [0.5, 1.5, 2.5];
const SPEEDS: [f64; 3] = [2.0, 3.55, 5.0];

fn fail(what: &str, e: impl std::fmt::Display) -> Error {
    Error::Scene(SceneError::file("regolith figures", format!("{what}: {e}")))
}

/// Runs what is missing under `runs` and draws every figure into `out`; returns the files.
pub fn make_figures(
    registries: &Arc<Registries>,
    scenes: &Path,
    runs: &Path,
    out: &Path,
    jobs: Option<usize>,
    report: &(dyn Fn(&str) + Sync),
) -> Result<Vec<PathBuf>, Error> {
    plot::register_font().map_err(|e| fail("font", e))?;
    std::fs::create_dir_all(runs).map_err(|e| fail(&runs.display().to_string(), e))?;
    std::fs::create_dir_all(out).map_err(|e| fail(&out.display().to_string(), e))?;
    let impact = scenes.join("impact_tipped_coarse.ron");
    let impact = std::path::absolute(&impact).map_err(|e| fail("scenes", e))?;
    let speeds: Vec<String> = SPEEDS.iter().map(|v| format!("\"(0.0, -{v})\"")).collect();
    let slopes: Vec<String> = SLOPES.iter().map(|s| format!("\"{s}\"")).collect();
    let sweep = |name: &str, set: &str, vary: String| -> Result<PathBuf, Error> {
        let file = runs.join(format!("{name}.ron"));
        let text = format!(
            "Sweep(name: {name:?}, scene: {:?}, set: [{set}], vary: [{vary}])",
            impact.display().to_string()
        );
        std::fs::write(&file, text).map_err(|e| fail(&file.display().to_string(), e))?;
        let spec = Sweep::load(&file)?;
        let dir = runs.join(name);
        report(&format!("sweep {name}: {} runs", spec.plan().len()));
        run_local(&file, &spec, &dir, jobs, registries, report)?;
        Ok(dir)
    };
    let speed_axis = format!(
        "(key: \"bodies.intruder.velocity\", values: [{}])",
        speeds.join(", ")
    );
    let depth_dir = sweep(
        "depth_energy",
        "",
        format!(
            "(key: \"bodies.intruder.shape.slope\", values: [{}]), {speed_axis}",
            slopes.join(", ")
        ),
    )?;
    let rate_dir = sweep(
        "rate_independent",
        "\"bodies.bed.material=DruckerPrager(youngs_modulus: 2.0e7, poisson_ratio: 0.45, \
         grain_density: 1280.0, packing_fraction: 0.79, mu_s: 0.320)\", \
         \"bodies.intruder.shape.slope=1.5\"",
        speed_axis.clone(),
    )?;
    let single = |name: &str| -> Result<PathBuf, Error> {
        let dir = runs.join(name);
        let done = std::fs::read_to_string(dir.join("summary.json"))
            .is_ok_and(|s| s.contains("\"status\": \"completed\""));
        if !done {
            report(&format!("run {name}"));
            let path = scenes.join(format!("{name}.ron"));
            let (scene, text) = Scene::load(&path, &[], registries)?;
            let from = Provenance {
                file: &path.display().to_string(),
                text: &text,
                overrides: &[],
            };
            run_scene(&scene, &from, &dir, CheckpointEvery(None), &mut |_: &_| {})?;
        }
        Ok(dir)
    };
    // The wall time of a run (s), for the titles.
    let wall = |dir: &Path| -> f64 {
        std::fs::read_to_string(dir.join("summary.json"))
            .ok()
            .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok())
            .and_then(|s| s["wall_s"].as_f64())
            .unwrap_or(f64::NAN)
    };
    let front_dir = single("force_propagation_coarse")?;
    let flow_dir = single("flow_field_coarse")?;
    let splash_dir = single("splash_seguin_coarse")?;

    let (impacts, moving) = read_impacts(&depth_dir)?;
    let cost = |rows: &[Impact]| rows.iter().map(|r| r.wall).sum::<f64>();
    let coarse = format!(
        "COARSE 50 x 50 cells, {} runs, {:.0} s of runs{}",
        impacts.len(),
        cost(&impacts),
        not_drawn(moving)
    );
    let mut written = draw_depth_energy(out, &impacts, &coarse)?;
    let mut draw = |name: &str, caption: String, result: Result<(), String>| -> Result<(), Error> {
        let path = out.join(name);
        result.map_err(|e| fail(&path.display().to_string(), e))?;
        written.push(write_caption(&path, &caption)?);
        written.push(path);
        Ok(())
    };
    let (rate, rate_moving) = read_impacts(&rate_dir)?;
    let mu_i: Vec<(f64, f64)> = impacts
        .iter()
        .filter(|r| (r.slope - 1.5).abs() < 1e-9)
        .map(|r| (r.energy, r.depth))
        .collect();
    draw(
        "rate_independent.png",
        format!(
            "mu(I) against the rate-independent bed, s = 1.5 (paper Fig. 10); COARSE 50 x 50 \
             cells, {:.0} s of runs{}",
            cost(&rate),
            not_drawn(moving + rate_moving)
        ),
        plot::curves(
            &out.join("rate_independent.png"),
            "mu(I) and rate-independent beds, s = 1.5",
            "impact energy over 3 mm (J)",
            "final depth (m)",
            &[
                Series {
                    label: "mu(I)".into(),
                    points: mu_i,
                    hollow: false,
                    band: None,
                },
                Series {
                    label: "rate-independent (Drucker-Prager)".into(),
                    points: rate.iter().map(|r| (r.energy, r.depth)).collect(),
                    hollow: true,
                    band: None,
                },
            ],
        ),
    )?;
    let shape_runs: Vec<&Impact> = impacts
        .iter()
        .filter(|r| (r.slope - 1.5).abs() < 1e-9)
        .collect();
    let shape: Vec<PathBuf> = shape_runs.iter().map(|r| r.dir.clone()).collect();
    let shape_cost = shape_runs.iter().map(|r| r.wall).sum::<f64>();
    let poncelet_runs = shape
        .iter()
        .map(|d| load_run(d, "intruder"))
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| fail("Poncelet fit", e))?;
    let depths = crate::poncelet::default_depths(&poncelet_runs);
    // `regolith fit`'s default, derivatives over three cells of depth: the interpolating
    // spline of the paper turns the coarse grid's crossing pulses into noise
    // (docs/VALIDATION.md).
    let terms = fit(&poncelet_runs, &depths, Derivatives::Cells(DEFAULT_CELLS));
    let f: Vec<_> = terms.iter().map(|p| (p.depth, p.f, p.f_error)).collect();
    let h: Vec<_> = terms.iter().map(|p| (p.depth, p.h, p.h_error)).collect();
    let fit_caption = |term: &str, side: &str| {
        format!(
            "Poncelet {term}(z), s = 1.5, fitted over {} speeds with derivatives over 3 cells of \
             depth, band one standard error of the fit (paper Fig. 4 {side}); COARSE 50 x 50 \
             cells, {shape_cost:.0} s of runs",
            shape.len()
        )
    };
    draw(
        "poncelet_f.png",
        fit_caption("f", "left"),
        plot::curves(
            &out.join("poncelet_f.png"),
            "Poncelet drag: depth term f(z)",
            "depth z (m)",
            "f over 3 mm (N)",
            &with_standard_error("f(z)", &f),
        ),
    )?;
    draw(
        "poncelet_h.png",
        fit_caption("h", "right"),
        plot::curves(
            &out.join("poncelet_h.png"),
            "Poncelet drag: inertial term h(z)",
            "depth z (m)",
            "h over 3 mm (kg/m)",
            &with_standard_error("h(z)", &h),
        ),
    )?;
    let diagram = read_space_time(&front_dir.join("pressure_front.csv"))?;
    // PS-1 (the scene's bed): E = 20 MPa, nu = 0.45, rho_c = 0.79 x 1280 kg/m^3.
    let (e, nu, rho_c) = (2.0e7f64, 0.45f64, 0.79 * 1280.0);
    let wave = (e * (1.0 - nu) / ((1.0 + nu) * (1.0 - 2.0 * nu)) / rho_c).sqrt();
    draw(
        "pressure_space_time.png",
        format!(
            "Mean pressure rise in 1 cm rings below the impact, with the p-wave line (paper \
             Fig. 5); COARSE 100 x 100 cells, {:.0} s",
            wall(&front_dir)
        ),
        plot::space_time(
            &out.join("pressure_space_time.png"),
            "Pressure rise below the impact",
            &diagram.times,
            &diagram.radii,
            &diagram.values,
            wave,
        ),
    )?;
    let (origins, vectors) = read_flow(&flow_dir.join("flow_field_1.csv"))?;
    draw(
        "flow_field.png",
        format!(
            "Bed velocity over the disc's speed at 45 ms, offsets in disc diameters D (paper \
             Fig. 6); COARSE, {:.0} s",
            wall(&flow_dir)
        ),
        plot::arrows(
            &out.join("flow_field.png"),
            "Flow around the disc at 45 ms",
            ("x offset / D", "y offset / D"),
            &origins,
            &vectors,
            ((-1.5, 1.5), (-2.5, 0.5)),
            &plot::ArrowKey {
                disc: ((0.0, 0.0), 0.5),
                length: FLOW_ARROW,
                meaning: "disc speed".into(),
            },
        ),
    )?;
    let mut panels = Vec::new();
    for (k, label) in [(0usize, "t = 0"), (1, "t = 25 ms")] {
        let file = splash_dir
            .join("snapshots")
            .join(format!("snapshot_{k:05}.csv"));
        panels.push((label.to_string(), read_cloud(&file)?));
    }
    draw(
        "splash.png",
        format!(
            "Splash of a 20 mm disc at 5 m/s into Seguin (2010) grains (paper Fig. 7); COARSE \
             4 mm cells, {:.0} s",
            wall(&splash_dir)
        ),
        plot::clouds(
            &out.join("splash.png"),
            "Splash of a 20 mm disc at 5 m/s",
            &panels,
            ((0.0, 0.2), (0.0, 0.12)),
        ),
    )?;
    Ok(written)
}

/// Draws the paper's Fig. 3 from `impacts` into `out`: final depth and stopping time
/// against impact energy, one curve per tip slope; `caption` ends both captions. Returns
/// the files written.
fn draw_depth_energy(out: &Path, impacts: &[Impact], caption: &str) -> Result<Vec<PathBuf>, Error> {
    let mut slopes: Vec<f64> = impacts.iter().map(|r| r.slope).collect();
    slopes.sort_by(f64::total_cmp);
    slopes.dedup();
    let by_slope = |f: fn(&Impact) -> f64| -> Vec<Series> {
        slopes
            .iter()
            .map(|&s| Series {
                label: if s.is_nan() {
                    "slope not varied".into()
                } else {
                    format!("s = {s}")
                },
                points: impacts
                    .iter()
                    .filter(|r| r.slope.total_cmp(&s).is_eq())
                    .map(|r| (r.energy, f(r)))
                    .collect(),
                hollow: false,
                band: None,
            })
            .collect()
    };
    // File, title, paper panel, y axis, measure.
    type Figure = (
        &'static str,
        &'static str,
        &'static str,
        &'static str,
        fn(&Impact) -> f64,
    );
    let figures: [Figure; 2] = [
        (
            "depth_energy.png",
            "Final depth against impact energy",
            "Fig. 3 left",
            "final depth (m)",
            |r| r.depth,
        ),
        (
            "stopping_time_energy.png",
            "Stopping time against impact energy",
            "Fig. 3 right",
            "stopping time (s)",
            |r| r.stopping,
        ),
    ];
    let mut written = Vec::new();
    for (name, title, panel, y, f) in figures {
        let path = out.join(name);
        plot::curves(&path, title, "impact energy over 3 mm (J)", y, &by_slope(f))
            .map_err(|e| fail(&path.display().to_string(), e))?;
        written.push(write_caption(
            &path,
            &format!("{title} (paper {panel}); {caption}"),
        )?);
        written.push(path);
    }
    Ok(written)
}

/// `regolith figures --from DIR`: the paper's Fig. 3 from the collected table of a sweep
/// (DIR/sweep.csv, from `regolith sweep` or `sweep --collect`) whose runs vary the tip
/// slope and the impact speed of an impact scene; returns the files written into `out`.
pub fn depth_energy_from(dir: &Path, out: &Path) -> Result<Vec<PathBuf>, Error> {
    plot::register_font().map_err(|e| fail("font", e))?;
    std::fs::create_dir_all(out).map_err(|e| fail(&out.display().to_string(), e))?;
    let (impacts, left_out) = read_impacts(dir)?;
    if impacts.is_empty() {
        return Err(fail(
            &dir.join("sweep.csv").display().to_string(),
            format!("no completed run with its intruder at rest to draw ({left_out} left out)"),
        ));
    }
    let name = dir
        .file_name()
        .map_or(String::new(), |n| n.to_string_lossy().into_owned());
    let caption = format!(
        "{name}: {} runs, {:.0} s of runs{}",
        impacts.len(),
        impacts.iter().map(|r| r.wall).sum::<f64>(),
        not_drawn(left_out)
    );
    draw_depth_energy(out, &impacts, &caption)
}

/// Writes a figure's caption beside it (`name.png` -> `name.txt`): what it shows, the
/// paper's panel, the resolution and the cost of its runs, kept out of the picture so the
/// figure can go into a paper as it is. Returns the caption's path.
fn write_caption(figure: &Path, caption: &str) -> Result<PathBuf, Error> {
    let path = figure.with_extension("txt");
    regolith::output::write_atomic(&path, format!("{caption}\n").as_bytes())
        .map_err(|e| fail(&path.display().to_string(), e))?;
    Ok(path)
}

/// The caption's note of runs left out: intruder still moving at the end, or run not completed.
fn not_drawn(left_out: usize) -> String {
    match left_out {
        0 => String::new(),
        n => format!(", {n} not at rest or not completed (not drawn)"),
    }
}
