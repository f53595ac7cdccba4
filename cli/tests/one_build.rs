//! One build for the README's two commands (issue 38): `cargo run --release` (the default
//! members, without their dev-dependencies) and `cargo test --release --workspace` (every
//! member with its dev-dependencies) must resolve every crate they share with the same
//! features, or each rebuilds what the other built (before: 85 crates, the Rerun SDK and
//! bevy_ecs among them, because the tests' proptest turned on `rand/std`, which bevy_ecs
//! uses). cli/Cargo.toml asks for the tests' features; this test says which crate to add
//! there when a new dependency splits the two again.

use std::collections::{BTreeMap, BTreeSet};
use std::process::Command;

/// Each package `cargo tree` lists for `args`, with the sets of features it is built with
/// (a crate built for the build scripts and for the code may have two).
fn features(args: &[&str]) -> BTreeMap<String, BTreeSet<String>> {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".to_string());
    let out = Command::new(cargo)
        .args(["tree", "--offline", "--prefix", "none", "-f", "{p}|{f}"])
        .args(args)
        .current_dir(root)
        .output()
        .expect("cargo tree runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let mut packages: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for line in String::from_utf8_lossy(&out.stdout).lines() {
        if let Some((package, features)) = line.split_once('|') {
            let features = features.trim_end_matches(" (*)").to_string();
            packages
                .entry(package.to_string())
                .or_default()
                .insert(features);
        }
    }
    packages
}

#[test]
fn the_run_command_and_the_test_command_build_shared_crates_alike() {
    // The default members, as `cargo run` in the root selects them (Cargo.toml).
    let run = features(&[
        "-p",
        "regolith",
        "-p",
        "regolith-lab",
        "-p",
        "regolith-cli",
        "-p",
        "regolith-benches",
        "-e",
        "normal,build",
    ]);
    let test = features(&["--workspace", "-e", "normal,build,dev"]);
    assert!(
        run.len() > 100,
        "{} packages: cargo tree said little",
        run.len()
    );
    let split: Vec<String> = run
        .iter()
        .filter_map(|(package, f)| {
            let t = test.get(package)?;
            (t != f).then(|| format!("{package}: run {f:?}, test {t:?}"))
        })
        .collect();
    assert!(
        split.is_empty(),
        "crates the two commands build with different features (add each to cli/Cargo.toml \
         with the test's features):\n{}",
        split.join("\n")
    );
}
