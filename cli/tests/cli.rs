//! The `regolith` command as a user scripts it: outputs, exit codes, one-line errors.

use std::path::Path;
use std::process::{Command, Output};

/// Path of a shipped scene (the scenes live at the workspace root).
fn scene_path(name: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../scenes")
        .join(format!("{name}.ron"))
}

fn regolith(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_regolith"))
        .args(args)
        .output()
        .expect("the binary runs")
}

/// `regolith run scene --quiet --set time.end=0.02 --out out [extra]`, on `threads` threads
/// when given; the run must succeed. Returns `out`.
fn run_to_20_ms(
    scene: &Path,
    out: &Path,
    threads: Option<&str>,
    extra: &[&str],
) -> std::path::PathBuf {
    let mut command = Command::new(env!("CARGO_BIN_EXE_regolith"));
    if let Some(threads) = threads {
        command.env("RAYON_NUM_THREADS", threads);
    }
    let o = command
        .args(["run", scene.to_str().unwrap(), "--quiet"])
        .args(["--set", "time.end=0.02", "--out", out.to_str().unwrap()])
        .args(extra)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    out.to_path_buf()
}

fn read_json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

#[test]
fn run_writes_summary_and_trajectory() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("column");
    let scene = scene_path("elastic_column_gravity");
    let o = regolith(&[
        "run",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--set",
        "time.end=0.05",
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s = read_json(&out.join("summary.json"));
    assert_eq!(s["status"], "completed");
    assert_eq!(s["scene"], "elastic_column_gravity");
    assert_eq!(s["time"], 0.05);
    for key in [
        "steps",
        "dt",
        "cfl",
        "particles",
        "wall_s",
        "particle_steps_per_s",
    ] {
        assert!(s[key].as_f64().unwrap() > 0.0, "{key} = {}", s[key]);
    }
    assert!(s["cfl"].as_f64().unwrap() <= 0.5 + 1e-12);
    let body = &s["bodies"][0];
    assert_eq!(body["name"], "column");
    assert!(body["kinetic_energy"].as_f64().unwrap() > 0.0);
    assert_eq!(body["centre_of_mass"].as_array().unwrap().len(), 2);
    let hash = body["state_hash"].as_str().unwrap();
    assert!(
        hash.len() == 16 && hash.chars().all(|c| c.is_ascii_hexdigit()),
        "state_hash {hash}"
    );
    let csv = std::fs::read_to_string(out.join("trajectory.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(
        lines.next().unwrap(),
        "t,column_x,column_y,column_vx,column_vy,column_depth,column_fx,column_fy"
    );
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    // t = 0, every 5 ms up to 50 ms: 11 rows.
    assert_eq!(rows.len(), 11, "{csv}");
    assert_eq!(rows[0][0], 0.0);
    assert_eq!(rows[10][0], 0.05);
    assert!(!out.join("trajectory.csv.part").exists());
    assert!(out.join("scene.ron").exists());
    assert!(out.join("snapshots/snapshot_00000.csv").exists());
}

#[test]
fn a_failing_run_keeps_its_outputs_and_says_why() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("escape");
    let scene = scene_path("elastic_column_gravity");
    let o = regolith(&[
        "run",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--set",
        "bodies.column.velocity=(0.0, 20.0)",
        "--quiet",
        "--vtk",
        "0.005",
    ]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("left the domain through the top"), "{err}");
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    let s = read_json(&out.join("summary.json"));
    assert_eq!(s["status"], "failed");
    assert!(s["failure"].as_str().unwrap().contains("column"));
    let csv = std::fs::read_to_string(out.join("trajectory.csv")).unwrap();
    assert!(
        csv.lines().count() >= 2,
        "the rows before the fault are kept"
    );
    // the VTK frames written before the fault are kept, and the collection lists each
    let pvd = std::fs::read_to_string(out.join("vtk/points.pvd")).unwrap();
    let files: Vec<&str> = pvd
        .lines()
        .filter_map(|l| l.split("file=\"").nth(1)?.split('"').next())
        .collect();
    assert!(files.len() >= 2, "{pvd}");
    for f in files {
        assert!(out.join("vtk").join(f).exists(), "{f} listed, not written");
    }
}

#[test]
fn check_prints_the_resolved_setup() {
    let scene = scene_path("elastic_bar_vibration");
    let o = regolith(&["check", scene.to_str().unwrap()]);
    assert!(o.status.success());
    let text = String::from_utf8_lossy(&o.stdout);
    for part in [
        "60 x 4 cells",
        "800 points",
        "first dt",
        "memory",
        "bytes per point",
        "transfer: AffineFlip",
        "p-wave speed 116.0",
    ] {
        assert!(text.contains(part), "missing {part:?} in\n{text}");
    }
}

#[test]
fn user_errors_are_one_line_without_panic() {
    let scene = scene_path("elastic_bar_vibration");
    let scene = scene.to_str().unwrap();
    let cases: &[(&[&str], &str)] = &[
        (&["run", "no/such/scene.ron"], "cannot read the scene"),
        (
            &["check", scene, "--set", "time.end=-1"],
            "time.end must be a positive",
        ),
        (
            &["check", scene, "--set", "bodies.bar.nope.x=1"],
            "no field `nope`",
        ),
        (&["check", scene, "--set", "garbage"], "key.path=value"),
        (
            &["check", scene, "--set", "integration=Quadratic"],
            "Quadratic",
        ),
        (&["check", scene, "--set", "preset=Quick"], "Quick"),
    ];
    for (args, expected) in cases {
        let o = regolith(args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
        assert!(
            err.starts_with("error: ") && err.contains(expected),
            "{args:?}: {err}"
        );
        assert_eq!(err.trim().lines().count(), 1, "{args:?}: {err}");
        assert!(!err.contains("panicked"));
    }
    // A call the command-line parser refuses exits with 2 (README, "Errors").
    for args in [
        &[][..],
        &["run", scene, "--preset", "quick"],
        &["run", scene, "--no-such-flag"],
    ] {
        let o = regolith(args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(
            err.contains("Usage") || err.contains("--help"),
            "{args:?}: {err}"
        );
    }
}

/// The command line: a run with checkpoints, resumed from its last one, ends with the same
/// summary bodies and trajectory as a run without.
#[test]
fn regolith_resume_finishes_a_run_identically() {
    let bin = env!("CARGO_BIN_EXE_regolith");
    let dir = tempfile::tempdir().unwrap();
    let scene = scene_path("contact_incline");
    let plain = run_to_20_ms(&scene, &dir.path().join("plain"), None, &[]);
    let checked = dir.path().join("checked");
    run_to_20_ms(&scene, &checked, None, &["--checkpoint-every", "100"]);
    assert!(checked.join("checkpoint.bin").exists());
    let o = Command::new(bin)
        .args(["resume", checked.to_str().unwrap(), "--quiet"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let body = |d: &std::path::Path| {
        let s: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(d.join("summary.json")).unwrap())
                .unwrap();
        (s["bodies"].clone(), s["steps"].clone())
    };
    assert_eq!(body(&plain), body(&checked));
    assert_eq!(
        std::fs::read_to_string(plain.join("trajectory.csv")).unwrap(),
        std::fs::read_to_string(checked.join("trajectory.csv")).unwrap()
    );
}

/// The state hash in `summary.json` lets a user check a run on another thread count: a
/// scene with two bodies in frictional contact ends bitwise the same on one and two threads.
#[test]
fn the_state_hash_is_the_same_on_one_and_two_threads() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene_path("contact_incline");
    let hashes = |threads: &str| {
        let out = run_to_20_ms(&scene, &dir.path().join(threads), Some(threads), &[]);
        let s = read_json(&out.join("summary.json"));
        assert_eq!(s["threads"].as_u64().unwrap().to_string(), threads);
        s["bodies"]
            .as_array()
            .unwrap()
            .iter()
            .map(|b| b["state_hash"].as_str().unwrap().to_string())
            .collect::<Vec<_>>()
    };
    let (one, two) = (hashes("1"), hashes("2"));
    assert_eq!(one.len(), 2);
    assert_eq!(one, two);
}

/// `--rrd` records with one flag: the file is a valid recording holding every body's points.
#[test]
fn run_records_for_rerun_with_one_flag() {
    use regolith_rerun::rerun::{ChunkStore, ChunkStoreConfig, StoreKind};
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let rrd = dir.path().join("impact.rrd");
    let scene = scene_path("impact_tipped_coarse");
    let o = regolith(&[
        "run",
        scene.to_str().unwrap(),
        "--quiet",
        "--set",
        "time.end=0.005",
        "--out",
        out.to_str().unwrap(),
        "--rrd",
        rrd.to_str().unwrap(),
        "--color",
        "plastic-strain-rate",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let mut file = std::fs::File::open(&rrd).unwrap();
    let stores = ChunkStore::from_rrd_reader(&ChunkStoreConfig::DEFAULT, &mut file).unwrap();
    let store = stores
        .iter()
        .find(|(id, _)| id.kind() == StoreKind::Recording)
        .map(|(_, s)| s)
        .expect("a recording");
    let paths: Vec<String> = store
        .iter_physical_chunks()
        .map(|c| c.entity_path().to_string())
        .collect();
    for p in [
        "/world/bed/points",
        "/world/intruder/points",
        "/plots/intruder/depth",
    ] {
        assert!(paths.iter().any(|q| q == p), "{p} not recorded");
    }
    // Nothing else changes: the run's own outputs are written as without recording.
    assert!(out.join("summary.json").exists() && out.join("trajectory.csv").exists());
}

/// `--rrd` with a relative path writes into the run directory (as the README and a
/// scene's `Rerun(file: ..)` have it), never into the directory the command ran from, and
/// the run's last line and summary.json say where the recording is.
#[test]
fn a_relative_rrd_goes_into_the_run_directory_and_is_named_at_the_end() {
    let dir = tempfile::tempdir().unwrap();
    let (out, cwd) = (dir.path().join("run"), dir.path().join("elsewhere"));
    std::fs::create_dir_all(&cwd).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_regolith"))
        .current_dir(&cwd)
        .args([
            "run",
            scene_path("impact_tipped_coarse").to_str().unwrap(),
            "--quiet",
            "--set",
            "time.end=0.002",
            "--out",
            out.to_str().unwrap(),
            "--rrd",
            "rec.rrd",
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(out.join("rec.rrd").is_file() && !cwd.join("rec.rrd").exists());
    let said = String::from_utf8_lossy(&o.stdout);
    let last = said.lines().last().unwrap_or_default();
    let path = out.canonicalize().unwrap().join("rec.rrd");
    assert!(
        last.contains(&format!("recording: {}", path.display())),
        "{said}"
    );
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["recording"], path.display().to_string());
}

/// A scene that lists its own `Rerun(..)` output, run with `--rrd`: one recording is made
/// (the command line's), and the run says that it replaced the scene's.
#[test]
fn rrd_says_it_replaces_the_scenes_recording() {
    let dir = tempfile::tempdir().unwrap();
    let own = dir.path().join("own.rrd");
    let text = std::fs::read_to_string(scene_path("impact_tipped_coarse"))
        .unwrap()
        .replace(
            "outputs: [Impact(",
            &format!(
                "outputs: [Rerun(file: {:?}), Impact(",
                own.display().to_string()
            ),
        );
    let scene = dir.path().join("recorded.ron");
    std::fs::write(&scene, text).unwrap();
    let cli = dir.path().join("cli.rrd");
    let o = regolith(&[
        "run",
        scene.to_str().unwrap(),
        "--quiet",
        "--set",
        "domain.cells=(25, 25)",
        "--set",
        "time.end=0.002",
        "--out",
        dir.path().join("out").to_str().unwrap(),
        "--rrd",
        cli.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("replaces the scene's own Rerun(..) output"),
        "{err}"
    );
    assert!(cli.exists() && !own.exists());
}

#[test]
fn recording_options_without_a_recording_are_an_error() {
    let scene = scene_path("impact_tipped_coarse");
    let o = regolith(&["run", scene.to_str().unwrap(), "--color", "phase"]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("need --rrd FILE or --spawn"), "{err}");
    let dir = tempfile::tempdir().unwrap();
    let rrd = dir.path().join("x.rrd");
    let o = regolith(&[
        "run",
        scene.to_str().unwrap(),
        "--rrd",
        rrd.to_str().unwrap(),
        "--color",
        "colour-of-money",
    ]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("--color colour-of-money: expected one of pressure, plastic-strain-rate")
            && err.lines().count() == 1,
        "{err}"
    );
}

/// `--vtk SECONDS` writes ParaView's files with one flag; the grid needs `--vtk`, and a bad
/// interval is refused in one line before anything runs.
#[test]
fn run_writes_vtk_files_with_one_flag() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene_path("impact_tipped_coarse");
    let out = run_to_20_ms(
        &scene,
        &dir.path().join("run"),
        None,
        &["--vtk", "0.01", "--vtk-grid"],
    );
    let pvd = std::fs::read_to_string(out.join("vtk/points.pvd")).unwrap();
    // t = 0, 0.01, 0.02 for the bed and the intruder
    assert_eq!(pvd.matches("<DataSet ").count(), 6, "{pvd}");
    for file in [
        "bed_00002.vtu",
        "intruder_00002.vtu",
        "intruder_grid_00002.vti",
        "grid.pvd",
    ] {
        assert!(out.join("vtk").join(file).exists(), "{file} not written");
    }
    let o = regolith(&["run", scene.to_str().unwrap(), "--vtk-grid"]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("--vtk <SECONDS>"));
    let o = regolith(&["run", scene.to_str().unwrap(), "--vtk=0"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        err.contains("--vtk")
            && err.contains("every must be a positive number of seconds, got 0")
            && err.lines().count() == 1,
        "{err}"
    );
}

/// A synthetic run of a constant deceleration (f only, h = 0), z = v0 t - a t^2 / 2 with
/// a = 20 m/s^2, written as `regolith run` writes a run (with `scene` as its scene.ron).
fn write_decelerating_run(run: &Path, v0: f64, scene: Option<&str>) {
    std::fs::create_dir_all(run).unwrap();
    let a = 20.0;
    let mut csv = String::from("t,intruder_x,intruder_y,intruder_vx,intruder_vy\n");
    let mut t = 0.0;
    while v0 - a * t > 0.0 {
        let z = v0 * t - 0.5 * a * t * t;
        csv.push_str(&format!("{t},0.5,{},0,{}\n", 0.6 - z, -(v0 - a * t)));
        t += 1e-3;
    }
    std::fs::write(run.join("trajectory.csv"), csv).unwrap();
    std::fs::write(
        run.join("summary.json"),
        r#"{"status": "completed", "gravity": [0.0, -9.81], "cell_size": 0.01,
            "bodies": [{"name": "intruder", "mass": 2.0}], "impact": {"contact_time": 0.0}}"#,
    )
    .unwrap();
    if let Some(scene) = scene {
        std::fs::write(run.join("scene.ron"), scene).unwrap();
    }
}

/// `regolith fit` on run directories: writes the table, and says clearly when it cannot fit.
#[test]
fn fit_writes_a_table_or_says_why_not() {
    let dir = tempfile::tempdir().unwrap();
    for (k, v0) in [2.0f64, 3.0, 4.0].iter().enumerate() {
        write_decelerating_run(&dir.path().join(format!("run{k}")), *v0, None);
    }
    let run = |k: usize| dir.path().join(format!("run{k}"));
    let arg = |p: &Path| p.to_str().unwrap().to_string();
    // `regolith fit` on the three runs with `extra` arguments.
    let fit_all = |extra: &[&str]| {
        let runs: Vec<String> = (0..3).map(|k| arg(&run(k))).collect();
        let mut args: Vec<&str> = vec!["fit"];
        args.extend(runs.iter().map(String::as_str));
        args.extend(extra);
        regolith(&args)
    };
    let o = fit_all(&["--depths", "0.01:0.08:8"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // Written beside the runs, not into the first run's own record.
    let table = dir.path().join("poncelet.csv");
    assert!(!run(0).join("poncelet.csv").exists());
    let text = std::fs::read_to_string(&table).unwrap();
    let rows: Vec<&str> = text.lines().collect();
    assert_eq!(rows[0], "depth,f,h,runs,residual,f_error,h_error,condition");
    assert_eq!(rows.len(), 9, "{text}");
    // m (g - z'') = m (g + a) everywhere: f = 2 x 29.81, h = 0.
    for row in &rows[1..] {
        let v: Vec<f64> = row.split(',').map(|c| c.parse().unwrap()).collect();
        assert!((v[1] - 59.62).abs() < 0.05 && v[2].abs() < 0.01, "{row}");
    }
    // Two runs determine f and h exactly: refused, in one line.
    let o = regolith(&["fit", &arg(&run(0)), &arg(&run(1))]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("3 or more speeds") && err.lines().count() == 1,
        "{err}"
    );
    // The same run twice.
    let o = regolith(&["fit", &arg(&run(0)), &arg(&run(1)), &arg(&run(0))]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("given twice"), "{err}");
    // Depths no run reaches: nothing fitted is a failure, not an empty table.
    let deep = arg(&dir.path().join("deep.csv"));
    let o = fit_all(&["--depths", "5:6:3", "--out", &deep]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("none of the 3 depths") && err.lines().count() == 1,
        "{err}"
    );
    assert!(!dir.path().join("deep.csv").exists());
    let o = regolith(&["fit", "/nonexistent/run"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("summary.json"), "{err}");
}

/// Runs of two shapes given together (one sweep over slope and speed) are fitted as two
/// groups, each alone with its own table, and the output says which is which; a group with
/// too few speeds is refused by name while the other is still written.
#[test]
fn fit_fits_each_shape_of_a_mixed_sweep_alone() {
    let dir = tempfile::tempdir().unwrap();
    let scene = |slope: &str, v: f64| {
        format!(
            "// shape {slope}\nScene(\n    time: (end: 0.3),\n    bodies: [(name: \"intruder\", shape: Tip(slope: {slope}), velocity: (0.0, -{v}))],\n)\n"
        )
    };
    let mut args = vec!["fit".to_string()];
    for (k, (slope, v0)) in [
        ("1.0", 2.0),
        ("2.0", 2.0),
        ("1.0", 3.0),
        ("2.0", 3.0),
        ("1.0", 4.0),
    ]
    .iter()
    .enumerate()
    {
        let run = dir.path().join(format!("run{k}"));
        write_decelerating_run(&run, *v0, Some(&scene(slope, *v0)));
        args.push(run.to_str().unwrap().to_string());
    }
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let o = regolith(&args);
    let (out, err) = (
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr),
    );
    assert!(!o.status.success(), "{out}");
    assert!(
        out.contains("5 runs of 2 scenes")
            && out.contains("group 1 (slope:1.0: ")
            && out.contains("3 runs, 20 of 20 depths fitted"),
        "{out}"
    );
    assert!(
        err.contains("group 2 (slope:2.0: ") && err.contains("got 2 run(s)"),
        "{err}"
    );
    assert!(dir.path().join("poncelet_1.csv").is_file());
    assert!(!dir.path().join("poncelet_2.csv").exists());
    assert!(!dir.path().join("poncelet.csv").exists());
    // A third speed of the second shape: both are fitted.
    let run = dir.path().join("run5");
    write_decelerating_run(&run, 4.0, Some(&scene("2.0", 4.0)));
    let mut all = args.clone();
    all.push(run.to_str().unwrap());
    let o = regolith(&all);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(dir.path().join("poncelet_2.csv").is_file());
    // Runs of one shape: one table as before, under its usual name.
    let o = regolith(&[args[0], args[1], args[3], args[5]]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(dir.path().join("poncelet.csv").is_file());
}

/// A run that ends while the intruder still moves reports no final depth or stopping
/// time: `summary.json` says `at_rest: false` and why, the run's last line says so, and
/// `fit` refuses the run instead of fitting half a trajectory.
#[test]
fn an_impact_cut_short_has_no_final_depth_and_fit_refuses_it() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("short");
    let scene = scene_path("impact_tipped_coarse");
    let o = regolith(&[
        "run",
        scene.to_str().unwrap(),
        "--set",
        "domain.cells=(25, 25)",
        "--set",
        "time.end=0.02",
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        stdout.contains("impact: NOT at rest, no final depth"),
        "{stdout}"
    );
    let s = read_json(&out.join("summary.json"));
    let impact = &s["impact"];
    assert_eq!(impact["at_rest"], false, "{impact}");
    assert!(impact["final_depth"].is_null() && impact["stopping_time"].is_null());
    assert!(impact["depth_at_end"].as_f64().unwrap() > 0.0);
    assert!(
        impact["not_at_rest"]
            .as_str()
            .unwrap()
            .contains("speed at the end")
    );
    assert_eq!(s["units"]["impact.final_depth"], "m");
    let o = regolith(&["fit", out.to_str().unwrap(), out.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("not at rest"), "{err}");
}

/// SIGINT: the run finishes its step, writes `checkpoint.bin` and a summary marked
/// `interrupted`, says how to resume and exits with 130; `regolith resume` then ends in the
/// same state as a run never interrupted.
#[cfg(unix)]
#[test]
fn an_interrupted_run_keeps_its_record_and_resumes() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene_path("impact_tipped_coarse");
    let args = |out: &Path| -> Vec<String> {
        [
            "run",
            scene.to_str().unwrap(),
            "--quiet",
            "--set",
            "domain.cells=(25, 25)",
            "--set",
            "time.end=0.3",
            "--out",
            out.to_str().unwrap(),
        ]
        .iter()
        .map(|s| s.to_string())
        .collect()
    };
    let out = dir.path().join("cut");
    let child = Command::new(env!("CARGO_BIN_EXE_regolith"))
        .args(args(&out))
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // Wait until the run is stepping (its trajectory has its first row, at t = 0), then
    // interrupt it: the whole run (about 3 s) is the margin by which the signal comes
    // before its end, and the run stops after the step the signal finds it in, at t > 0.
    let part = out.join("trajectory.csv.part");
    let started = std::time::Instant::now();
    while std::fs::read_to_string(&part).map_or(0, |t| t.lines().count()) < 2 {
        assert!(started.elapsed().as_secs() < 60, "the run never started");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    let kill = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(kill.success());
    let o = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(130), "{err}");
    assert!(err.contains("regolith resume"), "{err}");
    let s = read_json(&out.join("summary.json"));
    assert_eq!(s["status"], "interrupted");
    let t = s["time"].as_f64().unwrap();
    assert!(t > 0.0 && t < 0.3, "{t}");
    assert!(out.join("checkpoint.bin").exists());

    let o = regolith(&["resume", out.to_str().unwrap(), "--quiet"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let whole = dir.path().join("whole");
    let a: Vec<String> = args(&whole);
    let a: Vec<&str> = a.iter().map(|s| s.as_str()).collect();
    let o = regolith(&a);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (resumed, uncut) = (
        read_json(&out.join("summary.json")),
        read_json(&whole.join("summary.json")),
    );
    assert_eq!(resumed["status"], "completed");
    for b in 0..2 {
        assert_eq!(
            resumed["bodies"][b]["state_hash"], uncut["bodies"][b]["state_hash"],
            "body {b}"
        );
    }
    assert_eq!(resumed["impact"], uncut["impact"]);
}
