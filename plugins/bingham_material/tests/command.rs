//! The plugin's own command: runs the plugin's scene (a `Bingham` layer the plain `regolith`
//! command does not know) and refuses a mistyped constant at its line.

use std::process::Command;

const SCENE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/bingham_incline.ron");

fn regolith_bingham() -> Command {
    Command::new(env!("CARGO_BIN_EXE_regolith-bingham"))
}

#[test]
fn the_command_runs_the_plugins_scene() {
    let dir = tempfile::tempdir().unwrap();
    let status = regolith_bingham()
        .args(["run", SCENE, "-q", "--set", "time.end=0.02", "--out"])
        .arg(dir.path())
        .status()
        .unwrap();
    assert!(status.success());
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("summary.json")).unwrap())
            .unwrap();
    assert_eq!(summary["status"], "completed", "{summary}");
    let layer = &summary["bodies"][0];
    assert_eq!(layer["material"], "Bingham");
    assert!(layer["mass"].as_f64().unwrap() > 0.0);
}

#[test]
fn a_mistyped_constant_is_refused_at_its_line() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(SCENE).unwrap();
    let line = 1 + text
        .lines()
        .position(|l| l.contains("yield_stress:"))
        .unwrap();
    let scene = dir.path().join("typo.ron");
    std::fs::write(&scene, text.replacen("yield_stress:", "yeild_stress:", 1)).unwrap();
    let out = regolith_bingham()
        .args(["run", "-q", "--out"])
        .arg(dir.path().join("out"))
        .arg(&scene)
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("yeild_stress"), "{err}");
    assert!(
        err.contains(&format!(":{line}")),
        "line {line} not named: {err}"
    );
}
