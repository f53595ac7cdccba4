//! What holds for any scene: the same state at any thread count and through any resume, no
//! panic or silent wrong answer on random scenes, the memory a point takes.
//!
//! One test binary for the area (each binary links the engine, in release mode for CI);
//! each module is one subject (`cargo test --release --test NAME MODULE` runs one).

#[path = "../common/mod.rs"]
mod common;
#[path = "../common/property.rs"]
mod property;
#[path = "../common/resume.rs"]
mod resume_check;

mod determinism;
mod fuzz_scenes;
mod memory;
mod resume;
