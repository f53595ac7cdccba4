//! Whole-body measurements and the health check that stops a run going wrong.
//!
//! A run must give a bounded physical answer or stop with a clear explanation; the check
//! looks for non-finite state and points leaving the domain and records the first fault,
//! which the runner turns into a failed (but kept) run.

use bevy_ecs::prelude::*;
use rayon::prelude::*;

use crate::body::{Body, BodyState, Points};
use crate::error::Fault;
use crate::grid::GridGeometry;
use crate::sim::Clock;

/// The first fault seen, if any.
#[derive(Resource, Debug, Default)]
pub struct Health {
    pub fault: Option<Fault>,
}

/// Refreshes every body's centre of mass, velocity, kinetic energy and top speed.
pub fn measure_bodies(mut bodies: Query<(&Points, &mut BodyState)>) {
    for (points, mut state) in &mut bodies {
        *state = BodyState::measure(points);
    }
}

/// What is wrong with point `k`, if anything.
fn point_problem(points: &Points, k: usize, grid: &GridGeometry) -> Option<String> {
    let x = points.position[k];
    if !x.is_finite() {
        return Some("its position is not finite".into());
    }
    if !points.velocity[k].is_finite() {
        return Some("its velocity is not finite".into());
    }
    if !points.stress[k].is_finite() {
        return Some("its stress is not finite".into());
    }
    if !(points.volume[k].is_finite() && points.volume[k] > 0.0) {
        return Some(format!("its volume became {}", points.volume[k]));
    }
    let (lo, hi) = (grid.origin, grid.max());
    let sides = [
        (x.x < lo.x && !grid.periodic[0], "left"),
        (x.x > hi.x && !grid.periodic[0], "right"),
        (x.y < lo.y && !grid.periodic[1], "bottom"),
        (x.y > hi.y && !grid.periodic[1], "top"),
    ];
    sides
        .iter()
        .find(|(out, _)| *out)
        .map(|(_, side)| format!("it left the domain through the {side} side"))
}

/// Records the first non-finite value or escaped point.
pub fn check_health(
    clock: Res<Clock>,
    grid: Res<GridGeometry>,
    mut health: ResMut<Health>,
    bodies: Query<(&Body, &Points)>,
) {
    if health.fault.is_some() {
        return;
    }
    for (body, points) in &bodies {
        let found = (0..points.len())
            .into_par_iter()
            .find_first(|&k| point_problem(points, k, &grid).is_some());
        if let Some(k) = found {
            let why = point_problem(points, k, &grid).unwrap_or_default();
            let x = points.position[k];
            health.fault = Some(Fault {
                step: clock.step,
                time: clock.time,
                message: format!(
                    "body \"{}\", point {k} (at x = {:.4}, y = {:.4}): {why}",
                    body.name, x.x, x.y
                ),
            });
            return;
        }
    }
}
