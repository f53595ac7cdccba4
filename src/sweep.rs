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
//! Each run writes its own directory `run_NNNN/` (the usual outputs) under the sweep's
//! output directory; each runs on one thread, as the paper's authors did for throughput. A
//! run whose `summary.json` already says `completed` with the same overrides is skipped, so
//! an interrupted sweep continues where it stopped. `sweep.csv` is rewritten atomically
//! after every run.

use std::path::{Path, PathBuf};
use std::rc::Rc;
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

use serde::Deserialize;

use crate::claim::Claimed;
use crate::error::{Error, SceneError};
use crate::output::write_atomic;
use crate::registry::Registries;
use crate::run::{CheckpointEvery, Provenance, run_scene};
use crate::scene::Scene;

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
    let batch: T = crate::scene::ron_options().from_str(&text).map_err(|e| {
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

/// One run of the sweep: its directory name and overrides.
#[derive(Clone, Debug)]
pub struct Planned {
    pub dir: String,
    pub values: Vec<String>,
    pub sets: Vec<String>,
}

impl Sweep {
    pub fn load(path: &Path) -> Result<Sweep, SceneError> {
        let (sweep, origin) = load_batch_file(path, "sweep", |s: &Sweep| s.jobs)?;
        if sweep.vary.is_empty() || sweep.vary.iter().any(|v| v.values.is_empty()) {
            return Err(SceneError::file(
                &origin,
                "vary needs at least one key with at least one value",
            ));
        }
        Ok(sweep)
    }

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

/// A run directory's `summary.json`, if it holds one that parses.
pub(crate) fn read_summary(dir: &Path) -> Option<serde_json::Value> {
    let text = std::fs::read_to_string(dir.join("summary.json")).ok()?;
    serde_json::from_str(&text).ok()
}

/// Whether `summary` is of a completed run with exactly these overrides.
pub(crate) fn is_completed(summary: &serde_json::Value, sets: &[String]) -> bool {
    let same = summary["overrides"].as_array().is_some_and(|o| {
        o.iter()
            .map(|v| v.as_str().unwrap_or(""))
            .eq(sets.iter().map(String::as_str))
    });
    summary["status"] == "completed" && same
}

/// Whether the run in `dir` completed with exactly these overrides.
fn completed(dir: &Path, sets: &[String]) -> bool {
    read_summary(dir).is_some_and(|s| is_completed(&s, sets))
}

/// One CSV field, quoted when it holds a comma or a quote.
pub(crate) fn field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// Rewrites `sweep.csv` in `out` from the runs' summaries (runs not yet done get
/// `pending`); `keys` are the varied keys, `errors` the failures (run index, message) the
/// summaries do not record.
pub(crate) fn write_table(
    keys: &[String],
    runs: &[Planned],
    out: &Path,
    errors: &[(usize, String)],
) -> std::io::Result<()> {
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
    for (i, run) in runs.iter().enumerate() {
        let summary = read_summary(&out.join(&run.dir))
            .filter(|s| is_completed(s, &run.sets) || s["status"] == "failed")
            .unwrap_or(serde_json::Value::Null);
        let error = errors.iter().find(|(k, _)| *k == i).map(|(_, e)| e.clone());
        let status = match (&error, summary["status"].as_str()) {
            (Some(_), _) => "failed",
            (None, Some(s)) => s,
            (None, None) => "pending",
        };
        let mut row = vec![run.dir.clone()];
        row.extend(run.values.iter().map(|v| field(v)));
        row.push(status.to_string());
        for key in ["steps", "wall_s", "particle_steps_per_s"] {
            row.push(
                summary[key]
                    .as_f64()
                    .map_or(String::new(), |v| v.to_string()),
            );
        }
        for m in metrics {
            row.push(
                summary["impact"][m]
                    .as_f64()
                    .map_or(String::new(), |v| v.to_string()),
            );
        }
        let failure = error
            .or_else(|| summary["failure"].as_str().map(String::from))
            .unwrap_or_default();
        row.push(field(&failure));
        let impact = &summary["impact"];
        row.push(
            impact["at_rest"]
                .as_bool()
                .map_or(String::new(), |b| b.to_string()),
        );
        row.push(
            impact["depth_at_end"]
                .as_f64()
                .map_or(String::new(), |v| v.to_string()),
        );
        for key in ["host", "threads", "regolith_version"] {
            row.push(match &summary[key] {
                serde_json::Value::String(s) => field(s),
                serde_json::Value::Null => String::new(),
                v => v.to_string(),
            });
        }
        row.push(field(&state_hashes(&summary)));
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

/// Runs the sweep into `out`, `jobs` runs at once; reports each finished run to `report`.
pub fn run_sweep(
    sweep_path: &Path,
    sweep: &Sweep,
    out: &Path,
    jobs: Option<usize>,
    registries: impl Fn() -> Rc<Registries> + Sync,
    report: impl Fn(&str) + Sync,
) -> Result<usize, Error> {
    let scene_path = beside(sweep_path, &sweep.scene);
    let runs = sweep.plan();
    let keys = sweep.keys();
    let batch = Batch {
        scene: &scene_path,
        runs: &runs,
        out,
        jobs: jobs.or(sweep.jobs),
    };
    batch.run(registries, report, |errors| {
        write_table(&keys, &runs, out, errors).map_err(|e| Error::io("cannot write sweep.csv", e))
    })
}

/// A path written in a batch file (its scene), taken relative to that file's directory.
pub fn beside(file: &Path, relative: &str) -> PathBuf {
    file.parent().unwrap_or(Path::new(".")).join(relative)
}

/// Runs of one scene with different overrides, each in its own directory under `out`.
pub(crate) struct Batch<'a> {
    pub scene: &'a Path,
    pub runs: &'a [Planned],
    pub out: &'a Path,
    /// Runs at once (default: the number of cores).
    pub jobs: Option<usize>,
}

impl Batch<'_> {
    /// Runs every run not already completed, `jobs` at once on one thread each; after each
    /// (and once before any) calls `table` with the failures so far (index, message) so
    /// that the caller's table is always current. Returns how many runs failed.
    pub fn run(
        &self,
        registries: impl Fn() -> Rc<Registries> + Sync,
        report: impl Fn(&str) + Sync,
        table: impl Fn(&[(usize, String)]) -> Result<(), Error> + Sync,
    ) -> Result<usize, Error> {
        let (runs, out) = (self.runs, self.out);
        std::fs::create_dir_all(out)
            .map_err(|e| Error::io(format!("cannot create {}", out.display()), e))?;
        let pending: Vec<usize> = (0..runs.len())
            .filter(|&i| !completed(&out.join(&runs[i].dir), &runs[i].sets))
            .collect();
        let skipped = runs.len() - pending.len();
        if skipped > 0 {
            report(&format!(
                "{skipped} of {} runs already completed, skipped",
                runs.len()
            ));
        }
        let errors = Mutex::new(Vec::new());
        table(&[])?;
        let next = AtomicUsize::new(0);
        let jobs = self
            .jobs
            .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()))
            .max(1);
        std::thread::scope(|scope| {
            for _ in 0..jobs.min(pending.len().max(1)) {
                scope.spawn(|| {
                    let pool = rayon::ThreadPoolBuilder::new()
                        .num_threads(1)
                        .build()
                        .expect("a one-thread pool");
                    let registries = registries();
                    loop {
                        let k = next.fetch_add(1, Ordering::SeqCst);
                        let Some(&i) = pending.get(k) else { break };
                        let run = &runs[i];
                        let result = self.run_one(run, &pool, &registries);
                        let mut errors =
                            errors.lock().expect("no run panics while holding the lock");
                        match result {
                            Ok(Claimed::Mine(_)) => report(&format!(
                                "{}: completed ({})",
                                run.dir,
                                run.values.join(", ")
                            )),
                            Ok(Claimed::Completed) => report(&format!(
                                "{}: completed by another worker, skipped",
                                run.dir
                            )),
                            Ok(Claimed::Held { holder }) => {
                                report(&format!("{}: claimed by {holder}, skipped", run.dir))
                            }
                            Err(e) => {
                                report(&format!(
                                    "{}: failed ({}): {e}",
                                    run.dir,
                                    run.values.join(", ")
                                ));
                                errors.push((i, e.to_string()));
                            }
                        }
                        if let Err(e) = table(&errors) {
                            report(&e.to_string());
                        }
                    }
                });
            }
        });
        Ok(errors.into_inner().map(|e| e.len()).unwrap_or(0))
    }

    /// Runs `run` unless another worker completed it or holds it (the `claim` module, as
    /// for the lines of a plan); returns what the claim found, with the claim released.
    fn run_one(
        &self,
        run: &Planned,
        pool: &rayon::ThreadPool,
        registries: &Rc<Registries>,
    ) -> Result<Claimed, Error> {
        let dir = self.out.join(&run.dir);
        let claimed = crate::claim::claim(&dir, || completed(&dir, &run.sets))
            .map_err(|e| Error::io(format!("cannot claim {}", dir.display()), e))?;
        let Claimed::Mine(mut claim) = claimed else {
            return Ok(claimed);
        };
        let (scene, text) = Scene::load(self.scene, &run.sets, registries)?;
        let from = Provenance {
            file: &self.scene.display().to_string(),
            text: &text,
            overrides: &run.sets,
        };
        pool.install(|| {
            run_scene(
                &scene,
                &from,
                &dir,
                CheckpointEvery(None),
                &mut |_: &crate::sim::Clock| claim.heartbeat(),
            )
        })?;
        Ok(Claimed::Mine(claim))
    }
}
