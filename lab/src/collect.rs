//! What the runs of a plan have become, merged into the plan's table: `sweep.csv` for a
//! sweep, `study.csv`, `study.md` and `pareto.png` for a study.
//!
//! `regolith sweep --collect DIR` calls this once; the local `regolith sweep` and `study`
//! call it after every run, so their table is always current. A run is read from its own
//! directory only: its `summary.json` says whether it completed or failed, and its
//! `scene.ron` must still be the one planned (a scene edited after planning is reported,
//! not collected).

use std::path::Path;

use crate::batch::{PlanFile, RunState, State, read_summary};
use crate::plan::{digest, read_plan};
use crate::study::Study;
use regolith::error::{Error, SceneError};

/// Why a run whose scene differs from its plan is not collected.
const CHANGED: &str = "its scene.ron was changed or removed after planning";

/// The state of every run of `plan` (in `dir`); `errors` are failures (run index, message)
/// of runs that ended before writing a summary (a local worker's).
pub fn states(dir: &Path, plan: &PlanFile, errors: &[(usize, String)]) -> Vec<RunState> {
    plan.runs
        .iter()
        .enumerate()
        .map(|(i, run)| {
            let d = dir.join(&run.dir);
            let scene = std::fs::read_to_string(d.join("scene.ron")).unwrap_or_default();
            let summary = read_summary(&d).unwrap_or(serde_json::Value::Null);
            let error = errors.iter().find(|(k, _)| *k == i).map(|(_, e)| e.clone());
            // The summary is kept when it reports on the planned scene.
            let (state, keep) = if digest(&scene) != run.scene_digest {
                (State::Failed(CHANGED.into()), false)
            } else if let Some(e) = error {
                (State::Failed(e), summary["status"] == "failed")
            } else {
                match summary["status"].as_str() {
                    Some("completed") => (State::Completed, true),
                    Some("failed") => (
                        State::Failed(summary["failure"].as_str().unwrap_or("failed").into()),
                        true,
                    ),
                    _ => (State::Pending, false),
                }
            };
            let summary = if keep {
                summary
            } else {
                serde_json::Value::Null
            };
            RunState {
                dir: run.dir.clone(),
                values: run.values.clone(),
                state,
                summary,
            }
        })
        .collect()
}

/// What `collect` found.
#[derive(Debug, Default)]
pub struct Collected {
    pub runs: usize,
    pub completed: usize,
    /// Runs without a summary yet (never started, or running).
    pub missing: Vec<String>,
    /// `run: why` of failed runs and of runs whose scene was edited after planning.
    pub failed: Vec<String>,
    /// The table written (`sweep.csv` or `study.md`), relative to the plan directory.
    pub table: &'static str,
}

/// Reads the plan in `dir` and merges its runs into its table.
pub fn collect(dir: &Path) -> Result<Collected, Error> {
    collect_plan(dir, &read_plan(dir)?, &[])
}

/// Merges the runs of `plan` (in `dir`) into its table; `errors` as for [`states`].
pub fn collect_plan(
    dir: &Path,
    plan: &PlanFile,
    errors: &[(usize, String)],
) -> Result<Collected, Error> {
    let runs = states(dir, plan, errors);
    let table = match &plan.study {
        None => {
            crate::sweep::write_table(&plan.keys, &runs, dir)
                .map_err(|e| Error::io(format!("{}: cannot write sweep.csv", dir.display()), e))?;
            "sweep.csv"
        }
        Some(study) => {
            let study = Study::planned(study, &dir.join("plan.json").display().to_string())?;
            let (planned, entries) = study.plan();
            if planned.len() != runs.len() {
                return Err(SceneError::file(
                    &dir.join("plan.json").display().to_string(),
                    format!(
                        "{} runs listed, but its study plans {}",
                        runs.len(),
                        planned.len()
                    ),
                )
                .into());
            }
            crate::study::write_tables(&study, &runs, &entries, dir)?;
            "study.md"
        }
    };
    let mut found = Collected {
        runs: runs.len(),
        table,
        ..Collected::default()
    };
    for run in runs {
        match run.state {
            State::Completed => found.completed += 1,
            State::Failed(why) => found.failed.push(format!("{}: {why}", run.dir)),
            State::Pending => found.missing.push(run.dir),
        }
    }
    Ok(found)
}
