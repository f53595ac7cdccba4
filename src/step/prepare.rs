//! The clock: choosing the time step, advancing time, deciding when outputs are due.

use bevy_ecs::prelude::*;

use crate::body::{Body, BodyState};
use crate::diagnostics::Health;
use crate::error::Fault;
use crate::grid::{GridField, GridGeometry};
use crate::resources::{Clock, OutputClock, StepRule, TimeStep};

/// Fastest signal of the scene: each body's p-wave speed plus its fastest point.
pub fn signal_speed<'a>(bodies: impl Iterator<Item = (&'a Body, &'a BodyState)>) -> f64 {
    bodies
        .map(|(b, s)| b.wave_speed + s.max_speed)
        .fold(0.0, f64::max)
}

/// Sets `dt` (fixed, or `C h / (c + |v|max)`), clipping the last step onto the end time, and
/// records the CFL number actually used.
pub fn choose_time_step(
    mut clock: ResMut<Clock>,
    mut rule: ResMut<StepRule>,
    grid: Res<GridGeometry>,
    mut health: ResMut<Health>,
    bodies: Query<(&Body, &BodyState)>,
) {
    let h = grid.cell_size;
    let signal = signal_speed(bodies.iter());
    let remaining = clock.end - clock.time;
    let mut dt = rule.rule.dt(h, signal, remaining);
    rule.dt_min = rule.dt_min.min(dt);
    rule.dt_max = rule.dt_max.max(dt);
    let cfl = dt * signal / h;
    rule.cfl_max = rule.cfl_max.max(cfl);
    // Only a fixed step can outgrow the limit (a CFL rule stays on it up to round-off).
    let fixed = matches!(rule.rule, TimeStep::Fixed(_));
    if fixed && cfl > 1.0 && !rule.allow_unstable && health.fault.is_none() {
        let (body, fastest) = bodies
            .iter()
            .max_by(|a, b| a.1.max_speed.total_cmp(&b.1.max_speed))
            .map(|(b, s)| (b.name.clone(), s.max_speed))
            .unwrap_or_default();
        health.fault = Some(Fault {
            step: clock.step,
            time: clock.time,
            message: format!(
                "the fixed time step {dt:e} s is now above the CFL limit (c dt / h = {cfl:.3} > 1): body \"{body}\" has a point moving at {fastest:.3e} m/s; use a smaller step or Cfl(C)"
            ),
        });
    }
    // A remainder within a millionth of a step is folded into this step rather than left
    // as a sliver step of its own.
    clock.last_step = dt >= remaining * (1.0 - 1e-6);
    if clock.last_step {
        dt = remaining;
    }
    clock.dt = dt;
}

/// Zeroes every body's nodal field before the scatter.
pub fn clear_grids(mut fields: Query<&mut GridField>) {
    for mut f in &mut fields {
        f.clear();
    }
}

/// Moves time forward by the step just taken.
pub fn advance_clock(mut clock: ResMut<Clock>) {
    clock.step += 1;
    clock.time = if clock.last_step {
        clock.end
    } else {
        clock.time + clock.dt
    };
}

/// Flags an output at t = 0, at every `output_every`, and at the end.
pub fn decide_output(clock: Res<Clock>, mut outputs: ResMut<OutputClock>) {
    let outputs = &mut *outputs;
    outputs.due = outputs.interval.due(&clock);
}
