//! The command examples users paste (issue 38): the README's command lines and its `--set`
//! examples, the commands and `--set` examples in the shipped scenes' comments, and the
//! `--set` example of `regolith run --help`. Each must be valid shell as written (an
//! unquoted `(0,-1)` is a bash syntax error), and each that runs a shipped scene must load
//! it with its overrides: bash splits the line as a user's shell would, and the words go to
//! `regolith check` with the same `--set` and `--preset` arguments.

use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The spans between backticks on one line (unpaired ones ignored).
fn inline_code(line: &str) -> Vec<&str> {
    line.split('`').skip(1).step_by(2).collect()
}

/// The words bash makes of `line` (comments dropped, quotes removed), or why it cannot.
fn words(line: &str) -> Result<Vec<String>, String> {
    let out = Command::new("bash")
        .arg("-c")
        .arg(format!("printf '%s\\0' {line}"))
        .output()
        .map_err(|e| format!("bash: {e}"))?;
    if !out.status.success() {
        return Err(String::from_utf8_lossy(&out.stderr).trim().to_string());
    }
    Ok(String::from_utf8_lossy(&out.stdout)
        .split('\0')
        .filter(|w| !w.is_empty())
        .map(str::to_string)
        .collect())
}

/// Checks one command: valid shell, and, if it runs a scene that exists, `regolith check`
/// accepts the scene with its overrides.
fn check_example(example: &str, failures: &mut Vec<String>) {
    let syntax = Command::new("bash")
        .args(["-n", "-c", example])
        .output()
        .unwrap();
    if !syntax.status.success() {
        failures.push(format!(
            "{example}: {}",
            String::from_utf8_lossy(&syntax.stderr).trim()
        ));
        return;
    }
    let words = match words(example) {
        Ok(w) => w,
        Err(e) => return failures.push(format!("{example}: {e}")),
    };
    let args: Vec<&str> = words.iter().map(String::as_str).collect();
    let (file, rest) = match args.as_slice() {
        ["regolith", "run" | "check", file, rest @ ..] => (*file, rest),
        ["cargo", "run", "--release", "--", "run", file, rest @ ..] => (*file, rest),
        _ => return,
    };
    if !root().join(file).is_file() {
        return;
    }
    let mut check = vec!["check".to_string(), file.to_string()];
    let mut k = 0;
    while k < rest.len() {
        if matches!(rest[k], "--set" | "--preset") && k + 1 < rest.len() {
            check.extend([rest[k].to_string(), rest[k + 1].to_string()]);
            k += 1;
        }
        k += 1;
    }
    let o = Command::new(env!("CARGO_BIN_EXE_regolith"))
        .args(&check)
        .current_dir(root())
        .output()
        .unwrap();
    if !o.status.success() {
        failures.push(format!(
            "{example} (as regolith {}): {}",
            check.join(" "),
            String::from_utf8_lossy(&o.stderr).trim()
        ));
    }
}

#[test]
fn every_example_pastes_into_bash_and_loads_its_scene() {
    // Each a whole command line: a bare `--set` example is put after the scene it is for.
    let mut examples: Vec<String> = Vec::new();
    // The README: command lines in code blocks, `--set` examples in its text.
    let readme = std::fs::read_to_string(root().join("README.md")).unwrap();
    // Inside a fence: `Some(true)` for a plain one (shell), `Some(false)` for another language.
    let mut fence: Option<bool> = None;
    for line in readme.lines() {
        if line.starts_with("```") {
            fence = match fence {
                Some(_) => None,
                None => Some(line == "```"),
            };
            continue;
        }
        let in_block = fence.is_some();
        if fence == Some(false) {
            continue;
        }
        let line = line.trim();
        let placeholder = line.contains('[') || line.contains("SCENE") || line.contains('|');
        if in_block && (line.starts_with("regolith ") || line.starts_with("cargo run")) {
            if !placeholder {
                examples.push(line.to_string());
            }
        } else if !in_block {
            for code in inline_code(line) {
                if code.starts_with("--set ") {
                    let scene = "scenes/granular_column_collapse_a2.ron";
                    examples.push(format!("regolith check {scene} {code}"));
                }
            }
        }
    }
    // The shipped scenes' comments.
    let mut scenes: Vec<PathBuf> = std::fs::read_dir(root().join("scenes"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "ron"))
        .collect();
    scenes.sort();
    for path in &scenes {
        let scene = format!("scenes/{}", path.file_name().unwrap().to_string_lossy());
        for line in std::fs::read_to_string(path).unwrap().lines() {
            let Some(comment) = line.trim().strip_prefix("//") else {
                continue;
            };
            let comment = comment.trim();
            if comment.starts_with("regolith ") {
                examples.push(comment.to_string());
            }
            for code in inline_code(comment) {
                if code.starts_with("--set ") {
                    examples.push(format!("regolith check {scene} {code}"));
                } else if code.starts_with("regolith ") {
                    examples.push(code.to_string());
                }
            }
        }
    }
    // The help's example, for the scene whose intruder it sets.
    let help = Command::new(env!("CARGO_BIN_EXE_regolith"))
        .args(["run", "--help"])
        .output()
        .unwrap();
    let help = String::from_utf8_lossy(&help.stdout).into_owned();
    let from_help: Vec<&str> = help
        .lines()
        .filter_map(|l| l.split_once("e.g. ").map(|(_, e)| e.trim_end_matches('.')))
        .collect();
    assert!(!from_help.is_empty(), "no example in:\n{help}");
    examples.extend(
        from_help
            .iter()
            .map(|e| format!("regolith check scenes/impact_tipped_coarse.ron {e}")),
    );

    let mut failures = Vec::new();
    for example in &examples {
        check_example(example, &mut failures);
    }
    assert!(
        failures.is_empty(),
        "{} of {} examples fail:\n{}",
        failures.len(),
        examples.len(),
        failures.join("\n")
    );
    // What this reads today (2026-12-06: 21), so that a change of format is noticed.
    assert!(examples.len() >= 20, "{examples:#?}");
}
