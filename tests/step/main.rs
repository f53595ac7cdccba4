//! The step: against analytic answers (an elastic bar's period, a column's lithostatic
//! stress, free fall, a front at the p-wave speed), conservation, and its own table of
//! systems; transfers, shape functions, materials point by point, contact, walls and
//! obstacles, the delta-correction, the nonlocal fluidity on the grid, a plugin's systems.
//!
//! One test binary for the area (each binary links the engine, in release mode for CI);
//! each module is one subject (`cargo test --release --test NAME MODULE` runs one).

#[path = "../common/mod.rs"]
mod common;
#[path = "../common/property.rs"]
mod property;

mod active_nodes;
mod apic;
mod contact;
mod elastic_verification;
mod field_bodies;
mod granular_update;
mod integration_accuracy;
mod integration_schemes;
mod nonlocal_grid;
mod nonlocal_solver;
mod obstacles;
mod plugin_systems;
mod relaxation;
mod spacing;
mod step_order;
mod stress_suite;
mod transfer_conservation;
