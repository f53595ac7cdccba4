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
//! velocity and acceleration on their nodes.

use bevy_ecs::prelude::*;
use glam::DVec2;
use rayon::prelude::*;

use crate::grid::{GridField, GridGeometry};
use crate::resources::{Boundaries, Clock, Gravity, Side, Wall, Walls};

pub fn update_grid(
    clock: Res<Clock>,
    grid: Res<GridGeometry>,
    gravity: Res<Gravity>,
    walls: Res<Boundaries>,
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
        apply_walls(&grid, &walls.0, field, Some(dt));
    }
}

/// Which velocity components a wall removes: `(x, y)` masks.
fn constrained(wall: Wall, normal_axis: usize) -> [bool; 2] {
    match wall {
        Wall::Free | Wall::Open | Wall::Periodic => [false, false],
        Wall::NoSlip => [true, true],
        Wall::Slip => {
            let mut c = [false, false];
            c[normal_axis] = true;
            c
        }
    }
}

/// Zeroes the constrained components of node `n`. With `dt` (after the momentum update) the
/// acceleration becomes the change the wall imposes over the step, `-v^n / dt`, so that the
/// FLIP update of nearby points sees the wall stop them; without it (a velocity remap) only
/// velocities are touched.
fn constrain(field: &mut GridField, n: usize, mask: [bool; 2], dt: Option<f64>) {
    for (a, &fixed) in mask.iter().enumerate() {
        if !fixed {
            continue;
        }
        field.velocity[n][a] = 0.0;
        if let Some(dt) = dt {
            let m = field.mass[n];
            let start = if m > 0.0 {
                (field.momentum[n][a] - dt * field.force[n][a]) / m
            } else {
                0.0
            };
            field.force[n][a] = -m * start / dt;
            field.momentum[n][a] = 0.0;
            field.acceleration[n][a] = -start / dt;
        }
    }
}

/// Applies the walls to the nodes on the domain's edges, each node by the condition at its
/// place on the side (a segment's where one covers it); `dt` as in [`constrain`].
pub fn apply_walls(grid: &GridGeometry, walls: &Walls, field: &mut GridField, dt: Option<f64>) {
    for (side, axis, low) in Side::ALL {
        if walls.segments.iter().all(|s| s.side != side) {
            let mask = constrained(walls.side(side), axis);
            if mask == [false, false] {
                continue;
            }
            for n in grid.side_nodes(axis, low) {
                constrain(field, n, mask, dt);
            }
            continue;
        }
        for n in grid.side_nodes(axis, low) {
            let along = grid.node_coordinate(n, 1 - axis);
            let mask = constrained(walls.at(side, along), axis);
            if mask != [false, false] {
                constrain(field, n, mask, dt);
            }
        }
    }
}
