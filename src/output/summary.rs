//! `summary.json`: what ran, how it ended, what it cost, and each body's final state.

use std::collections::BTreeMap;

use serde::Serialize;

use crate::output::health::BodyHealth;
use serde_json::{Map, Value};

/// What a scene item (an output, a condition) adds to `summary.json`: entries under keys of
/// its own, the units of their dimensional fields (`"impact.final_depth": "m"`), and a line
/// the command prints after the run.
#[derive(Clone, Debug, Default)]
pub struct Section {
    pub entries: Map<String, Value>,
    pub units: Vec<(String, String)>,
    pub headline: Option<String>,
}

impl Section {
    /// A section of one entry.
    pub fn entry(key: &str, value: Value) -> Section {
        let mut entries = Map::new();
        entries.insert(key.to_string(), value);
        Section {
            entries,
            ..Section::default()
        }
    }
}

/// The whole summary. Field names are a public interface: extend, do not rename.
#[derive(Clone, Debug, Serialize)]
pub struct Summary {
    pub scene: String,
    pub scene_file: String,
    /// The `--set` overrides applied.
    pub overrides: Vec<String>,
    /// `completed` or `failed`.
    pub status: String,
    /// Why a failed run stopped.
    pub failure: Option<String>,
    /// Whether some output's or condition's results cover only part of the run: one that
    /// could not carry its state over a resume, or one added at a resume.
    pub partial: bool,
    /// Why, one sentence per item (empty when `partial` is false).
    pub partial_because: Vec<String>,
    pub integration: String,
    pub steps: u64,
    /// Simulated time reached (s).
    pub time: f64,
    /// The time step: the fixed one, or the largest a CFL rule chose (s).
    pub dt: f64,
    pub dt_min: f64,
    pub dt_max: f64,
    /// `fixed` or `cfl`.
    pub dt_rule: String,
    /// Largest CFL number `dt (c + |v|max) / h` actually used.
    pub cfl: f64,
    pub particles: usize,
    pub cells: [usize; 2],
    pub cell_size: f64,
    /// Body force per unit mass (m/s^2).
    pub gravity: [f64; 2],
    pub threads: usize,
    /// The step's kernels: `avx2`, or `scalar` (the reference path; module `kernels`).
    pub kernels: String,
    /// The machine the run ran on (its host name), for tables merged from many machines.
    pub host: String,
    /// The `regolith` version that produced the run.
    pub regolith_version: String,
    pub wall_s: f64,
    pub particle_steps_per_s: f64,
    /// Wall time per step set (s).
    pub timings_s: BTreeMap<String, f64>,
    pub bodies: Vec<BodySummary>,
    /// The unit of every dimensional field, by name (`impact.final_depth` for nested ones).
    pub units: BTreeMap<String, String>,
    /// The entries the scene's outputs and conditions add, each under its own key (the
    /// `Impact` output's `impact` and `impact_not_measured`, `PressureFront`'s
    /// `pressure_front`, ...).
    #[serde(flatten)]
    pub sections: Map<String, Value>,
    /// What passed a bound of `output::health` at the end (one sentence each; also the
    /// run's last lines): a run that completed with a flow gone unphysical says so here.
    pub warnings: Vec<String>,
    /// The lines the command prints after the run, one per item that has one.
    #[serde(skip)]
    pub headlines: Vec<String>,
}

/// One body's final state.
#[derive(Clone, Debug, Serialize)]
pub struct BodySummary {
    pub name: String,
    pub material: String,
    pub points: usize,
    /// Mass per unit thickness (kg/m).
    pub mass: f64,
    pub centre_of_mass: [f64; 2],
    pub velocity: [f64; 2],
    /// Kinetic energy per unit thickness (J/m).
    pub kinetic_energy: f64,
    /// Points that left through an `Open` side (their mass is no longer in `mass`).
    pub retired_points: usize,
    /// `Points::fingerprint` of the final state, 16 hex digits: equal for two runs exactly
    /// when their final point states are bitwise equal.
    pub state_hash: String,
    /// For a granular body: how honest its dense bulk still is (`output::health`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub health: Option<BodyHealth>,
}

/// The `units` map of `summary.json` for its own fields (items add theirs).
pub fn units() -> BTreeMap<String, String> {
    let top = [
        ("time", "s"),
        ("dt", "s"),
        ("dt_min", "s"),
        ("dt_max", "s"),
        ("cell_size", "m"),
        ("gravity", "m/s^2"),
        ("wall_s", "s (wall clock)"),
        ("particle_steps_per_s", "1/s (wall clock)"),
        ("timings_s", "s (wall clock)"),
        ("bodies.mass", "kg/m (per metre of thickness)"),
        ("bodies.centre_of_mass", "m"),
        ("bodies.velocity", "m/s"),
        ("bodies.kinetic_energy", "J/m (per metre of thickness)"),
    ];
    top.iter()
        .map(|&(k, u)| (k.to_string(), u.to_string()))
        .collect()
}
