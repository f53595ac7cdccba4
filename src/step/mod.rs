//! One explicit MPM step (update stress last; docs/model.md) as a chain of system sets.
//!
//! The crate's `schedule` module lists every core system in its set, in order, and builds
//! the step from these: read it first. `sets` names the stages. The other modules are the
//! systems: `prepare` (the clock), `locate` (each point's footprint, cell
//! and band), `scatter_gather` (the scatter, the gathers, MUSL's passes, the move), `cell_average` (the
//! cell-averaged dilatation, stress trace and density), `spacing` (the delta-correction that
//! moves points off over-filled nodes), `grid_update` (walls) and `bands` (the lock-free
//! parallel scatter).

pub(crate) mod bands;
pub mod cell_average;
mod grid_update;
mod locate;
pub(crate) mod prepare;
pub mod scatter_gather;
mod sets;
pub mod spacing;

pub use bands::Bands;
pub use cell_average::CellDilatation;
pub use grid_update::{apply_walls, update_grid};
pub use locate::{Location, locate_points};
pub use prepare::signal_speed;
pub use sets::{Core, StepSchedule, StepSet, Timings, output_due, stepping};
