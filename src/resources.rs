//! The simulation's global state, as resources every system may read: the clock, the time-step
//! rule, the output clock, gravity, the walls and the velocity rule.
//!
//! They live here, not with the scene format or the world builder, so that the step's systems
//! depend on neither: the builder (`sim`) fills them from a scene, the systems read them, and
//! a checkpoint saves the three that change (the clock, the step rule's record, the output
//! clock). The wall and time-step types are also the scene format's (`scene` re-exports them).

use bevy_ecs::prelude::*;
use glam::DVec2;
use serde::{Deserialize, Serialize};

use crate::transfer::Transfer;

/// Simulated time and the step count.
#[derive(Resource, Clone, Debug, Serialize, Deserialize)]
pub struct Clock {
    pub time: f64,
    pub dt: f64,
    pub step: u64,
    pub end: f64,
    /// True only while the t = 0 state is being observed (no step is taken).
    pub observing: bool,
    /// This step lands on the end time.
    pub last_step: bool,
}

impl Clock {
    /// At t = 0, observing the initial state, to run until `end`.
    pub fn start(end: f64) -> Clock {
        Clock {
            time: 0.0,
            dt: 0.0,
            step: 0,
            end,
            observing: true,
            last_step: false,
        }
    }
}

/// The scene's time-step rule, and the steps it has given so far.
#[derive(Resource, Clone, Debug, Serialize, Deserialize)]
pub struct StepRule {
    pub rule: TimeStep,
    /// A fixed step may exceed the CFL limit (the scene's `time.allow_unstable`).
    pub allow_unstable: bool,
    pub dt_min: f64,
    pub dt_max: f64,
    /// Largest CFL number used so far.
    pub cfl_max: f64,
}

impl StepRule {
    pub fn new(rule: TimeStep, allow_unstable: bool) -> StepRule {
        StepRule {
            rule,
            allow_unstable,
            dt_min: f64::INFINITY,
            dt_max: 0.0,
            cfl_max: 0.0,
        }
    }
}

/// A fixed output interval in simulated time: due at t = 0, then every `every` seconds, and
/// at the last step.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct Interval {
    pub every: f64,
    next: f64,
}

impl Interval {
    pub fn new(every: f64) -> Self {
        Interval { every, next: 0.0 }
    }

    /// Whether an output is due now (and, if so, moves on to the next time).
    pub fn due(&mut self, clock: &Clock) -> bool {
        let eps = 1e-9 * self.every;
        if !(clock.observing || clock.last_step || clock.time >= self.next - eps) {
            return false;
        }
        while self.next <= clock.time + eps {
            self.next += self.every;
        }
        true
    }
}

/// The scene's output interval (`time.output_every`): trajectory rows and the outputs that
/// follow it are written when `due`, set in the Diagnostics set.
#[derive(Resource, Clone, Debug, Serialize, Deserialize)]
pub struct OutputClock {
    pub interval: Interval,
    pub due: bool,
}

/// Body force per unit mass.
#[derive(Resource, Clone, Copy, Debug)]
pub struct Gravity(pub DVec2);

/// The walls of the domain.
#[derive(Resource, Clone, Debug)]
pub struct Boundaries(pub Walls);

/// How the points' velocities follow the grid: the scene's transfer and its FLIP fraction.
#[derive(Resource, Clone, Debug)]
pub struct VelocityRule {
    pub transfer: Box<dyn Transfer>,
    pub flip: f64,
}

impl VelocityRule {
    /// [`Transfer::pull`] for a step `dt` of a body of p-wave speed `c` on cells of size `h`.
    pub fn pull(&self, dt: f64, h: f64, c: f64) -> f64 {
        self.transfer.pull(self.flip, dt, h, c)
    }
}

/// How the time step is chosen.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum TimeStep {
    /// A fixed step (s).
    Fixed(f64),
    /// `dt = C h / max_b (c_b + max |v_p|)`, recomputed every step.
    Cfl(f64),
}

impl TimeStep {
    /// The step the rule gives on cells of size `h` for the fastest signal `signal`
    /// (`c + |v|`); `otherwise` when a CFL rule has no signal to go by (nothing moves and no
    /// material has a wave speed).
    pub fn dt(self, h: f64, signal: f64, otherwise: f64) -> f64 {
        match self {
            TimeStep::Fixed(dt) => dt,
            TimeStep::Cfl(c) if signal > 0.0 => c * h / signal,
            TimeStep::Cfl(_) => otherwise,
        }
    }
}

/// The four sides of the domain, each one condition from end to end except where a segment
/// gives a stretch of it another (a silo's orifice: `segments: [(side: Bottom, from: 0.45,
/// to: 0.55, wall: Open)]`).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Walls {
    pub left: Wall,
    pub right: Wall,
    pub bottom: Wall,
    pub top: Wall,
    #[serde(default)]
    pub segments: Vec<Segment>,
}

/// One side of the domain.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
pub enum Side {
    Left,
    Right,
    Bottom,
    Top,
}

impl Side {
    /// The sides in the order the walls are applied, with the axis of their normal and
    /// whether they are its low end.
    pub const ALL: [(Side, usize, bool); 4] = [
        (Side::Left, 0, true),
        (Side::Right, 0, false),
        (Side::Bottom, 1, true),
        (Side::Top, 1, false),
    ];

    /// The axis of the side's normal (0 for left and right, 1 for bottom and top).
    pub fn normal_axis(self) -> usize {
        match self {
            Side::Left | Side::Right => 0,
            Side::Bottom | Side::Top => 1,
        }
    }

    /// The side at the low (`high = false`) or high end of `axis`.
    pub fn of(axis: usize, high: bool) -> Side {
        match (axis, high) {
            (0, false) => Side::Left,
            (0, true) => Side::Right,
            (_, false) => Side::Bottom,
            (_, true) => Side::Top,
        }
    }
}

/// A stretch of a side, from `from` to `to` along it (m: x on the bottom and top, y on the
/// left and right), with its own condition. A grid node belongs to it when strictly inside,
/// so the nodes at its ends keep the side's condition; a point leaving through the side
/// between `from` and `to` meets the segment's.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Segment {
    pub side: Side,
    pub from: f64,
    pub to: f64,
    pub wall: Wall,
}

impl Segment {
    /// Whether this segment covers the place `along` of `side` (strictly inside it).
    #[inline]
    pub fn covers(&self, side: Side, along: f64) -> bool {
        self.side == side && self.from < along && along < self.to
    }
}

impl Walls {
    /// The condition of a whole side (its segments aside).
    pub fn side(&self, side: Side) -> Wall {
        match side {
            Side::Left => self.left,
            Side::Right => self.right,
            Side::Bottom => self.bottom,
            Side::Top => self.top,
        }
    }

    /// The condition on `side` at `along` (x on the bottom and top, y on the left and
    /// right): the segment's strictly inside one, the side's elsewhere.
    #[inline]
    pub fn at(&self, side: Side, along: f64) -> Wall {
        self.segments
            .iter()
            .find(|s| s.covers(side, along))
            .map_or(self.side(side), |s| s.wall)
    }
}

/// Boundary condition on one side, a segment of one, or an obstacle's surface.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
pub enum Wall {
    /// No constraint: material leaving the domain stops the run.
    Free,
    /// No constraint, and material crossing it leaves the simulation: its points are
    /// retired (mass, velocity, stress set to zero, parked on the boundary) and counted in
    /// `summary.json` (an open box top that a splash may leave).
    Open,
    /// Frictionless: the normal velocity is zero, the tangential one free.
    Slip,
    /// Both velocity components are zero.
    NoSlip,
    /// Coulomb friction with coefficient `friction` (`Frictional(friction: 0.3)`): motion
    /// into the wall is stopped and the sliding speed reduced by `friction` times the normal
    /// speed stopped, down to zero; material may leave the wall (`obstacle::surface_velocity`).
    Frictional { friction: f64 },
    /// Wraps to the opposite side (which must be periodic too).
    Periodic,
}

/// The update-stress-last variant (docs/numerics.md).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
pub enum StressUpdate {
    /// `L` from the updated grid velocity `(mv)/m` (the paper's choice). With `Linear`
    /// integration, nodes of tiny mass make it unstable (docs/numerics.md).
    #[default]
    Usl,
    /// Modified USL: `L` from the updated point velocities mapped back to the grid, which
    /// stays bounded at nodes of tiny mass; costs one more scatter and gather per step.
    Musl,
}

/// How the volumetric part of the velocity gradient is taken (docs/numerics.md).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
pub enum Dilatation {
    /// Each point's own `tr L` (the paper's formulation).
    PerPoint,
    /// The volume-weighted mean `tr L` of the points in the point's cell; removes the
    /// checkerboard pressure mode of several points per cell.
    #[default]
    CellAveraged,
}
