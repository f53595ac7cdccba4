//! Nodal momentum update and walls (docs/model.md §2, step 3).
//!
//! `(mv) += dt f`, `a = f/m`, `v = (mv)/m` on nodes heavier than the body's mass tolerance.
//! Lighter nodes (docs/model.md §2, step 3) drop their internal force, whose acceleration
//! `f/m` is unbounded as `m -> 0` with linear shape functions, but keep the velocity of
//! their few contributing points plus gravity: `a = g`, `v = (mv)/m + dt g`. Zeroing their
//! velocity instead, as is usual, gives every contributing point a spurious
//! velocity gradient `-v (outer) grad S` of order `|v|/h`; the free-fall test caught a body
//! blowing up that way (docs/numerics.md). Empty nodes get zero velocity.
//! Walls then zero the normal (Slip) or both (NoSlip) components of force, momentum,
//! velocity and acceleration on their nodes; `Frictional` sides and the obstacles' nodes
//! (`crate::obstacle`) take the one-sided surface law instead.

use bevy_ecs::prelude::*;
use glam::DVec2;
use rayon::prelude::*;

use crate::grid::{GridField, GridGeometry};
use crate::obstacle::{Obstacles, surface_velocity};
use crate::resources::{Boundaries, Clock, Gravity, Side, Wall, Walls};

pub fn update_grid(
    clock: Res<Clock>,
    grid: Res<GridGeometry>,
    gravity: Res<Gravity>,
    walls: Res<Boundaries>,
    obstacles: Res<Obstacles>,
    mut fields: Query<&mut GridField>,
) {
    let dt = clock.dt;
    let g = gravity.0;
    for mut field in &mut fields {
        let field = &mut *field;
        let tol = field.mass_tolerance;
        // Node by node, independent: parallel and bitwise the same for any thread count.
        // Nodes outside the active range are empty and at rest already.
        let nodes = field.active();
        field.mass[nodes.clone()]
            .par_iter()
            .zip(field.momentum[nodes.clone()].par_iter_mut())
            .zip(field.force[nodes.clone()].par_iter_mut())
            .zip(
                field.acceleration[nodes.clone()]
                    .par_iter_mut()
                    .zip(field.velocity[nodes].par_iter_mut()),
            )
            .for_each(|(((&m, mv), f), (a, v))| {
                if m > tol {
                    *mv += dt * *f;
                    *a = *f / m;
                    *v = *mv / m;
                } else if m > 0.0 {
                    *f = m * g;
                    *mv += dt * m * g;
                    *a = g;
                    *v = *mv / m;
                } else {
                    *a = DVec2::ZERO;
                    *v = DVec2::ZERO;
                }
            });
        apply_walls(&grid, &walls.0, &obstacles, field, Some(dt));
    }
}

/// Which velocity components a two-sided wall removes: `(x, y)` masks (`Frictional` is
/// one-sided and applied by its surface law instead).
fn constrained(wall: Wall, normal_axis: usize) -> [bool; 2] {
    match wall {
        Wall::Free | Wall::Open | Wall::Periodic | Wall::Frictional { .. } => [false, false],
        Wall::NoSlip => [true, true],
        Wall::Slip => {
            let mut c = [false, false];
            c[normal_axis] = true;
            c
        }
    }
}

/// Sets component `a` of node `n`'s velocity to `value`. With `dt` (after the momentum
/// update) the acceleration becomes the change the wall imposes over the step,
/// `(value - v^n) / dt`, and force and momentum follow, so that the FLIP update of nearby
/// points sees the wall stop them; without it (a velocity remap) only the velocity changes.
fn set_component(field: &mut GridField, n: usize, a: usize, value: f64, dt: Option<f64>) {
    field.velocity[n][a] = value;
    if let Some(dt) = dt {
        let m = field.mass[n];
        let start = if m > 0.0 {
            (field.momentum[n][a] - dt * field.force[n][a]) / m
        } else {
            0.0
        };
        field.force[n][a] = m * (value - start) / dt;
        field.momentum[n][a] = m * value;
        field.acceleration[n][a] = (value - start) / dt;
    }
}

/// Zeroes the constrained components of node `n`; `dt` as in [`set_component`].
fn constrain(field: &mut GridField, n: usize, mask: [bool; 2], dt: Option<f64>) {
    for (a, &fixed) in mask.iter().enumerate() {
        if fixed {
            set_component(field, n, a, 0.0, dt);
        }
    }
}

/// Applies a one-sided surface law (`obstacle::surface_velocity`) with outward normal
/// `normal` at node `n`; `dt` as in [`set_component`].
fn hold(field: &mut GridField, n: usize, normal: DVec2, wall: Wall, dt: Option<f64>) {
    let v = field.velocity[n];
    let kept = surface_velocity(v, normal, wall);
    for a in 0..2 {
        if kept[a] != v[a] {
            set_component(field, n, a, kept[a], dt);
        }
    }
}

/// Applies the walls to the nodes on the domain's edges, each node by the condition at its
/// place on the side (a segment's where one covers it), then the obstacles to the nodes they
/// hold; `dt` as in [`set_component`].
pub fn apply_walls(
    grid: &GridGeometry,
    walls: &Walls,
    obstacles: &Obstacles,
    field: &mut GridField,
    dt: Option<f64>,
) {
    for (side, axis, low) in Side::ALL {
        let uniform = walls.segments.iter().all(|s| s.side != side);
        let frictional = matches!(walls.side(side), Wall::Frictional { .. });
        if uniform && !frictional && constrained(walls.side(side), axis) == [false, false] {
            continue;
        }
        // The side's normal pointing into the domain: the wall's surface faces the inside.
        let mut inward = DVec2::ZERO;
        inward[axis] = if low { 1.0 } else { -1.0 };
        for n in grid.side_nodes(axis, low) {
            let wall = if uniform {
                walls.side(side)
            } else {
                walls.at(side, grid.node_coordinate(n, 1 - axis))
            };
            if let Wall::Frictional { .. } = wall {
                hold(field, n, inward, wall, dt);
                continue;
            }
            let mask = constrained(wall, axis);
            if mask != [false, false] {
                constrain(field, n, mask, dt);
            }
        }
    }
    for (n, normal, wall) in obstacles.held() {
        hold(field, n, normal, wall, dt);
    }
}
