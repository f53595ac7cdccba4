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

/// The shipped Poncelet sweep (`sweeps/poncelet_s1_coarse.ron`, four speeds of the s = 1
/// intruder on the coarse grid) fitted at the default gives a drag law at every depth:
/// f and h positive and each known to better than itself. The paper's spline, the default
/// before, turns the coarse grid's crossing pulses into a negative f at some depths, and
/// `fit` says so.
#[test]
fn the_shipped_poncelet_sweep_fits_a_physical_law_at_the_default() {
    let dir = tempfile::tempdir().unwrap();
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let out = dir.path().join("pon");
    let regolith = |args: &[&str]| {
        let o = Command::new(env!("CARGO_BIN_EXE_regolith"))
            .current_dir(&root)
            .args(args)
            .output()
            .unwrap();
        let text = String::from_utf8_lossy(&o.stdout).into_owned();
        assert!(
            o.status.success(),
            "{text}{}",
            String::from_utf8_lossy(&o.stderr)
        );
        text
    };
    let out_arg = out.to_str().unwrap();
    regolith(&[
        "sweep",
        "sweeps/poncelet_s1_coarse.ron",
        "--out",
        out_arg,
        "--jobs",
        "2",
    ]);
    let said = regolith(&["fit", out_arg]);
    assert!(
        said.contains("4 runs, 20 of 20 depths fitted") && !said.contains("warning"),
        "{said}"
    );
    let table = std::fs::read_to_string(out.join("poncelet.csv")).unwrap();
    for row in table.lines().skip(1) {
        let v: Vec<f64> = row.split(',').map(|c| c.parse().unwrap()).collect();
        let (f, h, f_error, h_error) = (v[1], v[2], v[5], v[6]);
        assert!(f > 0.0 && h > 0.0 && f_error < f && h_error < h, "{row}");
    }
    let spline = out.join("spline.csv");
    let said = regolith(&[
        "fit",
        out_arg,
        "--spline",
        "--out",
        spline.to_str().unwrap(),
    ]);
    assert!(said.contains("warning"), "{said}");
}
