//! The names of the step's stages: the sets a step runs in order ([`StepSet`]), the core of
//! each ([`Core`]), the wall-clock time spent in each ([`Timings`]), and the two run
//! conditions every builder needs. Which systems go where is `schedule.rs`'s (at the crate's
//! top, above every item whose systems it places); plugins and scene items name these sets
//! to add their own systems after a set's core.

use std::time::{Duration, Instant};

use bevy_ecs::prelude::*;
use bevy_ecs::schedule::ScheduleLabel;

use crate::resources::{Clock, OutputClock};

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
    /// Point velocities and velocity gradients from the grid.
    GridToParticle,
    /// Point positions, volumes and densities: the move.
    Move,
    /// The fields the points carry (`crate::field`: the nonlocal fluidity, a plugin's
    /// tracer), advanced on the grid, one system per kind of field.
    Fields,
    /// Stress update, one system per material type (reading the fields it needs).
    ConstitutiveUpdate,
    /// The clock advances by the step just taken.
    Clock,
    /// Whole-body quantities and health checks.
    Diagnostics,
    /// Rows, snapshots and other outputs, when an output time is due.
    Output,
}

impl StepSet {
    /// How many sets a step has.
    pub const COUNT: usize = 11;

    /// Every set, in the order a step runs them.
    pub const ALL: [StepSet; StepSet::COUNT] = [
        StepSet::Prepare,
        StepSet::ParticleToGrid,
        StepSet::GridUpdate,
        StepSet::Contact,
        StepSet::GridToParticle,
        StepSet::Move,
        StepSet::Fields,
        StepSet::ConstitutiveUpdate,
        StepSet::Clock,
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
            StepSet::Move => "move",
            StepSet::Fields => "fields",
            StepSet::ConstitutiveUpdate => "constitutive_update",
            StepSet::Clock => "clock",
            StepSet::Diagnostics => "diagnostics",
            StepSet::Output => "output",
        }
    }

    /// Whether the set advances the state, and so is skipped while the clock only observes
    /// (the t = 0 output).
    pub fn advances_state(self) -> bool {
        !matches!(self, StepSet::Diagnostics | StepSet::Output)
    }
}

/// The core systems of a set: plugin systems in the same set run after them.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Core(pub StepSet);

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
    /// Ends the lap of `set`: the time since the last lap is its.
    pub fn lap(&mut self, set: StepSet) {
        let now = Instant::now();
        self.per_set[set as usize] += now - self.last;
        self.last = now;
    }

    /// Restarts the lap clock (before a schedule run, so time between runs is not counted).
    pub fn restart(&mut self) {
        self.last = Instant::now();
    }
}

/// The clock steps (it is not only observing the t = 0 state).
pub fn stepping(clock: Res<Clock>) -> bool {
    !clock.observing
}

/// An output time is due (set in Diagnostics).
pub fn output_due(outputs: Res<OutputClock>) -> bool {
    outputs.due
}
