//! A run interrupted at two points and resumed must leave every file the uninterrupted run
//! leaves, byte for byte, and the same summary but for what measures the machine (issue 35).
//! Shared by the engine's tests and the plugin crates' (included by path).

use std::path::{Path, PathBuf};
use std::sync::Arc;

use regolith::error::Error;
use regolith::registry::Registries;
use regolith::run::{CheckpointEvery, Provenance, StopAfter, resume_run, run_scene};
use regolith::scene::Scene;

/// The summary fields that measure the run's machine and wall clock, not its results.
const MACHINE: [&str; 5] = [
    "wall_s",
    "particle_steps_per_s",
    "timings_s",
    "host",
    "threads",
];

fn run(
    file: &Path,
    sets: &[String],
    registries: &Arc<Registries>,
    out: &Path,
    stop: Option<u64>,
) -> Result<(), Error> {
    let (scene, text) = Scene::load(file, sets, registries).unwrap_or_else(|e| panic!("{e}"));
    let from = Provenance {
        file: &file.display().to_string(),
        text: &text,
        overrides: sets,
    };
    run_scene(
        &scene,
        &from,
        out,
        CheckpointEvery(None),
        &mut StopAfter(stop.unwrap_or(u64::MAX)),
    )
    .map(|_| ())
}

fn summary(dir: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(dir.join("summary.json")).unwrap();
    serde_json::from_str(&text).unwrap()
}

/// Every file below `dir`, relative to it, sorted.
fn files(dir: &Path) -> Vec<PathBuf> {
    let mut found = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let path = e.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else {
                found.push(path.strip_prefix(dir).unwrap().to_path_buf());
            }
        }
    }
    found.sort();
    found
}

/// Runs the scene in `file`, straight and interrupted after a third and two thirds of its
/// steps and resumed twice, and compares the two run directories. With a `budget` of
/// particle-steps the end time is cut to the time a first run reaches in about that many
/// (at most 600 steps). Returns the number of steps and of files compared.
pub fn check(file: &Path, registries: &Arc<Registries>, budget: Option<f64>) -> (u64, usize) {
    let root = tempfile::tempdir().unwrap();
    let name = file.display().to_string();
    let mut sets = Vec::new();
    if let Some(budget) = budget {
        // How far the budget goes: a probe interrupted when it is spent.
        let (scene, _) = Scene::load(file, &[], registries).unwrap_or_else(|e| panic!("{e}"));
        let points: usize = regolith::Simulation::new(&scene)
            .bodies()
            .iter()
            .map(|b| b.2)
            .sum();
        let steps = (budget / points.max(1) as f64).clamp(9.0, 600.0) as u64;
        let probe = root.path().join("probe");
        let _ = run(file, &[], registries, &probe, Some(steps));
        let end = summary(&probe)["time"].as_f64().unwrap();
        sets.push(format!("time.end={end:e}"));
    }

    let straight = root.path().join("straight");
    run(file, &sets, registries, &straight, None).unwrap_or_else(|e| panic!("{name}: {e}"));
    let total = summary(&straight)["steps"].as_u64().unwrap();
    assert!(
        total >= 3,
        "{name}: {total} steps are too few to interrupt twice"
    );

    let cut = root.path().join("interrupted");
    let (first, second) = (total / 3, 2 * total / 3);
    let interrupted = |r: Result<(), Error>, at: u64| match r {
        Err(Error::Interrupted { .. }) => {}
        other => panic!("{name}: the run stopped at step {at} ended with {other:?}"),
    };
    interrupted(run(file, &sets, registries, &cut, Some(first)), first);
    let resume = |stop: Option<u64>| {
        resume_run(
            registries,
            &cut,
            CheckpointEvery(None),
            |_| Ok(()),
            &mut StopAfter(stop.unwrap_or(u64::MAX)),
        )
        .map(|_| ())
    };
    interrupted(resume(Some(second)), second);
    resume(None).unwrap_or_else(|e| panic!("{name}: the last resume failed: {e}"));

    let mut listed = files(&straight);
    let mut resumed = files(&cut);
    resumed.retain(|f| f != Path::new("checkpoint.bin"));
    listed.retain(|f| f != Path::new("checkpoint.bin"));
    assert_eq!(resumed, listed, "{name}: the resumed run left other files");
    for f in &listed {
        if f == Path::new("summary.json") {
            continue;
        }
        let (a, b) = (
            std::fs::read(straight.join(f)).unwrap(),
            std::fs::read(cut.join(f)).unwrap(),
        );
        assert!(
            a == b,
            "{name}: {} differs after two resumes ({} bytes straight, {} resumed)",
            f.display(),
            a.len(),
            b.len()
        );
    }
    let (mut a, mut b) = (summary(&straight), summary(&cut));
    for key in MACHINE {
        a.as_object_mut().unwrap().remove(key);
        b.as_object_mut().unwrap().remove(key);
    }
    for (key, value) in a.as_object().unwrap() {
        assert_eq!(
            Some(value),
            b.get(key),
            "{name}: summary.json's {key} differs"
        );
    }
    assert_eq!(a, b, "{name}: summary.json differs");
    assert_eq!(
        b["partial"], false,
        "{name}: the resumed run says it is partial"
    );
    (total, listed.len())
}

/// [`check`] for every scene file in `dir`, each cut to `budget` particle-steps.
pub fn check_scenes(dir: &Path, registries: &Arc<Registries>, budget: f64) -> usize {
    let mut scenes: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "ron"))
        .collect();
    scenes.sort();
    for scene in &scenes {
        let (steps, files) = check(scene, registries, Some(budget));
        eprintln!("{}: {steps} steps, {files} files equal", scene.display());
    }
    scenes.len()
}
