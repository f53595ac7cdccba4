//! `regolith sweep --plan` / `--collect` and `regolith run --claim`: a sweep run by GNU
//! parallel (or any set of workers) on a plan gives the local sweep's results, each run
//! exactly once, and survives a killed worker.

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

const BIN: &str = env!("CARGO_BIN_EXE_regolith");

/// Writes `text` into `dir/name`, with `SCENE` standing for the coarse impact scene's path.
fn batch_file(dir: &Path, name: &str, text: &str) -> PathBuf {
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/impact_tipped_coarse.ron");
    let path = dir.join(name);
    std::fs::write(&path, text.replace("SCENE", &scene.display().to_string())).unwrap();
    path
}

/// A 2 x 2 sweep of 0.005 s coarse impacts under the `accurate` preset (the plan must
/// carry the preset's settings without applying it twice), written into `dir`.
fn tiny_sweep(dir: &Path, end: f64) -> PathBuf {
    let text = r#"Sweep(
        name: "tiny",
        scene: "SCENE",
        set: ["time.end=END", "preset=Accurate"],
        vary: [
            (key: "bodies.intruder.velocity", values: ["(0.0, -2.0)", "(0.0, -4.0)"]),
            (key: "contact", values: ["NoSlip", "Frictional(friction: 0.1)"]),
        ],
    )"#;
    batch_file(dir, "s.ron", &text.replace("END", &end.to_string()))
}

fn regolith(args: &[&str], cwd: &Path) -> Output {
    Command::new(BIN)
        .args(args)
        .current_dir(cwd)
        .output()
        .unwrap()
}

fn ok(o: &Output) -> String {
    assert!(
        o.status.success(),
        "{}\n{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// `PATH` with the `regolith` under test first, as a user's would have it.
fn path_with_regolith() -> String {
    let bin = Path::new(BIN).parent().unwrap().display().to_string();
    format!("{bin}:{}", std::env::var("PATH").unwrap_or_default())
}

/// Starts two copies of `command` together, waits for both, and returns their standard
/// outputs, one after the other (each must succeed).
fn two_at_once(command: impl Fn() -> Command) -> String {
    let spawn = || command().stdout(Stdio::piped()).spawn().unwrap();
    let (a, b) = (spawn(), spawn());
    [a.wait_with_output().unwrap(), b.wait_with_output().unwrap()]
        .iter()
        .map(ok)
        .collect()
}

/// Runs the plan in `plan` with `parallel -j 2 < jobs.txt`, one thread per run.
fn run_with_parallel(plan: &Path) {
    let parallel = Command::new("parallel")
        .args(["-j", "2"])
        .current_dir(plan)
        .env("PATH", path_with_regolith())
        .env("RAYON_NUM_THREADS", "1")
        .stdin(std::fs::File::open(plan.join("jobs.txt")).unwrap())
        .output()
        .unwrap_or_else(|e| {
            panic!(
                "GNU parallel is needed for this test (Debian: parallel; .ci/run installs it): {e}"
            )
        });
    ok(&parallel);
}

/// The `state_hash` column of a sweep.csv, by row.
fn hashes(csv: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(csv).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(header.last(), Some(&"state_hash"), "{text}");
    // The last field is never quoted (hex digits, names and spaces only).
    lines
        .map(|l| l.rsplit(',').next().unwrap().to_string())
        .collect()
}

#[test]
fn a_plan_run_by_gnu_parallel_gives_the_local_sweep_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let sweep = tiny_sweep(dir.path(), 0.005);
    let planned = ok(&regolith(
        &["sweep", sweep.to_str().unwrap(), "--plan", "plan"],
        dir.path(),
    ));
    assert!(planned.contains("4 runs planned"), "{planned}");
    let plan = dir.path().join("plan");
    let jobs = std::fs::read_to_string(plan.join("jobs.txt")).unwrap();
    assert_eq!(
        jobs.lines().next(),
        Some("regolith run runs/run_0001/scene.ron --out runs/run_0001 --claim --quiet")
    );
    let sbatch = std::fs::read_to_string(plan.join("slurm.sbatch")).unwrap();
    assert!(sbatch.contains("#SBATCH --array=1-4\n"), "{sbatch}");

    run_with_parallel(&plan);
    let collected = ok(&regolith(&["sweep", "--collect", "plan"], dir.path()));
    assert!(collected.contains("4 of 4 runs completed"), "{collected}");

    ok(&regolith(
        &[
            "sweep",
            sweep.to_str().unwrap(),
            "--out",
            "local",
            "--jobs",
            "2",
        ],
        dir.path(),
    ));
    // Runs of 0.005 s end with their intruders moving: no Fig. 3 to draw, and it says so.
    let figures = regolith(&["figures", "--from", "plan", "--out", "figs"], dir.path());
    assert!(!figures.status.success());
    let why = String::from_utf8_lossy(&figures.stderr);
    assert!(
        why.contains("no completed run with its intruder at rest to draw (4 left out)"),
        "{why}"
    );
    // Without --out the figures go under the sweep, never into the repository's docs/figures
    // (issue 38: they overwrote it).
    let figures = regolith(&["figures", "--from", "plan"], dir.path());
    assert!(!figures.status.success());
    assert!(
        !dir.path().join("docs").exists() && dir.path().join("plan/figures").is_dir(),
        "figures --from plan wrote outside plan/"
    );
    // The local sweep ran a plan of its own: collecting it rewrites the same table.
    let local_csv = std::fs::read_to_string(dir.path().join("local/sweep.csv")).unwrap();
    ok(&regolith(&["sweep", "--collect", "local"], dir.path()));
    assert_eq!(
        std::fs::read_to_string(dir.path().join("local/sweep.csv")).unwrap(),
        local_csv
    );
    let (remote, local) = (
        hashes(&plan.join("sweep.csv")),
        hashes(&dir.path().join("local/sweep.csv")),
    );
    assert_eq!(remote.len(), 4);
    assert!(
        remote
            .iter()
            .all(|h| h.contains("bed:") && h.contains("intruder:"))
    );
    assert_eq!(remote, local);
}

/// A study of three runs of 0.005 s on the coarse impact at 12 cells, written into `dir`.
fn tiny_study(dir: &Path) -> PathBuf {
    let text = r#"Study(
        name: "tiny_study",
        scene: "SCENE",
        set: ["time.end=0.005", "domain.cells=(12, 12)"],
        reference: (label: "16 cells", set: ["domain.cells=(16, 16)"]),
        knobs: [(name: "CFL", values: [(label: "0.3", set: ["time.step=Cfl(0.3)"])])],
    )"#;
    batch_file(dir, "study.ron", text)
}

/// Each run's final state hashes, read from its summary.
fn summary_hashes(run: &Path) -> String {
    let text = std::fs::read_to_string(run.join("summary.json")).unwrap();
    let s: serde_json::Value = serde_json::from_str(&text).unwrap();
    s["bodies"].to_string()
}

#[test]
fn a_study_planned_and_run_by_gnu_parallel_gives_the_local_study() {
    let dir = tempfile::tempdir().unwrap();
    let study = tiny_study(dir.path());
    let s = study.to_str().unwrap();
    let planned = ok(&regolith(&["study", s, "--plan", "plan"], dir.path()));
    assert!(planned.contains("3 runs planned"), "{planned}");
    assert!(planned.contains("regolith study --collect"), "{planned}");
    let plan = dir.path().join("plan");
    let jobs = std::fs::read_to_string(plan.join("jobs.txt")).unwrap();
    assert_eq!(
        jobs.lines().collect::<Vec<_>>(),
        [
            "regolith run runs/reference/scene.ron --out runs/reference --claim --quiet",
            "regolith run runs/baseline/scene.ron --out runs/baseline --claim --quiet",
            "regolith run runs/cfl_0.3/scene.ron --out runs/cfl_0.3 --claim --quiet",
        ]
    );
    let half = regolith(&["study", "--collect", "plan"], dir.path());
    assert!(!half.status.success());

    run_with_parallel(&plan);
    let collected = ok(&regolith(&["study", "--collect", "plan"], dir.path()));
    assert!(collected.contains("3 of 3 runs completed"), "{collected}");
    assert!(collected.contains("study.md"), "{collected}");
    let csv = std::fs::read_to_string(plan.join("study.csv")).unwrap();
    assert!(csv.contains("\nCFL,0.3,runs/cfl_0.3,"), "{csv}");

    ok(&regolith(
        &["study", s, "--out", "local", "--jobs", "2"],
        dir.path(),
    ));
    for run in ["reference", "baseline", "cfl_0.3"] {
        assert_eq!(
            summary_hashes(&plan.join("runs").join(run)),
            summary_hashes(&dir.path().join("local").join(run)),
            "{run}"
        );
    }
    // A study file with --collect is refused: collect reads only the plan.
    let both = regolith(&["study", s, "--collect", "plan"], dir.path());
    assert!(!both.status.success());
    assert!(String::from_utf8_lossy(&both.stderr).contains("without the study file"));
}

#[test]
fn two_workers_on_one_plan_run_each_run_exactly_once() {
    let dir = tempfile::tempdir().unwrap();
    let sweep = tiny_sweep(dir.path(), 0.005);
    ok(&regolith(
        &["sweep", sweep.to_str().unwrap(), "--plan", "plan"],
        dir.path(),
    ));
    let plan = dir.path().join("plan");
    // Two workers each take every line of jobs.txt in order, started together.
    let text = two_at_once(|| {
        let mut c = Command::new("sh");
        c.arg("jobs.txt")
            .current_dir(&plan)
            .env("PATH", path_with_regolith())
            .env("RAYON_NUM_THREADS", "1");
        c
    });
    for run in ["run_0001", "run_0002", "run_0003", "run_0004"] {
        let ran = text.matches(&format!("outputs in runs/{run}\n")).count();
        let skipped = text
            .lines()
            .filter(|l| l.starts_with(&format!("runs/{run}: ")) && l.ends_with("skipped"))
            .count();
        assert_eq!((ran, skipped), (1, 1), "{run}:\n{text}");
        assert!(!plan.join("runs").join(run).join("claim").exists());
    }
    ok(&regolith(&["sweep", "--collect", "plan"], dir.path()));
}

#[test]
fn a_run_left_by_a_killed_worker_is_taken_over() {
    let dir = tempfile::tempdir().unwrap();
    let sweep = tiny_sweep(dir.path(), 0.3);
    ok(&regolith(
        &["sweep", sweep.to_str().unwrap(), "--plan", "plan"],
        dir.path(),
    ));
    let plan = dir.path().join("plan");
    let run = plan.join("runs/run_0001");
    let line = [
        "run",
        "runs/run_0001/scene.ron",
        "--out",
        "runs/run_0001",
        "--claim",
        "--quiet",
    ];
    let mut first = Command::new(BIN)
        .args(line)
        .current_dir(&plan)
        .env("RAYON_NUM_THREADS", "1")
        .stdout(Stdio::null())
        .spawn()
        .unwrap();
    let started = std::time::Instant::now();
    // A running run writes trajectory.csv.part (renamed at its end).
    while !run.join("trajectory.csv.part").exists() {
        assert!(started.elapsed().as_secs() < 60, "the run did not start");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    // Killed as soon as it steps: the whole run (16 s on one thread here) is the margin
    // by which the kill comes before its end.
    first.kill().unwrap(); // SIGKILL: no chance to release the claim
    first.wait().unwrap();
    assert!(
        run.join("claim").exists(),
        "the killed worker left its claim"
    );
    assert!(!run.join("summary.json").exists(), "killed before the end");

    let collected = regolith(&["sweep", "--collect", "plan"], dir.path());
    assert!(!collected.status.success());
    let missing = String::from_utf8_lossy(&collected.stdout);
    assert!(missing.contains("missing (4): runs/run_0001"), "{missing}");

    let again = ok(&regolith(&line, &plan));
    assert!(again.contains("outputs in runs/run_0001"), "{again}");
    assert!(!run.join("claim").exists());
    let summary = std::fs::read_to_string(run.join("summary.json")).unwrap();
    assert!(summary.contains("\"status\": \"completed\""), "{summary}");
}

#[test]
fn bad_plans_are_refused_in_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let one_line = |o: &Output, needle: &str| {
        assert!(!o.status.success());
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(err.trim().lines().count(), 1, "{err}");
        assert!(err.contains(needle), "{err}");
    };
    one_line(
        &regolith(&["sweep", "--collect", "nowhere"], dir.path()),
        "not a plan directory",
    );

    let sweep = tiny_sweep(dir.path(), 0.005);
    let s = sweep.to_str().unwrap();
    ok(&regolith(&["sweep", s, "--plan", "plan"], dir.path()));
    let plan = dir.path().join("plan");
    // Half finished: one run done.
    ok(&regolith(
        &[
            "run",
            "runs/run_0002/scene.ron",
            "--out",
            "runs/run_0002",
            "--claim",
            "--quiet",
        ],
        &plan,
    ));
    let half = regolith(&["sweep", "--collect", "plan"], dir.path());
    one_line(&half, "3 of 4 runs missing or failed");
    let partial = ok(&regolith(
        &["sweep", "--collect", "plan", "--partial"],
        dir.path(),
    ));
    assert!(partial.contains("1 of 4 runs completed"), "{partial}");
    let csv = std::fs::read_to_string(plan.join("sweep.csv")).unwrap();
    assert_eq!(csv.matches(",pending,").count(), 3, "{csv}");

    // A planned scene edited by hand is reported, not collected.
    let scene = plan.join("runs/run_0003/scene.ron");
    let text = std::fs::read_to_string(&scene).unwrap();
    std::fs::write(&scene, text.replace("NoSlip", "Frictional(friction: 0.3)")).unwrap();
    let edited = ok(&regolith(
        &["sweep", "--collect", "plan", "--partial"],
        dir.path(),
    ));
    assert!(
        edited.contains("failed: runs/run_0003: its scene.ron was changed"),
        "{edited}"
    );

    // The sweep changed after planning, with a finished run that ran the old scene.
    let changed = std::fs::read_to_string(&sweep)
        .unwrap()
        .replace("(0.0, -2.0)", "(0.0, -2.5)");
    std::fs::write(&sweep, changed).unwrap();
    one_line(
        &regolith(&["sweep", s, "--plan", "plan"], dir.path()),
        "the sweep changed after",
    );
}

#[test]
fn two_local_sweeps_on_one_output_directory_share_the_runs() {
    let dir = tempfile::tempdir().unwrap();
    let sweep = tiny_sweep(dir.path(), 0.005);
    let text = two_at_once(|| {
        let mut c = Command::new(BIN);
        c.args([
            "sweep",
            sweep.to_str().unwrap(),
            "--out",
            "shared",
            "--jobs",
            "1",
        ])
        .current_dir(dir.path());
        c
    });
    for run in ["run_0001", "run_0002", "run_0003", "run_0004"] {
        let ran = text.matches(&format!("{run}: completed (")).count();
        assert_eq!(ran, 1, "{run}:\n{text}");
    }
}
