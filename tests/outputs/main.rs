//! Outputs and checkpoints: what a run writes, VTK files read back, a checkpoint's state.
//!
//! One test binary for the area (each binary links the engine, in release mode for CI);
//! each module is one subject (`cargo test --release --test NAME MODULE` runs one).

#[path = "../common/mod.rs"]
mod common;

mod checkpoint;
mod outputs;
mod vtk;
