//! One explicit MPM step (update stress last; docs/model.md) as a chain of system sets.
//!
//! [`schedule`] lists every core system in its set, in order: read it first. The other
//! modules are the systems: `prepare` (the clock), `locate` (each point's footprint, cell
//! and band), `transfer` (scatter, gather, MUSL's passes, the move), `cell_average` (the
//! cell-averaged dilatation, stress trace and density), `spacing` (the delta-correction that
//! moves points off over-filled nodes), `grid_update` (walls) and `bands` (the lock-free
//! parallel scatter).

pub(crate) mod bands;
pub mod cell_average;
mod grid_update;
mod locate;
mod prepare;
mod schedule;
pub mod spacing;
pub mod transfer;

pub use bands::Bands;
pub use cell_average::CellDilatation;
pub use grid_update::{apply_walls, update_grid};
pub use locate::{Location, locate_points};
pub use prepare::signal_speed;
pub use schedule::{
    Core, MaterialUpdates, StepOptions, StepSchedule, StepSet, Timings, add_transfers,
    build_schedule, output_due,
};
