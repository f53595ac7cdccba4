//! Outputs: the always-written `summary.json` and `trajectory.csv`, and plugin outputs.
//!
//! Plugin outputs (like the built-in `Snapshots`) are named in the scene's `outputs` list and
//! install their own resources and systems in the Output set, exactly as a user's would.
//! Files are written atomically (temporary file, then rename) so a crash never leaves a
//! truncated file that looks complete; the trajectory grows in `trajectory.csv.part` and is
//! renamed when the run ends.

pub mod discharge;
pub mod flow_field;
pub mod free_surface;
pub mod front;
pub mod health;
pub mod impact;
pub mod profile;
pub mod runout;
pub mod snapshots;
pub mod summary;
pub mod trajectory;
pub mod vtk;

use std::fmt::Debug;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use bevy_ecs::prelude::*;

use crate::body::Points;
use crate::carry::Carried;
use crate::error::Fault;
use crate::plugin::Install;
use crate::registry::DynItem;
use crate::resources::Clock;
use crate::scene_view::SceneView;

// Old paths, kept so that code written against them still builds; the one documented path
// is `format` and `resources`, below the outputs.
#[doc(hidden)]
pub use crate::format::{Num, Seconds};
#[doc(hidden)]
pub use crate::resources::Interval;

/// The directory a run writes into, if it writes files at all (tests run without one).
#[derive(Resource, Clone, Debug, Default)]
pub struct RunDir(pub Option<PathBuf>);

/// An extra output: an [`Item`](crate::registry::Item) (its scene name and parameter
/// checks) that implements this, registered with `app.register::<dyn Output, YourType>()`.
pub trait Output: DynItem {
    /// The bodies the output names; the default `check_scene` refuses a scene without them.
    fn bodies(&self) -> Vec<&str> {
        Vec::new()
    }
    /// What must hold between the output and the rest of the scene; `check` reports a
    /// failure at the output's line. By default, that the bodies it names exist.
    fn check_scene(&self, scene: &SceneView) -> Result<(), String> {
        self.bodies()
            .into_iter()
            .try_for_each(|b| scene.body(b).map(|_| ()))
    }
    /// Adds the output's resources and its systems (in [`crate::step::StepSet::Output`]).
    fn install(&self, sim: &mut Install);
    /// What the output carries across a checkpoint (`crate::carry`). By default it says it
    /// cannot, so a resumed run is marked partial rather than restart the output's record
    /// silently: an output with state returns it, one without returns `Carried::Nothing`.
    fn save(&self, _world: &World) -> Carried {
        Carried::Lost(format!(
            "the {} output does not save its state in checkpoints: its record restarted at the resume",
            self.name()
        ))
    }
    /// Puts back the state `save` returned (as `Carried::State`), in a fresh simulation of
    /// the same scene, before the first resumed step.
    fn restore(&self, _world: &mut World, _state: &[u8]) -> Result<(), String> {
        Err(format!("the {} output cannot restore a state", self.name()))
    }
    /// The output's entries in `summary.json`; by default none.
    fn summary(&self, _world: &World) -> summary::Section {
        summary::Section::default()
    }
}

item_kind!(Output, "output");

/// Listed output times: each is written at the first step at or past it.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct Instants {
    times: Vec<f64>,
    next: usize,
}

impl Instants {
    /// `times` must be increasing (see [`check_instants`]).
    pub fn new(times: Vec<f64>) -> Self {
        Instants { times, next: 0 }
    }

    /// Whether an output is due now (and, if so, moves past every listed time reached).
    pub fn due(&mut self, clock: &Clock) -> bool {
        let Some(&t) = self.times.get(self.next) else {
            return false;
        };
        if clock.time < t - 1e-12 {
            return false;
        }
        while self
            .times
            .get(self.next)
            .is_some_and(|&t| t <= clock.time + 1e-12)
        {
            self.next += 1;
        }
        true
    }

    /// How many listed times have passed.
    pub fn done(&self) -> usize {
        self.next
    }
}

/// When a file output writes: `every` seconds or `at` listed times, exactly one of them
/// (the two optional fields of `Snapshots(..)` and `Vtk(..)`).
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub enum Timing {
    Every(Interval),
    At(Instants),
}

impl Timing {
    /// Checks that exactly one of `every` and `at` is given, and that it is valid.
    pub fn check(every: Option<f64>, at: Option<&[f64]>) -> Result<(), String> {
        match (every, at) {
            (Some(every), None) if every.is_finite() && every > 0.0 => Ok(()),
            (Some(every), None) => Err(format!(
                "every must be a positive number of seconds, got {every}"
            )),
            (None, Some(at)) => check_instants(at),
            _ => Err("give either every (an interval) or at (a list of times)".into()),
        }
    }

    /// The timing of checked fields (see [`Timing::check`]).
    pub fn new(every: Option<f64>, at: Option<&[f64]>) -> Self {
        match every {
            Some(every) => Timing::Every(Interval::new(every)),
            None => Timing::At(Instants::new(at.unwrap_or_default().to_vec())),
        }
    }

    /// Whether a file is due now (and, if so, moves on).
    pub fn due(&mut self, clock: &Clock) -> bool {
        match self {
            Timing::Every(interval) => interval.due(clock),
            Timing::At(instants) => instants.due(clock),
        }
    }
}

/// An output's `every`: a positive, finite interval (s).
pub fn check_every(every: f64) -> Result<(), String> {
    if every.is_finite() && every > 0.0 {
        Ok(())
    } else {
        Err(format!("every must be a positive time, got {every}"))
    }
}

/// The points of `body`, the entity an item found at install (`Install::body`).
pub fn points_of<'a>(bodies: &'a Query<&Points>, body: Option<Entity>) -> Option<&'a Points> {
    body.and_then(|e| bodies.get(e).ok())
}

/// The points of `body` (as [`points_of`]) when `interval` is due at `clock` (the start of
/// every periodic output's record); `None` when not due or when the body has no points.
pub fn due_points<'a>(
    interval: &mut Interval,
    clock: &Clock,
    bodies: &'a Query<&Points>,
    body: Option<Entity>,
) -> Option<&'a Points> {
    if !interval.due(clock) {
        return None;
    }
    points_of(bodies, body)
}

/// Checks a list of output times: non-empty, finite, non-negative, increasing.
pub fn check_instants(at: &[f64]) -> Result<(), String> {
    if at.is_empty() || at.iter().any(|t| !t.is_finite() || *t < 0.0) {
        return Err("at must list one or more non-negative times".into());
    }
    if !at.windows(2).all(|w| w[1] > w[0]) {
        return Err("at must be increasing".into());
    }
    Ok(())
}

/// Faults reported by outputs (an output that cannot write stops the run with a message).
/// Outputs only read this resource, so any number of them can sit in the Output set without
/// an ordering between them (a shared `ResMut<Health>` would make every pair ambiguous);
/// `Simulation::step` moves the first report into `diagnostics::Health`.
#[derive(Resource, Debug, Default)]
pub struct OutputFaults(Mutex<Option<Fault>>);

impl OutputFaults {
    /// Records `message` as the run's fault at the clock's step, unless one is recorded.
    pub fn report(&self, clock: &Clock, message: String) {
        let mut first = self.0.lock().unwrap_or_else(|e| e.into_inner());
        first.get_or_insert(Fault {
            step: clock.step,
            time: clock.time,
            message,
        });
    }

    /// Whether an output has reported a fault.
    pub fn any(&self) -> bool {
        self.0.lock().map(|f| f.is_some()).unwrap_or(true)
    }

    /// Takes the reported fault, if any.
    pub fn take(&self) -> Option<Fault> {
        self.0.lock().unwrap_or_else(|e| e.into_inner()).take()
    }
}

/// A time-series table as CSV: a `t` column, then one column per label; a NaN value is
/// left empty.
pub fn series_csv(labels: &[String], times: &[f64], rows: &[Vec<f64>]) -> String {
    let mut s = String::from("t");
    for label in labels {
        s.push(',');
        s.push_str(label);
    }
    s.push('\n');
    for (t, row) in times.iter().zip(rows) {
        s.push_str(&Num(*t).to_string());
        for v in row {
            if v.is_nan() {
                s.push(',');
            } else {
                s.push_str(&format!(",{}", Num(*v)));
            }
        }
        s.push('\n');
    }
    s
}

/// Writes `bytes` to `path` atomically, or reports why not.
pub fn write_or_fault(path: &Path, bytes: &[u8], clock: &Clock, faults: &OutputFaults) {
    if let Err(e) = write_atomic(path, bytes) {
        faults.report(clock, format!("cannot write {}: {e}", path.display()));
    }
}

/// Writes `bytes` to `path` through a temporary file in the same directory and a rename.
/// The temporary file is named after the process, so that two processes sharing a
/// directory (two workers of one sweep writing `sweep.csv`) never write into each other's.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let mut tmp = path.as_os_str().to_owned();
    tmp.push(format!(".tmp.{}", std::process::id()));
    let tmp = PathBuf::from(tmp);
    {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
    }
    std::fs::rename(&tmp, path)
}
