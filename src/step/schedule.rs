//! The step in one place: every core system, in its set, in order.
//!
//! ```text
//! Prepare            choose_time_step, clear_grids
//! ParticleToGrid     locate_points::<S>, average_stress_trace, particle_to_grid
//!                    (S: the scene's shape functions, `ShapeFunctions::add_transfers`)
//! GridUpdate         update_grid
//! Contact            the scene's contact law: no_slip | frictional (two or more bodies;
//!                    added by the law item, `Contact::install`)
//! GridToParticle     grid_to_particle | affine_to_particle::<S> (USL)
//!                    | musl_velocity, musl_remap, musl_gradient | musl_apic_gradient::<S> (MUSL)
//!                    then average_dilatation, advect_points, cell_density (CellAveraged)
//!                    or advect_points, point_density (PerPoint), with the scene's
//!                    `spacing: DeltaCorrection(..)` correct_spacing after advect_points
//! ConstitutiveUpdate update_stress::<M> per material type       (added by the material item)
//! Diagnostics        advance_clock, survey_bodies, check_energy, decide_output
//! Output             record_trajectory, then the outputs' own systems when due
//! ```
//!
//! The core systems of each set sit in its [`Core`] subset; a plugin's systems
//! (`Regolith::add_systems`, module `plugin`) run in the set after its core, so a plugin that moves
//! points in `Prepare` sees this step's time step and cleared grids. Each set is followed by
//! a timing lap ([`Timings`]). The executor is single-threaded with ambiguity detection set
//! to error: two systems that touch the same data in no defined order stop the build, named.
//! Systems parallelise inside with rayon. Everything before `Diagnostics` is skipped while the
//! clock only observes (the t = 0 output before the first step).

use std::time::{Duration, Instant};

use bevy_ecs::prelude::*;
use bevy_ecs::schedule::{LogLevel, ScheduleBuildSettings, ScheduleLabel, SingleThreadedExecutor};

use super::spacing::{self, Spacing};
use super::{cell_average, grid_update, locate, prepare, transfer};
use crate::diagnostics;
use crate::output::trajectory;
use crate::resources::{Clock, OutputClock};
use crate::resources::{Dilatation, StressUpdate};
use crate::shape_functions::{Scheme, ShapeFunctions};

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
    /// How many sets a step has.
    pub const COUNT: usize = 8;

    /// Every set, in the order a step runs them.
    pub const ALL: [StepSet; StepSet::COUNT] = [
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

    /// Whether the set advances the state, and so is skipped while the clock only observes
    /// (the t = 0 output).
    fn advances_state(self) -> bool {
        !matches!(self, StepSet::Diagnostics | StepSet::Output)
    }
}

/// The core systems of a set: plugin systems in the same set run after them.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Core(pub StepSet);

/// The material update systems: each touches only bodies of its own material, so they may
/// run in any order relative to each other.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct MaterialUpdates;

/// The timing lap after a set.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
struct Lap(StepSet);

/// The gather systems that produce point velocities and velocity gradients.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
struct Gather;

#[derive(ScheduleLabel, Debug, Clone, PartialEq, Eq, Hash)]
pub struct StepSchedule;

/// Wall time spent in each step set, in [`StepSet::ALL`]'s order.
#[derive(Resource, Debug)]
pub struct Timings {
    pub per_set: [Duration; StepSet::COUNT],
    last: Instant,
}

impl Default for Timings {
    fn default() -> Self {
        Timings {
            per_set: [Duration::ZERO; StepSet::COUNT],
            last: Instant::now(),
        }
    }
}

impl Timings {
    fn lap(&mut self, set: StepSet) {
        let now = Instant::now();
        self.per_set[set as usize] += now - self.last;
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
pub fn output_due(outputs: Res<OutputClock>) -> bool {
    outputs.due
}

/// The numerical options that decide which core systems a step has.
#[derive(Clone, Copy, Debug)]
pub struct StepOptions<'a> {
    pub integration: &'a dyn ShapeFunctions,
    pub update: StressUpdate,
    pub dilatation: Dilatation,
    /// Whether points carry an affine field (the transfer's `affine`).
    pub affine: bool,
    /// Whether the delta-correction follows the move.
    pub spacing: Spacing,
}

/// The schedule of one step with the core systems for the given options.
pub fn build_schedule(options: &StepOptions) -> Schedule {
    let mut schedule = Schedule::new(StepSchedule);
    schedule.set_executor(SingleThreadedExecutor::new());
    schedule.set_build_settings(ScheduleBuildSettings {
        ambiguity_detection: LogLevel::Error,
        ..Default::default()
    });
    configure_sets(&mut schedule);

    schedule.add_systems(
        (prepare::choose_time_step, prepare::clear_grids)
            .chain()
            .in_set(Core(StepSet::Prepare)),
    );
    options.integration.add_transfers(&mut schedule, options);
    schedule.add_systems(grid_update::update_grid.in_set(Core(StepSet::GridUpdate)));
    // Contact: the contact law item adds its system to `Core(StepSet::Contact)`
    // (`Contact::install`), in scenes of two or more bodies.
    let after_gather = Core(StepSet::GridToParticle);
    match options.dilatation {
        Dilatation::PerPoint => {
            schedule.add_systems(
                (transfer::advect_points, transfer::point_density)
                    .chain()
                    .in_set(after_gather)
                    .after(Gather),
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
                    .in_set(after_gather)
                    .after(Gather),
            );
        }
    }
    if let Spacing::DeltaCorrection(_) = options.spacing {
        schedule.add_systems(
            spacing::correct_spacing
                .in_set(after_gather)
                .after(transfer::advect_points)
                .before(transfer::point_density)
                .before(cell_average::cell_density),
        );
    }
    // ConstitutiveUpdate: one `update_stress::<M>` per material of the scene, added by the
    // material item (`MaterialSpec::add_systems`) into `Core(ConstitutiveUpdate)`.
    schedule.add_systems(
        (
            prepare::advance_clock.run_if(stepping),
            diagnostics::survey_bodies,
            diagnostics::check_energy.run_if(stepping),
            prepare::decide_output,
        )
            .chain()
            .in_set(Core(StepSet::Diagnostics)),
    );
    schedule.add_systems(
        trajectory::record_trajectory
            .in_set(Core(StepSet::Output))
            .run_if(output_due),
    );
    schedule
}

/// Chains the sets with a timing lap after each, and puts each set's core first.
fn configure_sets(schedule: &mut Schedule) {
    let mut previous: Option<Lap> = None;
    for set in StepSet::ALL {
        if let Some(lap) = previous {
            schedule.configure_sets(lap.before(set));
        }
        schedule.configure_sets(set.before(Lap(set)));
        schedule.configure_sets(Core(set).in_set(set));
        if set.advances_state() {
            schedule.configure_sets(set.run_if(stepping));
        }
        schedule.add_systems((move |mut t: ResMut<Timings>| t.lap(set)).in_set(Lap(set)));
        previous = Some(Lap(set));
    }
}

/// The scatter and the gather for shape functions `S`.
pub fn add_transfers<S: Scheme>(schedule: &mut Schedule, options: &StepOptions) {
    schedule.add_systems(
        (
            locate::locate_points::<S>,
            cell_average::average_stress_trace,
            transfer::particle_to_grid,
        )
            .chain()
            .in_set(Core(StepSet::ParticleToGrid)),
    );
    let gather = Core(StepSet::GridToParticle);
    let affine = options.affine;
    match (options.update, affine) {
        (StressUpdate::Usl, false) => {
            schedule.add_systems(transfer::grid_to_particle.in_set(gather).in_set(Gather));
        }
        (StressUpdate::Usl, true) => {
            schedule.add_systems(
                transfer::affine_to_particle::<S>
                    .in_set(gather)
                    .in_set(Gather),
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
                    .in_set(gather)
                    .in_set(Gather),
            );
        }
    }
}
