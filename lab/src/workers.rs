//! The local workers: runs a plan on this machine, several runs at once on one thread
//! each, every run claimed exactly as a line of the plan's `jobs.txt` claims it
//! (`regolith run ... --claim`). So a local `regolith sweep` or `study`, GNU parallel and a
//! Slurm array all run the same planned scenes through the same claims, and any of them can
//! share a plan with the others. The plan's table is merged again (the `collect` module)
//! after every run.

use std::path::Path;
use std::sync::Arc;
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

use crate::batch::{BatchFile, PlanFile, PlannedRun, read_summary};
use crate::claim::{Claimed, claim};
use crate::collect::collect_plan;
use crate::plan::{Layout, SlurmOptions, write_plan};
use regolith::error::Error;
use regolith::registry::Registries;
use regolith::run::{CheckpointEvery, Provenance, run_scene};
use regolith::scene::Scene;

/// Runs the sweep or study `batch` (read from `path`) into `out`: writes its plan there
/// (runs at the top, `Layout::Local`) and runs it, `jobs` runs at once (default: the
/// file's `jobs`, else the number of cores). Returns the number of failed runs.
pub fn run_local(
    path: &Path,
    batch: &impl BatchFile,
    out: &Path,
    jobs: Option<usize>,
    registries: &Arc<Registries>,
    report: impl Fn(&str) + Sync,
) -> Result<usize, Error> {
    let plan = write_plan(
        path,
        batch,
        out,
        Layout::Local,
        registries,
        &SlurmOptions::default(),
    )?;
    run_plan(out, &plan, jobs.or(batch.jobs()), registries, report)
}

/// Whether the run in `dir` completed.
fn completed(dir: &Path) -> bool {
    read_summary(dir).is_some_and(|s| s["status"] == "completed")
}

/// Runs every run of `plan` (written in `dir`) not already completed, `jobs` at once
/// (default: the number of cores), reporting each to `report`; merges the table before
/// the first run and after each. Returns how many runs failed.
pub fn run_plan(
    dir: &Path,
    plan: &PlanFile,
    jobs: Option<usize>,
    registries: &Arc<Registries>,
    report: impl Fn(&str) + Sync,
) -> Result<usize, Error> {
    let runs = &plan.runs;
    let pending: Vec<usize> = (0..runs.len())
        .filter(|&i| !completed(&dir.join(&runs[i].dir)))
        .collect();
    let skipped = runs.len() - pending.len();
    if skipped > 0 {
        report(&format!(
            "{skipped} of {} runs already completed, skipped",
            runs.len()
        ));
    }
    // Failures that left no summary, by run index; the table is written under this lock.
    let errors = Mutex::new(Vec::new());
    collect_plan(dir, plan, &[])?;
    let next = AtomicUsize::new(0);
    let jobs = jobs
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()))
        .max(1);
    std::thread::scope(|scope| {
        for _ in 0..jobs.min(pending.len().max(1)) {
            scope.spawn(|| {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(1)
                    .build()
                    .expect("a one-thread pool");
                loop {
                    let k = next.fetch_add(1, Ordering::SeqCst);
                    let Some(&i) = pending.get(k) else { break };
                    let run = &runs[i];
                    let result = run_one(dir, run, &pool, registries);
                    let mut errors = errors.lock().expect("no run panics while holding the lock");
                    let values = run.values.join(", ");
                    match result {
                        Ok(Claimed::Mine(_)) => {
                            report(&format!("{}: completed ({values})", run.dir))
                        }
                        Ok(Claimed::Completed) => report(&format!(
                            "{}: completed by another worker, skipped",
                            run.dir
                        )),
                        Ok(Claimed::Held { holder }) => {
                            report(&format!("{}: claimed by {holder}, skipped", run.dir))
                        }
                        Err(e) => {
                            report(&format!("{}: failed ({values}): {e}", run.dir));
                            errors.push((i, e.to_string()));
                        }
                    }
                    if let Err(e) = collect_plan(dir, plan, &errors) {
                        report(&e.to_string());
                    }
                }
            });
        }
    });
    Ok(errors.into_inner().map(|e| e.len()).unwrap_or(0))
}

/// Runs the planned `run` unless another worker completed it or holds it; returns what the
/// claim found, with the claim released.
fn run_one(
    dir: &Path,
    run: &PlannedRun,
    pool: &rayon::ThreadPool,
    registries: &Arc<Registries>,
) -> Result<Claimed, Error> {
    let out = dir.join(&run.dir);
    let claimed = claim(&out, || completed(&out))
        .map_err(|e| Error::io(format!("cannot claim {}", out.display()), e))?;
    let Claimed::Mine(mut claim) = claimed else {
        return Ok(claimed);
    };
    let path = out.join("scene.ron");
    let (scene, text) = Scene::load(&path, &[], registries)?;
    let from = Provenance {
        file: &path.display().to_string(),
        text: &text,
        overrides: &[],
    };
    pool.install(|| {
        run_scene(
            &scene,
            &from,
            &out,
            CheckpointEvery(None),
            &mut |_: &regolith::resources::Clock| claim.heartbeat(),
        )
    })?;
    Ok(Claimed::Mine(claim))
}
