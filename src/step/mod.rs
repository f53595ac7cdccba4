//! One explicit MPM step (update stress last, FLIP; SCIENCE.md 2) as a chain of system sets.
//!
//! ```text
//! Prepare -> ParticleToGrid -> GridUpdate -> Contact -> GridToParticle
//!         -> ConstitutiveUpdate -> Diagnostics -> Output
//! ```
//! Each set is followed by a timing lap so a run can say where its time went. The schedule
//! runs on the single-threaded executor with ambiguity detection set to error; systems
//! parallelise inside with rayon. Everything up to the constitutive update is skipped while
//! the clock is only observing (the t = 0 output before the first step).

mod bands;
pub mod cell_average;
mod grid_update;
mod locate;
mod prepare;
pub mod transfer;

use std::time::{Duration, Instant};

use bevy_ecs::prelude::*;
use bevy_ecs::schedule::{LogLevel, ScheduleBuildSettings, ScheduleLabel};

use crate::integration::{CpdiFixed, Integration, Linear, QuadraticBspline, Scheme};
use crate::scene::{Dilatation, StressUpdate, Transfer};
use crate::sim::Clock;

pub use bands::Bands;
pub use cell_average::CellDilatation;
pub use grid_update::{apply_walls, update_grid};
pub use locate::{Location, locate_points};
pub use prepare::signal_speed;

/// The stages of a step, run in this order.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum StepSet {
    /// Time step from the CFL condition, grids cleared.
    Prepare,
    /// Mass, momentum and forces scattered from points to each body's grid.
    ParticleToGrid,
    /// Nodal velocities and accelerations, walls.
    GridUpdate,
    /// Forces between bodies at shared nodes (only in scenes with two or more bodies).
    Contact,
    /// Point velocities, positions, velocity gradients and volumes from the grid.
    GridToParticle,
    /// Stress update, one system per material type.
    ConstitutiveUpdate,
    /// Whole-body quantities and health checks.
    Diagnostics,
    /// Rows, snapshots and other outputs, when an output time is due.
    Output,
}

impl StepSet {
    pub const ALL: [StepSet; 8] = [
        StepSet::Prepare,
        StepSet::ParticleToGrid,
        StepSet::GridUpdate,
        StepSet::Contact,
        StepSet::GridToParticle,
        StepSet::ConstitutiveUpdate,
        StepSet::Diagnostics,
        StepSet::Output,
    ];

    pub fn label(self) -> &'static str {
        match self {
            StepSet::Prepare => "prepare",
            StepSet::ParticleToGrid => "particle_to_grid",
            StepSet::GridUpdate => "grid_update",
            StepSet::Contact => "contact",
            StepSet::GridToParticle => "grid_to_particle",
            StepSet::ConstitutiveUpdate => "constitutive_update",
            StepSet::Diagnostics => "diagnostics",
            StepSet::Output => "output",
        }
    }
}

/// The material update systems: each touches only bodies of its own material, so they may
/// run in any order relative to each other.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct MaterialUpdates;

/// The timing lap after set `k`.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
struct Lap(usize);

#[derive(ScheduleLabel, Debug, Clone, PartialEq, Eq, Hash)]
pub struct StepSchedule;

/// Wall time spent in each step set.
#[derive(Resource, Debug)]
pub struct Timings {
    pub per_set: [Duration; 8],
    last: Instant,
}

impl Default for Timings {
    fn default() -> Self {
        Timings {
            per_set: [Duration::ZERO; 8],
            last: Instant::now(),
        }
    }
}

impl Timings {
    fn lap(&mut self, k: usize) {
        let now = Instant::now();
        self.per_set[k] += now - self.last;
        self.last = now;
    }

    /// Restarts the lap clock (before a schedule run, so time between runs is not counted).
    pub fn restart(&mut self) {
        self.last = Instant::now();
    }
}

fn stepping(clock: Res<Clock>) -> bool {
    !clock.observing
}

/// An output time is due (set in Diagnostics).
pub fn output_due(clock: Res<Clock>) -> bool {
    clock.output_due
}

/// The numerical options that decide which core systems a step has.
#[derive(Clone, Copy, Debug)]
pub struct StepOptions {
    pub integration: Integration,
    pub update: StressUpdate,
    pub dilatation: Dilatation,
    pub transfer: Transfer,
}

/// The schedule of one step with the core systems for the given options.
pub fn build_schedule(options: StepOptions) -> Schedule {
    let mut schedule = Schedule::new(StepSchedule);
    schedule.set_build_settings(ScheduleBuildSettings {
        ambiguity_detection: LogLevel::Error,
        ..Default::default()
    });
    for (k, set) in StepSet::ALL.iter().enumerate() {
        if k > 0 {
            schedule.configure_sets(Lap(k - 1).before(*set));
        }
        schedule.configure_sets(set.before(Lap(k)));
        schedule.add_systems((move |mut t: ResMut<Timings>| t.lap(k)).in_set(Lap(k)));
    }
    for set in &StepSet::ALL[..6] {
        schedule.configure_sets(set.run_if(stepping));
    }
    schedule.add_systems(
        (prepare::choose_time_step, prepare::clear_grids)
            .chain()
            .in_set(StepSet::Prepare),
    );
    match options.integration {
        Integration::Linear => add_transfers::<Linear>(&mut schedule, options),
        Integration::CpdiFixed => add_transfers::<CpdiFixed>(&mut schedule, options),
        Integration::QuadraticBspline => add_transfers::<QuadraticBspline>(&mut schedule, options),
    }
    let gradient_done = StepSet::GridToParticle;
    match options.dilatation {
        Dilatation::PerPoint => {
            schedule.add_systems(
                (transfer::advect_points, transfer::point_density)
                    .chain()
                    .in_set(gradient_done)
                    .after(GradientSystems),
            );
        }
        Dilatation::CellAveraged => {
            schedule.add_systems(
                (
                    cell_average::average_dilatation,
                    transfer::advect_points,
                    cell_average::cell_density,
                )
                    .chain()
                    .in_set(gradient_done)
                    .after(GradientSystems),
            );
        }
    }
    schedule.add_systems(grid_update::update_grid.in_set(StepSet::GridUpdate));
    schedule.add_systems(
        (
            prepare::advance_clock.run_if(stepping),
            crate::diagnostics::survey_bodies,
            crate::diagnostics::check_energy.run_if(stepping),
            prepare::decide_output,
        )
            .chain()
            .in_set(StepSet::Diagnostics),
    );
    schedule.add_systems(
        crate::output::trajectory::record_trajectory
            .in_set(StepSet::Output)
            .run_if(output_due),
    );
    schedule
}

/// The gather systems that produce point velocities and velocity gradients.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
struct GradientSystems;

fn add_transfers<S: Scheme>(schedule: &mut Schedule, options: StepOptions) {
    schedule.add_systems(
        (
            locate_points::<S>,
            cell_average::average_stress_trace,
            transfer::particle_to_grid,
        )
            .chain()
            .in_set(StepSet::ParticleToGrid),
    );
    let gather = (StepSet::GridToParticle, GradientSystems);
    let affine = options.transfer.affine();
    match (options.update, affine) {
        (StressUpdate::Usl, false) => {
            schedule.add_systems(transfer::grid_to_particle.in_set(gather.0).in_set(gather.1));
        }
        (StressUpdate::Usl, true) => {
            schedule.add_systems(
                transfer::affine_to_particle::<S>
                    .in_set(gather.0)
                    .in_set(gather.1),
            );
        }
        (StressUpdate::Musl, _) => {
            let gradient = if affine {
                transfer::musl_apic_gradient::<S>.into_configs()
            } else {
                transfer::musl_gradient.into_configs()
            };
            schedule.add_systems(
                (transfer::musl_velocity, transfer::musl_remap, gradient)
                    .chain()
                    .in_set(gather.0)
                    .in_set(gather.1),
            );
        }
    }
}
