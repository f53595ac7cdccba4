//! The command examples users paste (issue 38): the command lines and `--set` examples of
//! the README and the guides in docs/ (and the README's commands run as written), the commands and `--set` examples in the shipped scenes' comments, and the
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
    // The README and the guides: command lines in code blocks, `--set` examples in text.
    let readme: String = [
        "README.md",
        "docs/cli.md",
        "docs/scenes.md",
        "docs/sweeps.md",
        "docs/viewers.md",
        "docs/extending.md",
    ]
    .iter()
    .map(|f| std::fs::read_to_string(root().join(f)).unwrap())
    .collect::<Vec<_>>()
    .join("\n");
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
        // A usage line (`[--out DIR]`, `SCENE.ron`, `A|B`, `key.path=value`), not a command.
        let placeholder = |l: &str| {
            l.contains('[') || l.contains("SCENE") || l.contains('|') || l.contains("key.path")
        };
        if in_block && (line.starts_with("regolith ") || line.starts_with("cargo run")) {
            if !placeholder(line) {
                examples.push(line.to_string());
            }
        } else if !in_block {
            for code in inline_code(line) {
                if code.starts_with("--set ") && !placeholder(code) {
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

/// The README's shell commands that a test cannot run, and why: building and testing are
/// what runs this test, and the viewers are programs with windows. A viewer's command is
/// checked instead for the file it opens, which the command before it must have written.
const NOT_RUN: [(&str, &str); 3] = [
    ("cargo build --release", "the build this test runs in"),
    ("bash .ci/run", "the tests this test is one of"),
    (
        "cargo test --release --workspace",
        "the tests this test is one of",
    ),
];

/// Every command of the README's shell blocks, run as written in a scratch directory that
/// holds the repository's scenes: a newcomer's first commands must work, and the files a
/// viewer is then told to open must exist.
#[test]
fn the_readme_commands_run_as_written() {
    let readme = std::fs::read_to_string(root().join("README.md")).unwrap();
    let mut commands = Vec::new();
    let mut fence: Option<bool> = None;
    for line in readme.lines() {
        let trimmed = line.trim();
        if trimmed.starts_with("```") {
            fence = match fence {
                Some(_) => None,
                None => Some(trimmed == "```"),
            };
            continue;
        }
        if fence == Some(true) && !trimmed.is_empty() {
            commands.push(trimmed.to_string());
        }
    }
    assert!(commands.len() >= 5, "commands found: {commands:?}");
    let scratch = tempfile::tempdir().unwrap();
    std::os::unix::fs::symlink(root().join("scenes"), scratch.path().join("scenes")).unwrap();
    let mut ran = 0;
    for command in &commands {
        if NOT_RUN.iter().any(|(c, _)| c == command) {
            continue;
        }
        let words = words(command).unwrap_or_else(|e| panic!("{command}: {e}"));
        let args: Vec<&str> = words.iter().map(String::as_str).collect();
        let args = match args.as_slice() {
            ["regolith", rest @ ..] | ["cargo", "run", "--release", "--", rest @ ..] => rest,
            ["rerun" | "paraview", file] => {
                assert!(
                    scratch.path().join(file).is_file(),
                    "{command}: the command before it wrote no {file}"
                );
                continue;
            }
            _ => panic!("{command}: a README command this test neither runs nor lists in NOT_RUN"),
        };
        let quiet = (args.first() == Some(&"run")).then_some("--quiet");
        let out = Command::new(env!("CARGO_BIN_EXE_regolith"))
            .args(args)
            .args(quiet)
            .current_dir(scratch.path())
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{command}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        ran += 1;
    }
    assert!(ran >= 4, "{ran} commands run");
}
