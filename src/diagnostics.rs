//! Whole-body measurements and the health check that stops a run going wrong.
//!
//! A run must give a bounded physical answer or stop with a clear explanation; the check
//! looks for non-finite state and points leaving the domain and records the first fault,
//! which the runner turns into a failed (but kept) run.

use bevy_ecs::prelude::*;
use glam::DVec2;
use rayon::prelude::*;

use crate::body::{Body, BodyState, ChunkSurvey, Points};
use crate::error::Fault;
use crate::grid::GridGeometry;
use crate::resources::{Clock, Gravity};

/// The first fault seen, if any.
#[derive(Resource, Debug, Default)]
pub struct Health {
    pub fault: Option<Fault>,
}

/// The kinetic energy past which a run is declared diverging (J/m); `None` until the first
/// step sets the default (see `scene::Limits`).
#[derive(Resource, Debug, Default)]
pub struct EnergyLimit {
    pub bound: Option<f64>,
}

/// Stops a run whose total kinetic energy exceeds its bound. Without an explicit bound, the
/// first step sets ten times the kinetic plus potential energy then, plus the kinetic
/// energy of every body moving at 1% of its p-wave speed (what a 1% elastic strain stores):
/// no source in the model adds energy, so only a numerical blow-up crosses it.
pub fn check_energy(
    clock: Res<Clock>,
    grid: Res<GridGeometry>,
    gravity: Res<Gravity>,
    mut limit: ResMut<EnergyLimit>,
    mut health: ResMut<Health>,
    bodies: Query<(&Body, &BodyState)>,
) {
    if health.fault.is_some() {
        return;
    }
    let kinetic: f64 = bodies.iter().map(|(_, s)| s.kinetic_energy).sum();
    let Some(bound) = limit.bound else {
        let g = gravity.0;
        let (lo, hi) = (grid.origin, grid.max());
        let corners = [lo, DVec2::new(hi.x, lo.y), hi, DVec2::new(lo.x, hi.y)];
        let lowest = corners
            .iter()
            .map(|c| -g.dot(*c))
            .fold(f64::INFINITY, f64::min);
        let energy: f64 = bodies
            .iter()
            .map(|(b, s)| {
                let potential = s.mass * (-g.dot(s.centre_of_mass) - lowest);
                let strain = 0.5 * s.mass * (0.01 * b.wave_speed).powi(2);
                10.0 * (s.kinetic_energy + potential) + strain
            })
            .sum();
        limit.bound = Some(energy);
        return;
    };
    if kinetic > bound {
        let (body, state) = bodies
            .iter()
            .max_by(|a, b| a.1.kinetic_energy.total_cmp(&b.1.kinetic_energy))
            .map(|(b, s)| (b.name.clone(), *s))
            .unwrap_or_default();
        health.fault = Some(Fault {
            step: clock.step,
            time: clock.time,
            message: format!(
                "the kinetic energy {kinetic:.3e} J/m exceeds its bound {bound:.3e} J/m (set limits.max_kinetic_energy to change it): the run is diverging; body \"{body}\" carries {:.3e} J/m and its fastest point moves at {:.3e} m/s",
                state.kinetic_energy, state.max_speed
            ),
        });
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

/// Chunk surveys of a body's points, kept so that the survey allocates nothing per step.
#[derive(Component, Clone, Debug, Default)]
pub struct Surveys(Vec<ChunkSurvey>);

/// Whether a chunk may hold a faulty point: the screen is exact (it flags every chunk that
/// holds one), so only flagged chunks are searched point by point.
fn suspect(s: &ChunkSurvey, grid: &GridGeometry) -> bool {
    let (lo, hi) = (grid.origin, grid.max());
    let outside = |a: usize| !grid.periodic[a] && (s.lowest[a] < lo[a] || s.highest[a] > hi[a]);
    s.non_finite != 0.0 || s.min_volume <= 0.0 || outside(0) || outside(1)
}

/// Refreshes every body's centre of mass, velocity, kinetic energy and top speed, and
/// records the first non-finite value, empty volume or escaped point. One parallel pass
/// over fixed chunks does both (the sums are deterministic, see `body::SURVEY_CHUNK`).
pub fn survey_bodies(
    clock: Res<Clock>,
    grid: Res<GridGeometry>,
    mut health: ResMut<Health>,
    mut bodies: Query<(&Body, &Points, &mut BodyState, &mut Surveys)>,
) {
    for (body, points, mut state, mut surveys) in &mut bodies {
        let n = points.len();
        surveys
            .0
            .resize(ChunkSurvey::count(n), ChunkSurvey::default());
        surveys
            .0
            .par_iter_mut()
            .enumerate()
            .for_each(|(c, s)| *s = ChunkSurvey::over(points, c));
        *state = BodyState::from_chunks(surveys.0.iter().copied());
        if health.fault.is_some() {
            continue;
        }
        let faulty = surveys
            .0
            .iter()
            .enumerate()
            .filter(|(_, s)| suspect(s, &grid))
            .find_map(|(c, _)| {
                ChunkSurvey::range(c, n).find_map(|k| Some(k).zip(point_problem(points, k, &grid)))
            });
        if let Some((k, why)) = faulty {
            let x = points.position[k];
            health.fault = Some(Fault {
                step: clock.step,
                time: clock.time,
                message: format!(
                    "body \"{}\", point {k} (at x = {:.4}, y = {:.4}): {why}",
                    body.name, x.x, x.y
                ),
            });
        }
    }
}
