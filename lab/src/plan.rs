//! A sweep or a study as a directory of self-contained runs, for whatever runs them:
//! `regolith sweep SWEEP.ron --plan DIR` (or `study STUDY.ron --plan DIR`) writes it, GNU
//! parallel or a Slurm array runs its `jobs.txt`, and `--collect DIR` merges what has
//! finished. The local `regolith sweep` / `study` write the same plan into their output
//! directory and run it with the `workers` module, so every way of running shares this code.
//!
//! ```text
//! DIR/plan.json                the runs: directory, varied values, scene digest, cost
//! DIR/runs/NAME/scene.ron      each run's scene with every override applied
//! DIR/jobs.txt                 one `regolith run ... --claim` line per run, relative to DIR
//! DIR/slurm.sbatch             a job array over the lines of jobs.txt
//! ```
//!
//! Runs keep the names the local commands give them (`run_NNNN` in a sweep's order, the
//! knob and value in a study); the local commands put them at the top of their output
//! directory (no `runs/`), where earlier versions wrote them. A line of `jobs.txt` may be
//! run by several workers at once: `--claim` (the `claim` module) lets exactly one of them
//! run it and the others skip it, and a run left by a killed worker is taken over by the
//! next. Planning again into the same directory keeps finished runs whose scene is
//! unchanged and refuses a directory whose finished runs were made from other scenes (the
//! sweep changed after planning).

use std::fmt::Write as _;
use std::path::Path;

use crate::batch::{BatchFile, PlanFile, Planned, PlannedRun, read_summary};
use regolith::error::{Error, SceneError};
use regolith::output::write_atomic;
use regolith::registry::Registries;
use regolith::scene::Scene;

/// Where a plan puts its runs: under `runs/` in a plan directory, at the top of a local
/// command's output directory (as earlier versions did, so their runs are found again).
#[derive(Clone, Copy, Debug)]
pub enum Layout {
    Plan,
    Local,
}

impl Layout {
    fn dir(self, run: &str) -> String {
        match self {
            Layout::Plan => format!("runs/{run}"),
            Layout::Local => run.to_string(),
        }
    }
}

/// Slurm settings of `slurm.sbatch` (`--slurm-*` flags).
#[derive(Clone, Debug, Default)]
pub struct SlurmOptions {
    /// `--time`, e.g. `02:00:00`; default: the slowest run's estimate, tripled, at least 10 min.
    pub time: Option<String>,
    pub partition: Option<String>,
    /// CPUs per task (default 1; each run then uses that many threads).
    pub cpus: u32,
    /// At most this many array tasks at once (`%M`; default: no limit).
    pub max_running: Option<u32>,
}

/// Particle-steps per second assumed on one thread for the time estimate: about half of
/// what the full model measures (docs/BENCHMARKS.md), so that slow nodes fit.
const ASSUMED_RATE: f64 = 4.0e6;

/// FNV-1a over `text`, as 16 hex digits.
pub(crate) fn digest(text: &str) -> String {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in text.bytes() {
        h = (h ^ b as u64).wrapping_mul(0x0100_0000_01b3);
    }
    format!("{h:016x}")
}

/// A scene's text with the overrides applied and its preset removed (the preset's settings
/// are already in the text; a preset left in would be applied again over them when the
/// text is loaded).
fn resolved_text(
    scene_path: &Path,
    run: &Planned,
    registries: &std::sync::Arc<Registries>,
) -> Result<(Scene, String), Error> {
    let (scene, text) = Scene::load(scene_path, &run.sets, registries)?;
    if scene.preset.is_none() {
        return Ok((scene, text));
    }
    let text = regolith::scene::overrides::set_in_text(&text, "preset=None")
        .map_err(|e| SceneError::file(&scene_path.display().to_string(), format!("preset: {e}")))?;
    let scene = Scene::parse(&text, &scene_path.display().to_string(), registries)?;
    Ok((scene, text))
}

/// Estimated wall time of `scene` on one thread (s): steps at its first time step, times
/// its particles, at [`ASSUMED_RATE`].
fn estimate(scene: &Scene) -> f64 {
    let mut sim = regolith::sim::Simulation::new(scene);
    let (dt, _) = sim.next_time_step();
    let steps = (scene.time.end / dt).ceil();
    steps * sim.particle_count() as f64 / ASSUMED_RATE
}

/// Writes the plan of `batch` (read from `path`) into `dir` and returns it: every run's
/// resolved scene, then `plan.json`, `jobs.txt`, `slurm.sbatch` and `logs/`. Refuses
/// (before writing anything) when a finished run in `dir` ran another scene than the one
/// planned for it now.
pub fn write_plan(
    path: &Path,
    batch: &impl BatchFile,
    dir: &Path,
    layout: Layout,
    registries: &std::sync::Arc<Registries>,
    slurm: &SlurmOptions,
) -> Result<PlanFile, Error> {
    batch.check(path, registries)?;
    let scene_path = crate::batch::beside(path, batch.scene());
    let runs = batch.runs();
    let io = |what: &str, e| Error::io(format!("{}: cannot write {what}", dir.display()), e);
    let mut plan = batch.head();
    let mut scenes = Vec::with_capacity(runs.len());
    for run in &runs {
        let (scene, text) = resolved_text(&scene_path, run, registries)?;
        let rel = layout.dir(&run.dir);
        let old = dir.join(&rel);
        let kept = std::fs::read_to_string(old.join("scene.ron")).ok();
        if read_summary(&old).is_some() && kept.as_deref().is_some_and(|k| k != text) {
            return Err(SceneError::file(
                &path.display().to_string(),
                format!(
                    "the {} changed after {} was planned: {rel} ran another scene than the {} now gives; plan into a new directory, or remove {rel}",
                    plan.kind,
                    dir.display(),
                    plan.kind
                ),
            )
            .into());
        }
        plan.runs.push(PlannedRun {
            dir: rel,
            values: run.values.clone(),
            scene_digest: digest(&text),
            estimated_s: estimate(&scene),
        });
        scenes.push(text);
    }
    for (run, text) in plan.runs.iter().zip(&scenes) {
        let d = dir.join(&run.dir);
        std::fs::create_dir_all(&d).map_err(|e| io(&run.dir, e))?;
        write_atomic(&d.join("scene.ron"), text.as_bytes()).map_err(|e| io(&run.dir, e))?;
    }
    let json = serde_json::to_string_pretty(&plan).expect("a plan serialises");
    write_atomic(&dir.join("plan.json"), json.as_bytes()).map_err(|e| io("plan.json", e))?;
    write_atomic(&dir.join("jobs.txt"), jobs_text(&plan).as_bytes())
        .map_err(|e| io("jobs.txt", e))?;
    write_atomic(
        &dir.join("slurm.sbatch"),
        sbatch_text(&plan, slurm).as_bytes(),
    )
    .map_err(|e| io("slurm.sbatch", e))?;
    std::fs::create_dir_all(dir.join("logs")).map_err(|e| io("logs/", e))?;
    Ok(plan)
}

/// The command that runs one planned run, from the plan directory.
fn job_line(run: &PlannedRun) -> String {
    format!(
        "regolith run {0}/scene.ron --out {0} --claim --quiet",
        run.dir
    )
}

fn jobs_text(plan: &PlanFile) -> String {
    plan.runs.iter().map(|r| job_line(r) + "\n").collect()
}

/// `HH:MM:SS` of `seconds`, rounded up to the minute.
fn clock_time(seconds: f64) -> String {
    let minutes = (seconds / 60.0).ceil() as u64;
    format!("{:02}:{:02}:00", minutes / 60, minutes % 60)
}

fn sbatch_text(plan: &PlanFile, slurm: &SlurmOptions) -> String {
    let slowest = plan.runs.iter().map(|r| r.estimated_s).fold(0.0, f64::max);
    let time = slurm
        .time
        .clone()
        .unwrap_or_else(|| clock_time((3.0 * slowest).max(600.0)));
    let cpus = slurm.cpus.max(1);
    let mut s = String::new();
    let _ = writeln!(s, "#!/bin/bash");
    let _ = writeln!(
        s,
        "# A Slurm job array over the lines of jobs.txt, written by `regolith {} --plan`.\n\
         # Submit from this directory: sbatch slurm.sbatch. Resubmitting is safe: finished\n\
         # runs are skipped and runs held by a live task are left to it. The lines below\n\
         # are yours to edit (account, QOS, modules); the time is the slowest run's\n\
         # estimate tripled ({:.1} s estimated).",
        plan.kind, slowest
    );
    let _ = writeln!(s, "#SBATCH --job-name={}", plan.name);
    let limit = slurm.max_running.map_or(String::new(), |m| format!("%{m}"));
    let _ = writeln!(s, "#SBATCH --array=1-{}{limit}", plan.runs.len());
    let _ = writeln!(s, "#SBATCH --ntasks=1");
    let _ = writeln!(s, "#SBATCH --cpus-per-task={cpus}");
    let _ = writeln!(s, "#SBATCH --time={time}");
    if let Some(p) = &slurm.partition {
        let _ = writeln!(s, "#SBATCH --partition={p}");
    }
    let _ = writeln!(s, "#SBATCH --output=logs/%a.out");
    let _ = writeln!(s, "#SBATCH --error=logs/%a.err");
    let _ = writeln!(s);
    let _ = writeln!(s, "set -euo pipefail");
    let _ = writeln!(s, "cd \"${{SLURM_SUBMIT_DIR:-.}}\"");
    let _ = writeln!(s, "export RAYON_NUM_THREADS={cpus}");
    let _ = writeln!(
        s,
        "line=$(sed -n \"${{SLURM_ARRAY_TASK_ID}}p\" jobs.txt)\n\
         [ -n \"$line\" ] || {{ echo \"jobs.txt has no line $SLURM_ARRAY_TASK_ID\" >&2; exit 2; }}\n\
         eval \"$line\""
    );
    s
}

/// Reads `dir/plan.json`, with a one-line error when `dir` holds no plan.
pub fn read_plan(dir: &Path) -> Result<PlanFile, Error> {
    let path = dir.join("plan.json");
    let origin = path.display().to_string();
    let text = std::fs::read_to_string(&path).map_err(|_| {
        SceneError::file(
            &dir.display().to_string(),
            "not a plan directory (no plan.json; write one with `regolith sweep SWEEP.ron --plan DIR` or `regolith study STUDY.ron --plan DIR`)",
        )
    })?;
    let plan: PlanFile = serde_json::from_str(&text)
        .map_err(|e| SceneError::at(&origin, e.line(), e.column(), format!("not a plan: {e}")))?;
    match (plan.kind.as_str(), &plan.study) {
        ("sweep", None) | ("study", Some(_)) => {}
        ("study", None) => {
            return Err(SceneError::file(&origin, "a study plan without its study").into());
        }
        (kind, _) => {
            return Err(SceneError::file(&origin, format!("unknown plan kind `{kind}`")).into());
        }
    }
    Ok(plan)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn times_round_up_to_the_minute() {
        assert_eq!(clock_time(600.0), "00:10:00");
        assert_eq!(clock_time(601.0), "00:11:00");
        assert_eq!(clock_time(3.0 * 3600.0 + 1.0), "03:01:00");
    }

    #[test]
    fn the_digest_tells_texts_apart() {
        assert_eq!(digest(""), "cbf29ce484222325");
        assert_ne!(digest("a"), digest("b"));
    }
}
