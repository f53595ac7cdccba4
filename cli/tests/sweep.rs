//! `regolith sweep`: the cross product, one CSV row per run, resumable.

use std::process::Command;

#[test]
fn a_sweep_runs_the_cross_product_and_resumes() {
    let dir = tempfile::tempdir().unwrap();
    let scenes = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
    let sweep = dir.path().join("s.ron");
    std::fs::write(
        &sweep,
        format!(
            r#"Sweep(
                name: "tiny",
                scene: "{}",
                set: ["time.end=0.005"],
                vary: [
                    (key: "bodies.intruder.velocity", values: ["(0.0, -2.0)", "(0.0, -4.0)"]),
                    (key: "contact", values: ["NoSlip", "Frictional(friction: 0.1)"]),
                ],
                jobs: 2,
            )"#,
            scenes.join("impact_tipped_coarse.ron").display()
        ),
    )
    .unwrap();
    let out = dir.path().join("out");
    let run = || {
        let o = Command::new(env!("CARGO_BIN_EXE_regolith"))
            .args([
                "sweep",
                sweep.to_str().unwrap(),
                "--out",
                out.to_str().unwrap(),
            ])
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        String::from_utf8_lossy(&o.stdout).into_owned()
    };
    run();
    let csv = std::fs::read_to_string(out.join("sweep.csv")).unwrap();
    let rows: Vec<&str> = csv.lines().skip(1).collect();
    assert_eq!(rows.len(), 4, "{csv}");
    assert!(rows.iter().all(|r| r.contains(",completed,")), "{csv}");
    assert!(
        rows[0].starts_with("run_0001,\"(0.0, -2.0)\",NoSlip,"),
        "{csv}"
    );
    // The impact energy column follows the speed: 4x for twice the speed.
    let energy = |r: &str| -> f64 { r.split(',').nth(10).unwrap().parse().unwrap() };
    assert!(
        (energy(rows[2]) / energy(rows[0]) - 4.0).abs() < 1e-9,
        "{csv}"
    );

    std::fs::remove_file(out.join("run_0003/summary.json")).unwrap();
    let again = run();
    assert!(
        again.contains("3 of 4 runs already completed, skipped"),
        "{again}"
    );
    assert!(
        again.contains("run_0003: completed") && !again.contains("run_0001: completed"),
        "{again}"
    );
}
