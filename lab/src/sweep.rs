//! `regolith sweep SWEEP.ron`: the cross product of parameter values, several runs at once,
//! resumable, one CSV row per run.
//!
//! ```ron
//! Sweep(
//!     name: "slope_speed",
//!     scene: "../scenes/impact_tipped_coarse.ron",      // relative to the sweep file
//!     set: ["time.end=0.3"],                            // overrides for every run
//!     vary: [
//!         (key: "bodies.intruder.shape.slope", values: ["0.5", "1.0"]),
//!         (key: "bodies.intruder.velocity", values: ["(0.0, -2.0)", "(0.0, -3.55)"]),
//!     ],
//!     jobs: 2,                                          // runs at once; default: cores
//! )
//! ```
//! The sweep is planned into its output directory (the `plan` module: each run's resolved
//! scene in `run_NNNN/scene.ron`, with `plan.json` and `jobs.txt`) and run there by the
//! `workers` module, one thread per run, as the paper's authors did for throughput; the
//! same plan written elsewhere with `--plan` is run by GNU parallel or Slurm instead. A run
//! whose `summary.json` already says `completed` is skipped, so an interrupted sweep
//! continues where it stopped. `sweep.csv` is rewritten atomically after every run (the
//! `collect` module).

use std::path::Path;

use serde::Deserialize;

use crate::batch::{BatchFile, PlanFile, Planned, RunState, State, field};
use regolith::error::SceneError;
use regolith::output::write_atomic;

/// A sweep file.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Sweep {
    pub name: String,
    /// The scene file, relative to the sweep file.
    pub scene: String,
    /// `key.path=value` overrides applied to every run.
    #[serde(default)]
    pub set: Vec<String>,
    /// The parameters varied; runs are their cross product.
    pub vary: Vec<Varied>,
    /// Runs at once (default: the number of cores).
    #[serde(default)]
    pub jobs: Option<usize>,
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Varied {
    pub key: String,
    pub values: Vec<String>,
}

impl Sweep {
    /// The varied keys, in the file's order (the table's parameter columns).
    pub fn keys(&self) -> Vec<String> {
        self.vary.iter().map(|v| v.key.clone()).collect()
    }

    /// The runs, in order: the last key varies fastest.
    pub fn plan(&self) -> Vec<Planned> {
        let mut runs = vec![Vec::new()];
        for v in &self.vary {
            runs = runs
                .into_iter()
                .flat_map(|prefix| {
                    v.values.iter().map(move |value| {
                        let mut p = prefix.clone();
                        p.push(value.clone());
                        p
                    })
                })
                .collect();
        }
        runs.into_iter()
            .enumerate()
            .map(|(i, values)| {
                let mut sets = self.set.clone();
                sets.extend(
                    self.vary
                        .iter()
                        .zip(&values)
                        .map(|(v, value)| format!("{}={value}", v.key)),
                );
                Planned {
                    dir: format!("run_{:04}", i + 1),
                    values,
                    sets,
                }
            })
            .collect()
    }
}

/// Rewrites `sweep.csv` in `out` from the runs' states; `keys` are the varied keys.
pub(crate) fn write_table(keys: &[String], runs: &[RunState], out: &Path) -> std::io::Result<()> {
    let metrics = [
        "final_depth",
        "stopping_time",
        "impact_energy",
        "peak_deceleration",
    ];
    let mut csv = String::from("run");
    for key in keys {
        csv.push(',');
        csv.push_str(&field(key));
    }
    csv.push_str(",status,steps,wall_s,particle_steps_per_s");
    for m in metrics {
        csv.push(',');
        csv.push_str(m);
    }
    // Appended after `failure` so that columns scripts already read keep their places.
    csv.push_str(",failure,at_rest,depth_at_end,host,threads,regolith_version,state_hash\n");
    for run in runs {
        let summary = &run.summary;
        let number = |v: &serde_json::Value| v.as_f64().map_or(String::new(), |v| v.to_string());
        let mut row = vec![field(&run.dir)];
        row.extend(run.values.iter().map(|v| field(v)));
        row.push(run.status().to_string());
        for key in ["steps", "wall_s", "particle_steps_per_s"] {
            row.push(number(&summary[key]));
        }
        for m in metrics {
            row.push(number(&summary["impact"][m]));
        }
        let failure = match &run.state {
            State::Failed(why) => why.as_str(),
            _ => "",
        };
        row.push(field(failure));
        let impact = &summary["impact"];
        row.push(
            impact["at_rest"]
                .as_bool()
                .map_or(String::new(), |b| b.to_string()),
        );
        row.push(number(&impact["depth_at_end"]));
        for key in ["host", "threads", "regolith_version"] {
            row.push(match &summary[key] {
                serde_json::Value::String(s) => field(s),
                serde_json::Value::Null => String::new(),
                v => v.to_string(),
            });
        }
        row.push(field(&state_hashes(summary)));
        csv.push_str(&row.join(","));
        csv.push('\n');
    }
    write_atomic(&out.join("sweep.csv"), csv.as_bytes())
}

/// Every body's final `state_hash` as `name:hash` pairs joined by spaces (empty without a
/// summary): equal strings mean bitwise equal final states.
fn state_hashes(summary: &serde_json::Value) -> String {
    summary["bodies"]
        .as_array()
        .map_or(String::new(), |bodies| {
            bodies
                .iter()
                .map(|b| {
                    format!(
                        "{}:{}",
                        b["name"].as_str().unwrap_or(""),
                        b["state_hash"].as_str().unwrap_or("")
                    )
                })
                .collect::<Vec<_>>()
                .join(" ")
        })
}

impl BatchFile for Sweep {
    const KIND: &'static str = "sweep";
    const TABLE: &'static str = "sweep.csv";

    fn validate(&self, origin: &str) -> Result<(), SceneError> {
        if self.vary.is_empty() || self.vary.iter().any(|v| v.values.is_empty()) {
            return Err(SceneError::file(
                origin,
                "vary needs at least one key with at least one value",
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
        self.plan()
    }

    fn jobs(&self) -> Option<usize> {
        self.jobs
    }

    fn head(&self) -> PlanFile {
        PlanFile {
            kind: Self::KIND.into(),
            name: self.name.clone(),
            keys: self.keys(),
            runs: Vec::new(),
            study: None,
        }
    }
}
