//! Scenes: the format's refusals, presets, and the shipped experiments run short (the
//! paper's impact, force propagation and flow field, the authors' impact, granular beds and
//! collapses, the silo).
//!
//! One test binary for the area (each binary links the engine, in release mode for CI);
//! each module is one subject (`cargo test --release --test NAME MODULE` runs one).

#[path = "../common/mod.rs"]
mod common;

mod authors_code;
mod bad_scenes;
mod flow_field;
mod force_propagation;
mod granular_scenes;
mod impact;
mod presets;
mod silo;
