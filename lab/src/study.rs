//! `regolith study STUDY.ron`: what each accuracy knob costs and what it buys.
//!
//! ```ron
//! Study(
//!     name: "impact_knobs",
//!     scene: "../scenes/impact_tipped.ron",          // relative to the study file
//!     set: ["time.end=0.4", "time.step=Cfl(0.5)"],   // the baseline: every run has these
//!     reference: (label: "200 cells, CFL 0.2", set: ["domain.cells=(200, 200)"]),
//!     knobs: [
//!         (name: "cells", values: [
//!             (label: "50", set: ["domain.cells=(50, 50)"]),
//!             (label: "100", set: []),               // empty: the baseline itself
//!         ]),
//!     ],
//!     jobs: 2,
//! )
//! ```
//! One knob at a time moves away from the baseline (a full cross product of six knobs is
//! hundreds of runs and says little more about each knob's price). Every run is compared with
//! the reference, the finest run the study can afford, which the study names: the errors are
//! `|x - x_ref| / |x_ref|` of final depth, stopping time and peak deceleration, and the cost
//! is the run's wall time on one thread. The study is planned and run as a sweep is (the
//! `plan`, `workers` and `collect` modules: `jobs` at once, completed runs skipped, or
//! `--plan DIR` for GNU parallel and Slurm). Writes `study.csv`, `study.md` (the table, the
//! reference named, the frontier marked) and `pareto.png` (depth error against wall time,
//! the runs no other run beats on both joined up).

use std::path::Path;
use std::sync::Arc;

use serde::{Deserialize, Serialize};

use crate::batch::{BatchFile, PlanFile, Planned, RunState, State, beside, field};
use regolith::error::{Error, SceneError};
use regolith::output::write_atomic;
use regolith::registry::Registries;

/// A study file.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Study {
    pub name: String,
    /// The scene file, relative to the study file.
    pub scene: String,
    /// Overrides of the baseline, applied to every run (the reference included).
    #[serde(default)]
    pub set: Vec<String>,
    /// The finest affordable run, against which errors are measured.
    pub reference: Setting,
    /// The knobs, each moved alone from the baseline.
    pub knobs: Vec<Knob>,
    /// Runs at once (default: the number of cores).
    #[serde(default)]
    pub jobs: Option<usize>,
}

/// A labelled set of overrides.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Setting {
    pub label: String,
    #[serde(default)]
    pub set: Vec<String>,
}

/// One knob and the values the study gives it.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Knob {
    pub name: String,
    pub values: Vec<Setting>,
    /// A change of the problem or the model (material law, contact law, impact speed)
    /// rather than of the numerics: its difference from the reference is the change's
    /// effect, not an error, so its runs are listed but kept off the frontier. Default false.
    #[serde(default)]
    pub model: bool,
}

/// One row of the study: a knob value and the run that measures it.
#[derive(Clone, Debug)]
pub struct Entry {
    pub knob: String,
    pub label: String,
    /// From a model knob (kept off the frontier).
    pub model: bool,
    /// Index into the planned runs (several entries may share the baseline run).
    pub run: usize,
}

/// The measured quantities, in table order.
const METRICS: [&str; 3] = ["final_depth", "stopping_time", "peak_deceleration"];

impl Study {
    /// The runs (the reference first, then the baseline, then each knob value that differs
    /// from a run already planned) and the table's entries.
    pub fn plan(&self) -> (Vec<Planned>, Vec<Entry>) {
        let with = |extra: &[String]| {
            let mut sets = self.set.clone();
            sets.extend(extra.iter().cloned());
            sets
        };
        let mut runs = vec![
            Planned {
                dir: "reference".into(),
                values: vec!["reference".into(), self.reference.label.clone()],
                sets: with(&self.reference.set),
            },
            Planned {
                dir: "baseline".into(),
                values: vec!["baseline".into(), String::new()],
                sets: with(&[]),
            },
        ];
        let mut entries = vec![Entry {
            knob: "baseline".into(),
            label: String::new(),
            model: false,
            run: 1,
        }];
        for knob in &self.knobs {
            for value in &knob.values {
                let sets = with(&value.set);
                let run = runs.iter().position(|r| r.sets == sets).unwrap_or_else(|| {
                    let mut dir = format!("{}_{}", slug(&knob.name), slug(&value.label));
                    while runs.iter().any(|r| r.dir == dir) {
                        dir.push('+');
                    }
                    runs.push(Planned {
                        dir,
                        values: vec![knob.name.clone(), value.label.clone()],
                        sets,
                    });
                    runs.len() - 1
                });
                entries.push(Entry {
                    knob: knob.name.clone(),
                    label: value.label.clone(),
                    model: knob.model,
                    run,
                });
            }
        }
        (runs, entries)
    }
}

/// A directory-safe form of a knob name or value: letters, digits and dots kept
/// (lowercased), anything else a dash. Run directories are named after what they vary, so
/// that editing the study file (adding a value, a knob) never renames a finished run.
fn slug(text: &str) -> String {
    text.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '.' {
                c.to_ascii_lowercase()
            } else {
                '-'
            }
        })
        .collect()
}

/// What a completed run measured: its cost (wall time, and points x steps, which does
/// not depend on the machine's load) and the impact metrics.
#[derive(Clone, Copy, Debug, Default)]
struct Measured {
    wall: Option<f64>,
    particle_steps: Option<f64>,
    metrics: [Option<f64>; 3],
}

fn measured(run: &RunState) -> (String, Measured) {
    if run.state != State::Completed {
        return (run.status().into(), Measured::default());
    }
    let summary = &run.summary;
    let m = Measured {
        wall: summary["wall_s"].as_f64(),
        particle_steps: summary["steps"]
            .as_f64()
            .zip(summary["particles"].as_f64())
            .map(|(s, p)| s * p),
        metrics: METRICS.map(|k| summary["impact"][k].as_f64()),
    };
    // A run whose intruder had not stopped has no final depth or stopping time to compare.
    let status = if summary["impact"]["at_rest"] == false {
        "not at rest"
    } else {
        "completed"
    };
    (status.into(), m)
}

fn relative_error(x: Option<f64>, reference: Option<f64>) -> Option<f64> {
    match (x, reference) {
        (Some(x), Some(r)) if r != 0.0 => Some((x - r).abs() / r.abs()),
        _ => None,
    }
}

/// One finished row: the entry, its run's status and numbers, its errors.
struct Row<'a> {
    entry: &'a Entry,
    run: &'a RunState,
    status: String,
    measured: Measured,
    errors: [Option<f64>; 3],
    /// The larger of the depth and stopping-time errors: what the frontier ranks by.
    impact_error: Option<f64>,
    frontier: bool,
}

/// Rows of numerical knobs not beaten by another such row on both wall time and impact
/// error (ties kept). The impact error is the larger of the final-depth and stopping-time
/// errors: a setting must get both of the paper's main results right. (The peak
/// deceleration is left out: grid-crossing pulses dominate it at every resolution studied,
/// docs/ACCURACY.md.)
fn mark_frontier(rows: &mut [Row]) {
    let cost_error: Vec<Option<(f64, f64)>> = rows
        .iter()
        .map(|r| {
            if r.entry.model {
                None
            } else {
                r.measured.wall.zip(r.impact_error)
            }
        })
        .collect();
    for (i, row) in rows.iter_mut().enumerate() {
        let Some((w, e)) = cost_error[i] else {
            continue;
        };
        row.frontier = !cost_error.iter().enumerate().any(|(j, other)| {
            j != i && other.is_some_and(|(w2, e2)| w2 <= w && e2 <= e && (w2 < w || e2 < e))
        });
    }
}

fn number(x: Option<f64>, digits: usize) -> String {
    x.map_or(String::new(), |v| format!("{v:.digits$}"))
}

fn percent(x: Option<f64>) -> String {
    x.map_or(String::new(), |v| format!("{:.1}%", 100.0 * v))
}

/// Rewrites `study.csv`, `study.md` and (once the reference and one other run are in)
/// `pareto.png` from the runs' summaries.
pub(crate) fn write_tables(
    study: &Study,
    runs: &[RunState],
    entries: &[Entry],
    out: &Path,
) -> Result<(), Error> {
    let (ref_status, reference) = measured(&runs[0]);
    let mut rows: Vec<Row> = entries
        .iter()
        .map(|entry| {
            let run = &runs[entry.run];
            let (status, measured) = measured(run);
            let errors =
                [0, 1, 2].map(|k| relative_error(measured.metrics[k], reference.metrics[k]));
            let impact_error = errors[0].zip(errors[1]).map(|(d, t)| d.max(t));
            Row {
                entry,
                run,
                status,
                measured,
                errors,
                impact_error,
                frontier: false,
            }
        })
        .collect();
    mark_frontier(&mut rows);

    let mut csv = String::from(
        "knob,value,run,status,wall_s,particle_steps,final_depth,stopping_time,peak_deceleration,error_final_depth,error_stopping_time,error_peak_deceleration,error_impact,on_frontier\n",
    );
    // The reference's errors are zero by definition, once it has run.
    let zero = if ref_status == "completed" { "0" } else { "" };
    let full = |x: Option<f64>| x.map_or(String::new(), |v| v.to_string());
    let reference_row = format!(
        "reference,{},reference,{ref_status},{},{},{},{},{},{zero},{zero},{zero},{zero},\n",
        field(&study.reference.label),
        full(reference.wall),
        full(reference.particle_steps),
        full(reference.metrics[0]),
        full(reference.metrics[1]),
        full(reference.metrics[2]),
    );
    csv.push_str(&reference_row);
    for r in &rows {
        let mut line = vec![
            field(&r.entry.knob),
            field(&r.entry.label),
            r.run.dir.clone(),
            r.status.clone(),
            full(r.measured.wall),
            full(r.measured.particle_steps),
        ];
        line.extend(r.measured.metrics.iter().map(|&m| full(m)));
        line.extend(r.errors.iter().map(|&e| full(e)));
        line.push(full(r.impact_error));
        line.push(r.frontier.to_string());
        csv.push_str(&line.join(","));
        csv.push('\n');
    }
    write_atomic(&out.join("study.csv"), csv.as_bytes())
        .map_err(|e| Error::io("cannot write study.csv", e))?;

    let mut md = format!(
        "# Study {}\n\nScene `{}`, baseline overrides `{:?}`.\n\n**Reference** (the finest affordable run; errors are relative to it): {} (`{:?}`), {}: wall {} s, final depth {} m, stopping time {} s, peak deceleration {} m/s^2.\n\nWall time is one thread per run, two runs at once; particle-steps (points x steps) is the cost without the machine's load. * = on the frontier (no other run of a numerical knob is both faster and smaller in impact error, the larger of the depth and stopping-time errors); model knobs (marked m) change the physics, so their difference from the reference is not an error and they are kept off the frontier.\n\n| knob | value | run | status | wall (s) | particle-steps | depth (m) | stop (s) | peak decel. (m/s^2) | depth err | stop err | peak err | impact err | |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
        study.name,
        study.scene,
        study.set,
        study.reference.label,
        study.reference.set,
        ref_status,
        number(reference.wall, 1),
        number(reference.metrics[0], 4),
        number(reference.metrics[1], 4),
        number(reference.metrics[2], 1),
    );
    for r in &rows {
        md.push_str(&format!(
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |\n",
            r.entry.knob,
            r.entry.label,
            r.run.dir,
            r.status,
            number(r.measured.wall, 1),
            r.measured
                .particle_steps
                .map_or(String::new(), |n| format!("{n:.2e}")),
            number(r.measured.metrics[0], 4),
            number(r.measured.metrics[1], 4),
            number(r.measured.metrics[2], 1),
            percent(r.errors[0]),
            percent(r.errors[1]),
            percent(r.errors[2]),
            percent(r.impact_error),
            match (r.frontier, r.entry.model) {
                (true, _) => "*",
                (false, true) => "m",
                (false, false) => "",
            },
        ));
    }
    write_atomic(&out.join("study.md"), md.as_bytes())
        .map_err(|e| Error::io("cannot write study.md", e))?;

    // One point per run (the baseline stands for every knob value that equals it), named
    // after the setting the run was planned for.
    let mut points: Vec<crate::figures::plot::Labelled> = Vec::new();
    let mut drawn: Vec<usize> = Vec::new();
    for r in rows.iter().filter(|r| !r.entry.model) {
        let Some((w, e)) = r.measured.wall.zip(r.impact_error) else {
            continue;
        };
        if drawn.contains(&r.entry.run) {
            continue;
        }
        drawn.push(r.entry.run);
        points.push((r.run.values.join(" ").trim().to_string(), w, e, r.frontier));
    }
    if points.len() >= 2 {
        let title = format!(
            "{}: impact error vs wall time (reference: {})",
            study.name, study.reference.label
        );
        crate::figures::plot::pareto(&out.join("pareto.png"), &title, &points)
            .map_err(|e| Error::io("cannot draw pareto.png", std::io::Error::other(e)))?;
    }
    Ok(())
}

impl Study {
    /// The study a plan carries (`plan.json`'s `study`); `origin` names the plan in the
    /// message when it is not one.
    pub fn planned(value: &serde_json::Value, origin: &str) -> Result<Study, SceneError> {
        Study::deserialize(value)
            .map_err(|e| SceneError::file(origin, format!("its study is not a study: {e}")))
    }
}

impl BatchFile for Study {
    const KIND: &'static str = "study";
    const TABLE: &'static str = "study.md";

    fn validate(&self, origin: &str) -> Result<(), SceneError> {
        if self.knobs.is_empty() || self.knobs.iter().any(|k| k.values.is_empty()) {
            return Err(SceneError::file(
                origin,
                "knobs needs at least one knob with at least one value",
            ));
        }
        Ok(())
    }

    fn name(&self) -> &str {
        &self.name
    }

    fn scene(&self) -> &str {
        &self.scene
    }

    fn runs(&self) -> Vec<Planned> {
        self.plan().0
    }

    fn jobs(&self) -> Option<usize> {
        self.jobs
    }

    fn head(&self) -> PlanFile {
        PlanFile {
            kind: Self::KIND.into(),
            name: self.name.clone(),
            keys: Vec::new(),
            runs: Vec::new(),
            // A study is plain data (names, numbers, overrides): it always converts.
            study: serde_json::to_value(self).ok(),
        }
    }

    /// The measures come from the scene's Impact output: a scene without one is refused.
    fn check(&self, path: &Path, registries: &Arc<Registries>) -> Result<(), Error> {
        let scene = beside(path, &self.scene);
        let (base, _) = regolith::scene::Scene::load(&scene, &self.set, registries)?;
        if base.outputs.iter().any(|o| o.name() == "Impact") {
            return Ok(());
        }
        Err(Error::Scene(SceneError::file(
            &path.display().to_string(),
            format!(
                "the study's scene {} has no Impact output, which gives the measures a study compares (add outputs: [Impact(body: ..., surface: ...)])",
                scene.display()
            ),
        )))
    }
}
