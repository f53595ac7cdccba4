//! Helpers shared by the integration tests.
#![allow(dead_code)]

use std::path::PathBuf;

use regolith::{Regolith, Scene};

/// Path of a shipped scene.
pub fn scene_path(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(format!("{name}.ron"))
}

/// Loads a shipped scene with `--set`-style overrides.
pub fn scene(name: &str, sets: &[&str]) -> Scene {
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    Scene::load(&scene_path(name), &sets, &Regolith::default().registries())
        .unwrap_or_else(|e| panic!("{e}"))
        .0
}
