//! `regolith study`: a tiny study (the coarse impact on 12-20 cells, to 0.4 s so that every
//! intruder is at rest: a run cut short has no final depth to compare) plans one run per distinct
//! setting, measures every row against the named reference, marks the frontier, draws the
//! plot, and skips finished runs when run again.

#[path = "../../tests/common/mod.rs"]
mod common;

use std::sync::Mutex;

use regolith::Regolith;
use regolith_lab::batch::BatchFile;
use regolith_lab::study::Study;
use regolith_lab::workers::run_local;

fn write_study(dir: &std::path::Path) -> std::path::PathBuf {
    let scene = common::scene_path("impact_tipped_coarse");
    let text = format!(
        r#"Study(
    name: "tiny",
    scene: "{}",
    set: ["time.end=0.4", "domain.cells=(12, 12)"],
    reference: (label: "20 cells, CFL 0.3", set: ["domain.cells=(20, 20)", "time.step=Cfl(0.3)"]),
    knobs: [
        (name: "cells", values: [(label: "12", set: []), (label: "16", set: ["domain.cells=(16, 16)"])]),
        (name: "CFL", values: [(label: "0.5", set: []), (label: "0.3", set: ["time.step=Cfl(0.3)"])]),
        (name: "contact", model: true, values: [(label: "no-slip", set: ["contact=NoSlip"])]),
    ],
    jobs: 2,
)"#,
        scene.display()
    );
    let path = dir.join("tiny.ron");
    std::fs::write(&path, text).unwrap();
    path
}

/// The fields of one CSV line (fields with commas are quoted).
fn split_csv(line: &str) -> Vec<String> {
    let (mut fields, mut current, mut quoted) = (Vec::new(), String::new(), false);
    for c in line.chars() {
        match c {
            '"' => quoted = !quoted,
            ',' if !quoted => fields.push(std::mem::take(&mut current)),
            _ => current.push(c),
        }
    }
    fields.push(current);
    fields
}

fn run(path: &std::path::Path, out: &std::path::Path) -> Vec<String> {
    let study = Study::load(path).unwrap();
    let registries = Regolith::default().registries();
    let lines = Mutex::new(Vec::new());
    let failed = run_local(path, &study, out, Some(2), &registries, |l: &str| {
        lines.lock().unwrap().push(l.to_string())
    })
    .unwrap();
    assert_eq!(failed, 0);
    lines.into_inner().unwrap()
}

#[test]
fn a_study_measures_each_knob_against_the_reference() {
    let dir = tempfile::tempdir().unwrap();
    let path = write_study(dir.path());
    let study = Study::load(&path).unwrap();
    let (runs, entries) = study.plan();
    // reference, baseline, 16 cells, CFL 0.3, no-slip: the empty settings share the baseline.
    assert_eq!(runs.len(), 5);
    assert_eq!(entries.len(), 6);
    assert!(entries.iter().filter(|e| e.run == 1).count() == 3);

    let out = dir.path().join("out");
    let first = run(&path, &out);
    assert_eq!(first.len(), 5, "{first:?}");

    let csv = std::fs::read_to_string(out.join("study.csv")).unwrap();
    let rows: Vec<Vec<String>> = csv.lines().skip(1).map(split_csv).collect();
    assert_eq!(rows.len(), 1 + entries.len());
    let reference = &rows[0];
    assert_eq!(reference[0], "reference");
    let depth_ref: f64 = reference[6].parse().unwrap();
    for row in &rows[1..] {
        assert_eq!(row[3], "completed", "{row:?}");
        // Particle-steps: points x steps, positive.
        assert!(row[5].parse::<f64>().unwrap() > 0.0);
        // The error column is |x - x_ref| / |x_ref| of the depth column.
        let depth: f64 = row[6].parse().unwrap();
        let error: f64 = row[9].parse().unwrap();
        let expected = (depth - depth_ref).abs() / depth_ref.abs();
        // The frontier's error is the larger of the depth and stopping-time errors.
        let stop_error: f64 = row[10].parse().unwrap();
        assert_eq!(row[12].parse::<f64>().unwrap(), error.max(stop_error));
        assert!(
            (error - expected).abs() < 1e-12,
            "{row:?}: {error} vs {expected}"
        );
    }
    assert!(
        rows.iter().any(|r| r[13] == "true"),
        "no run on the frontier:\n{csv}"
    );
    // A model knob is measured but never on the frontier.
    let no_slip = rows.iter().find(|r| r[0] == "contact").unwrap();
    assert_eq!(no_slip[13], "false");
    let md = std::fs::read_to_string(out.join("study.md")).unwrap();
    assert!(md.contains("**Reference**") && md.contains("20 cells, CFL 0.3"));
    assert!(out.join("pareto.png").metadata().unwrap().len() > 1000);

    // Run again: everything is already there.
    let second = run(&path, &out);
    assert!(
        second.len() == 1 && second[0].contains("5 of 5 runs already completed"),
        "{second:?}"
    );
}

/// A study of a scene without an Impact output is refused before anything runs.
#[test]
fn a_scene_without_impact_measures_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bar.ron");
    let scene = common::scene_path("elastic_bar_vibration");
    let text = format!(
        r#"Study(name: "bar", scene: "{}", reference: (label: "fine", set: []), knobs: [(name: "cfl", values: [(label: "0.3", set: ["time.step=Cfl(0.3)"])])])"#,
        scene.display()
    );
    std::fs::write(&path, text).unwrap();
    let study = Study::load(&path).unwrap();
    let registries = Regolith::default().registries();
    let out = dir.path().join("out");
    let err = run_local(&path, &study, &out, Some(1), &registries, |_: &str| {})
        .unwrap_err()
        .to_string();
    assert!(err.contains("no Impact output"), "{err}");
    assert!(!out.exists(), "nothing should have run");
}
