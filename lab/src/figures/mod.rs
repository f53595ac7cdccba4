//! `regolith figures`: runs the coarse versions of the paper's experiments and draws the
//! paper's figures from them (PNG), so every committed figure can be regenerated.
//!
//! Runs go to `--runs` (default `out/figures`) and are reused when already complete (the
//! sweeps skip finished runs, the single scenes are skipped when their `summary.json` says
//! completed); figures go to `--out` (default `docs/figures`). Every figure's title names
//! the resolution (COARSE: these are the CI-sized scenes, not the paper's) and the run cost.
//! The figures: final depth and stopping time against impact energy per tip slope (Fig. 3),
//! the Poncelet terms f(z) and h(z) (Fig. 4), mu(I) against the rate-independent bed
//! (Fig. 10), the pressure space-time diagram with the p-wave line (Fig. 5), the normalised
//! flow field ahead of the disc (Fig. 6) and splash snapshots (Fig. 7).

pub mod plot;

use std::path::{Path, PathBuf};
use std::sync::Arc;

use crate::plan::BatchFile;
use crate::poncelet::{Derivatives, fit, load_run};
use crate::sweep::Sweep;
use crate::workers::run_local;
use regolith::error::{Error, SceneError};
use regolith::registry::Registries;
use regolith::run::{CheckpointEvery, Provenance, run_scene};
use regolith::scene::Scene;

use plot::Series;

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
    let mut draw = |name: &str, result: Result<(), String>| -> Result<(), Error> {
        let path = out.join(name);
        result.map_err(|e| fail(&path.display().to_string(), e))?;
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
        plot::curves(
            &out.join("rate_independent.png"),
            &format!(
                "mu(I) against rate-independent bed, s = 1.5 (paper Fig. 10); COARSE, {:.0} s{}",
                cost(&rate),
                not_drawn(moving + rate_moving)
            ),
            "impact energy over 3 mm (J)",
            "final depth (m)",
            &[
                Series {
                    label: "mu(I)".into(),
                    points: mu_i,
                    hollow: false,
                },
                Series {
                    label: "rate-independent (Drucker-Prager)".into(),
                    points: rate.iter().map(|r| (r.energy, r.depth)).collect(),
                    hollow: true,
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
    // Derivatives over an 18 ms window: the interpolating spline of the paper turns the
    // coarse grid's crossing pulses into noise (docs/VALIDATION.md).
    let terms = fit(&poncelet_runs, &depths, Derivatives::Window(0.018));
    let f: Vec<_> = terms.iter().map(|p| (p.depth, p.f, p.f_error)).collect();
    let h: Vec<_> = terms.iter().map(|p| (p.depth, p.h, p.h_error)).collect();
    draw(
        "poncelet_f.png",
        plot::curves(
            &out.join("poncelet_f.png"),
            &format!(
                "Poncelet f(z), s = 1.5, {} speeds, 18 ms window fit (paper Fig. 4 left); COARSE, {shape_cost:.0} s",
                shape.len()
            ),
            "depth z (m)",
            "f over 3 mm (N)",
            &with_standard_error("f(z)", &f),
        ),
    )?;
    draw(
        "poncelet_h.png",
        plot::curves(
            &out.join("poncelet_h.png"),
            &format!(
                "Poncelet h(z), s = 1.5, {} speeds, 18 ms window fit (paper Fig. 4 right); COARSE, {shape_cost:.0} s",
                shape.len()
            ),
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
        plot::space_time(
            &out.join("pressure_space_time.png"),
            &format!(
                "Mean pressure rise in 1 cm rings below the impact (paper Fig. 5); COARSE 100 x 100, {:.0} s",
                wall(&front_dir)
            ),
            &diagram.times,
            &diagram.radii,
            &diagram.values,
            wave,
        ),
    )?;
    let (origins, vectors) = read_flow(&flow_dir.join("flow_field_1.csv"))?;
    draw(
        "flow_field.png",
        plot::arrows(
            &out.join("flow_field.png"),
            &format!(
                "Bed velocity / disc speed at 45 ms, offsets in disc diameters D (Fig. 6); COARSE, {:.0} s",
                wall(&flow_dir)
            ),
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
        plot::clouds(
            &out.join("splash.png"),
            &format!(
                "Splash of a 20 mm disc at 5 m/s, Seguin (2010) grains (paper Fig. 7); COARSE 4 mm, {:.0} s",
                wall(&splash_dir)
            ),
            &panels,
            ((0.0, 0.2), (0.0, 0.12)),
        ),
    )?;
    Ok(written)
}

/// Draws the paper's Fig. 3 from `impacts` into `out`: final depth and stopping time
/// against impact energy, one curve per tip slope; `caption` ends both titles. Returns
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
            })
            .collect()
    };
    // File, title, y axis, measure.
    type Figure = (&'static str, &'static str, &'static str, fn(&Impact) -> f64);
    let figures: [Figure; 2] = [
        (
            "depth_energy.png",
            "Final depth against impact energy (paper Fig. 3 left)",
            "final depth (m)",
            |r| r.depth,
        ),
        (
            "stopping_time_energy.png",
            "Stopping time against impact energy (paper Fig. 3 right)",
            "stopping time (s)",
            |r| r.stopping,
        ),
    ];
    let mut written = Vec::new();
    for (name, title, y, f) in figures {
        let path = out.join(name);
        plot::curves(
            &path,
            &format!("{title}; {caption}"),
            "impact energy over 3 mm (J)",
            y,
            &by_slope(f),
        )
        .map_err(|e| fail(&path.display().to_string(), e))?;
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

/// The title's note of runs left out: intruder still moving at the end, or run not completed.
fn not_drawn(left_out: usize) -> String {
    match left_out {
        0 => String::new(),
        n => format!(", {n} not at rest or not completed (not drawn)"),
    }
}

/// One impact run's measures.
struct Impact {
    dir: PathBuf,
    slope: f64,
    /// Impact energy over the experiment's thickness (J).
    energy: f64,
    depth: f64,
    stopping: f64,
    wall: f64,
}

/// The completed runs of a sweep's table (`sweep.csv` in `dir`, as `regolith sweep` and
/// `sweep --collect` write it) whose intruder came to rest, with the tip slope from the
/// table's `bodies.intruder.shape.slope` column (NaN when the sweep does not vary it), and
/// how many were left out: still moving at the end (their depth is not a result) or not
/// completed.
fn read_impacts(dir: &Path) -> Result<(Vec<Impact>, usize), Error> {
    let path = dir.join("sweep.csv");
    let origin = path.display().to_string();
    let mut table = csv::Reader::from_path(&path).map_err(|e| fail(&origin, e))?;
    let header = table.headers().map_err(|e| fail(&origin, e))?.clone();
    let column = |name: &str| header.iter().position(|h| h == name);
    let required = |name: &str| {
        column(name).ok_or_else(|| fail(&origin, format!("no `{name}` column: not a sweep table")))
    };
    let [run, status, wall, energy, depth, stopping, at_rest] = [
        "run",
        "status",
        "wall_s",
        "impact_energy",
        "final_depth",
        "stopping_time",
        "at_rest",
    ]
    .map(required);
    let (run, status, wall, energy, depth, stopping, at_rest) =
        (run?, status?, wall?, energy?, depth?, stopping?, at_rest?);
    let slope = column("bodies.intruder.shape.slope");
    let mut kept = Vec::new();
    let mut left_out = 0;
    for (k, record) in table.records().enumerate() {
        let record = record.map_err(|e| fail(&format!("{origin}: row {}", k + 2), e))?;
        let num = |i: usize| {
            record
                .get(i)
                .and_then(|v| v.parse().ok())
                .unwrap_or(f64::NAN)
        };
        if record.get(status) != Some("completed") || record.get(at_rest) != Some("true") {
            left_out += 1;
            continue;
        }
        kept.push(Impact {
            dir: dir.join(record.get(run).unwrap_or_default()),
            slope: slope.map_or(f64::NAN, num),
            energy: num(energy) * THICKNESS,
            depth: num(depth),
            stopping: num(stopping),
            wall: num(wall),
        });
    }
    Ok((kept, left_out))
}

fn read_csv(path: &Path) -> Result<(Vec<String>, Vec<Vec<f64>>), Error> {
    let text = std::fs::read_to_string(path).map_err(|e| fail(&path.display().to_string(), e))?;
    let mut lines = text.lines();
    let header: Vec<String> = lines
        .next()
        .unwrap_or("")
        .split(',')
        .map(str::to_string)
        .collect();
    let rows = lines
        .map(|l| {
            l.split(',')
                .map(|c| c.parse().unwrap_or(f64::NAN))
                .collect()
        })
        .collect();
    Ok((header, rows))
}

/// A space-time diagram: a row of bin values per time.
struct SpaceTime {
    times: Vec<f64>,
    radii: Vec<f64>,
    values: Vec<Vec<f64>>,
}

/// A fitted term per depth (`(depth, value, standard error)`, per metre of thickness) as
/// three curves over the scene's thickness: the value and one standard error either side.
fn with_standard_error(label: &str, terms: &[(f64, f64, f64)]) -> [Series; 3] {
    let curve = |sign: f64| -> Vec<(f64, f64)> {
        terms
            .iter()
            .map(|&(z, v, e)| (z, (v + sign * e) * THICKNESS))
            .collect()
    };
    [
        Series {
            label: label.into(),
            points: curve(0.0),
            hollow: false,
        },
        Series {
            label: "+1 standard error (fit residual)".into(),
            points: curve(1.0),
            hollow: true,
        },
        Series {
            label: "-1 standard error".into(),
            points: curve(-1.0),
            hollow: true,
        },
    ]
}

/// `pressure_front.csv`: times, bin radii (from the `rR` headers) and the rows.
fn read_space_time(path: &Path) -> Result<SpaceTime, Error> {
    let (header, rows) = read_csv(path)?;
    Ok(SpaceTime {
        radii: header[1..]
            .iter()
            .map(|h| h.trim_start_matches('r').parse().unwrap_or(f64::NAN))
            .collect(),
        times: rows.iter().map(|r| r[0]).collect(),
        values: rows.iter().map(|r| r[1..].to_vec()).collect(),
    })
}

/// Length (in disc diameters) of the flow field's arrow for a point moving at the disc's speed.
const FLOW_ARROW: f64 = 0.15;

/// `flow_field_K.csv`: offsets and normalised velocities of every point (arrows scaled to
/// [`FLOW_ARROW`] per unit of normalised velocity).
fn read_flow(path: &Path) -> Result<(plot::Cloud, plot::Cloud), Error> {
    let (_, rows) = read_csv(path)?;
    let (mut o, mut v) = (Vec::new(), Vec::new());
    for r in &rows {
        if r.len() >= 7 && r[3].abs() < 1.5 && r[4] > -2.5 && r[4] < 0.5 {
            o.push((r[3], r[4]));
            v.push((FLOW_ARROW * r[5], FLOW_ARROW * r[6]));
        }
    }
    Ok((o, v))
}

/// A snapshot's points, one cloud per body (in order of appearance).
fn read_cloud(path: &Path) -> Result<Vec<Vec<(f64, f64)>>, Error> {
    let text = std::fs::read_to_string(path).map_err(|e| fail(&path.display().to_string(), e))?;
    let mut names: Vec<String> = Vec::new();
    let mut clouds: Vec<Vec<(f64, f64)>> = Vec::new();
    for line in text.lines().skip(1) {
        let c: Vec<&str> = line.split(',').collect();
        if c.len() < 7 || c[6].parse::<f64>().unwrap_or(0.0) == 0.0 {
            continue;
        }
        let k = match names.iter().position(|n| n == c[1]) {
            Some(k) => k,
            None => {
                names.push(c[1].to_string());
                clouds.push(Vec::new());
                names.len() - 1
            }
        };
        if let (Ok(x), Ok(y)) = (c[2].parse(), c[3].parse()) {
            clouds[k].push((x, y));
        }
    }
    Ok(clouds)
}

#[cfg(test)]
mod tests {
    use super::read_impacts;

    /// A run whose intruder is still moving has no final depth, and a run not completed
    /// has no result: the figures must leave both out (and say so), not plot them. The
    /// table is read by column name, with a quoted velocity as the sweep writes it.
    #[test]
    fn runs_not_at_rest_or_not_completed_are_left_out_and_counted() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(
            dir.path().join("sweep.csv"),
            "run,bodies.intruder.shape.slope,bodies.intruder.velocity,status,wall_s,impact_energy,final_depth,stopping_time,at_rest\n\
             runs/run_0001,1.5,\"(0.0, -2.0)\",completed,2.0,100.0,0.3,0.25,true\n\
             runs/run_0002,1.5,\"(0.0, -3.0)\",completed,2.0,200.0,,,false\n\
             runs/run_0003,2.5,\"(0.0, -2.0)\",pending,,,,,\n",
        )
        .unwrap();
        let (kept, left_out) = read_impacts(dir.path()).unwrap();
        assert_eq!(left_out, 2);
        assert_eq!(kept.len(), 1);
        assert_eq!((kept[0].depth, kept[0].slope), (0.3, 1.5));
        assert_eq!(kept[0].energy, 100.0 * super::THICKNESS);
        assert_eq!(kept[0].dir, dir.path().join("runs/run_0001"));
    }

    /// A table without the impact columns is refused with the file named.
    #[test]
    fn a_table_that_is_not_a_sweep_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(
            dir.path().join("sweep.csv"),
            "run,status\nrun_0001,completed\n",
        )
        .unwrap();
        let Err(e) = read_impacts(dir.path()) else {
            panic!("accepted")
        };
        assert!(
            e.to_string().contains("sweep.csv") && e.to_string().contains("wall_s"),
            "{e}"
        );
    }
}
