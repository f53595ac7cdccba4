//! What sweeps and studies share: the batch file a command reads ([`BatchFile`]), the runs it
//! plans ([`Planned`], [`PlanFile`] as `plan.json`), what a run has become ([`RunState`]),
//! and the few file helpers both use.
//!
//! It stands below `sweep`, `study`, `plan` and `collect`: each kind of batch implements
//! [`BatchFile`] here, `plan` writes what it returns, and `collect` reads the runs back and
//! hands them to the kind's own table writer. A study travels through `plan.json` as plain
//! JSON, so this module knows no kind of batch.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use serde::{Deserialize, Serialize};

use regolith::error::{Error, SceneError};
use regolith::registry::Registries;

/// A file of runs of one scene with different overrides: a sweep or a study. What the
/// local commands, `--plan` and `--collect` need of it.
pub trait BatchFile: Sized + serde::de::DeserializeOwned {
    /// `sweep` or `study`: the command, and `plan.json`'s kind.
    const KIND: &'static str;
    /// The table a finished batch is read from, in its directory.
    const TABLE: &'static str;
    /// Reads the file at `path` and checks it; errors name the file (and line).
    fn load(path: &Path) -> Result<Self, SceneError> {
        let (batch, origin) = load_batch_file(path, Self::KIND, Self::jobs)?;
        batch.validate(&origin)?;
        Ok(batch)
    }
    /// Refuses what parses but cannot be run (`origin` names the file in messages).
    fn validate(&self, origin: &str) -> Result<(), SceneError>;
    fn name(&self) -> &str;
    /// The scene file, relative to the batch file.
    fn scene(&self) -> &str;
    /// Runs at once the file asks for.
    fn jobs(&self) -> Option<usize>;
    /// The runs, in order.
    fn runs(&self) -> Vec<Planned>;
    /// `plan.json` without its runs.
    fn head(&self) -> PlanFile;
    /// Refuses a batch that cannot give its results, before anything is written.
    fn check(&self, _path: &Path, _registries: &Arc<Registries>) -> Result<(), Error> {
        Ok(())
    }
}

/// `plan.json`.
#[derive(Debug, Serialize, Deserialize)]
pub struct PlanFile {
    /// `sweep` or `study`: which table `--collect` writes.
    pub kind: String,
    pub name: String,
    /// The varied keys of a sweep, in its order (the table's parameter columns); empty
    /// for a study.
    pub keys: Vec<String>,
    pub runs: Vec<PlannedRun>,
    /// The study file as planned (a study's tables need its knobs and reference), kept as
    /// the JSON it is written as: the study module reads it back (`Study::planned`), so
    /// that the plan's format does not depend on the study's.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub study: Option<serde_json::Value>,
}

/// One run of a plan.
#[derive(Debug, Serialize, Deserialize)]
pub struct PlannedRun {
    /// The run's directory relative to the plan: `runs/run_NNNN` (a plan), `run_NNNN` (a
    /// local sweep's output directory).
    pub dir: String,
    /// The varied values, in the order of `keys` (a study: the knob and the value).
    pub values: Vec<String>,
    /// FNV-1a digest of the run's `scene.ron`, 16 hex digits.
    pub scene_digest: String,
    /// Estimated wall time on one thread (s).
    pub estimated_s: f64,
}

/// One run of the sweep: its directory name and overrides.
#[derive(Clone, Debug)]
pub struct Planned {
    pub dir: String,
    pub values: Vec<String>,
    pub sets: Vec<String>,
}

/// Where a planned run stands.
#[derive(Clone, Debug, PartialEq)]
pub enum State {
    Completed,
    /// Failed, with why (its summary's `failure`, or the worker's error).
    Failed(String),
    /// Not started, or running.
    Pending,
}

/// One planned run as found on disk.
#[derive(Clone, Debug)]
pub struct RunState {
    /// Relative to the plan directory.
    pub dir: String,
    /// The varied values, as planned.
    pub values: Vec<String>,
    pub state: State,
    /// Its `summary.json` when it completed or failed, else `Null`.
    pub summary: serde_json::Value,
}

impl RunState {
    /// `completed`, `failed` or `pending`, as the tables print it.
    pub fn status(&self) -> &'static str {
        match self.state {
            State::Completed => "completed",
            State::Failed(_) => "failed",
            State::Pending => "pending",
        }
    }
}

/// Reads and parses a batch file (a sweep or a study; `what` names it in messages) and
/// checks its `jobs`; returns it with the file's name for further messages.
pub(crate) fn load_batch_file<T: serde::de::DeserializeOwned>(
    path: &Path,
    what: &str,
    jobs: impl Fn(&T) -> Option<usize>,
) -> Result<(T, String), SceneError> {
    let origin = path.display().to_string();
    let text = std::fs::read_to_string(path)
        .map_err(|e| SceneError::file(&origin, format!("cannot read the {what}: {e}")))?;
    let batch: T = regolith::scene::ron_options()
        .from_str(&text)
        .map_err(|e| {
            SceneError::at(
                &origin,
                e.span.start.line,
                e.span.start.col,
                e.code.to_string(),
            )
        })?;
    if jobs(&batch) == Some(0) {
        return Err(SceneError::file(&origin, "jobs must be at least 1"));
    }
    Ok((batch, origin))
}

/// A run directory's `summary.json`, if it holds one that parses.
pub fn read_summary(dir: &Path) -> Option<serde_json::Value> {
    let text = std::fs::read_to_string(dir.join("summary.json")).ok()?;
    serde_json::from_str(&text).ok()
}

/// One CSV field, quoted when it holds a comma or a quote.
pub(crate) fn field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// A path written in a batch file (its scene), taken relative to that file's directory.
pub fn beside(file: &Path, relative: &str) -> PathBuf {
    file.parent().unwrap_or(Path::new(".")).join(relative)
}
