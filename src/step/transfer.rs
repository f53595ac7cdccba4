//! Particle-to-grid scatter and grid-to-particle gather (SCIENCE.md 2, steps 1 and 5-6).
//!
//! Each body scatters only to its own nodal field and gathers only from it; bodies meet
//! through the Contact set. The gathers are parallel over points; the scatter is serial per
//! body for now (a lock-free parallel scatter is the performance issue's work).
//!
//! USL gathers velocity, acceleration and velocity gradient in one pass. MUSL splits it:
//! the velocity pass updates `v_p` and keeps the advection velocity, the remap scatters the
//! new `m_p v_p` back to the grid, and the gradient pass takes `L` from those remapped nodal
//! velocities, which are weighted averages of point velocities and so stay bounded at nodes
//! of tiny mass.

use bevy_ecs::prelude::*;
use glam::{DMat2, DVec2};
use rayon::prelude::*;

use super::grid_update::apply_walls;
use crate::body::Points;
use crate::grid::{GridField, GridGeometry};
use crate::integration::{Scheme, Stencil};
use crate::sim::{Boundaries, Clock, FlipRatio, Gravity};

/// `m_i = sum S m`, `(mv)_i = sum S m v`, `f_i = sum [S m g - V T . grad S]`, and, when the
/// field keeps normals, `g_i = sum m grad S`.
pub fn particle_to_grid<S: Scheme>(
    grid: Res<GridGeometry>,
    gravity: Res<Gravity>,
    mut bodies: Query<(&Points, &mut GridField)>,
) {
    let g = gravity.0;
    for (points, mut field) in &mut bodies {
        let field = &mut *field;
        let normals = !field.mass_gradient.is_empty();
        for p in 0..points.len() {
            let stencil = Stencil::new::<S>(&grid, points.position[p], points.half_width[p]);
            let m = points.mass[p];
            let mv = m * points.velocity[p];
            let vol = points.volume[p];
            let t = points.stress[p];
            for (n, w, grad) in stencil.iter() {
                field.mass[n] += w * m;
                field.momentum[n] += w * mv;
                field.force[n] += w * m * g - vol * t.traction(grad);
                if normals {
                    field.mass_gradient[n] += m * grad;
                }
            }
        }
    }
}

/// `sum v_i (outer) grad S_ip`.
#[inline]
fn velocity_gradient(stencil: &Stencil, velocity: &[DVec2]) -> DMat2 {
    let mut l = DMat2::ZERO;
    for (n, _, grad) in stencil.iter() {
        let v = velocity[n];
        l += DMat2::from_cols(v * grad.x, v * grad.y);
    }
    l
}

/// Interpolated grid velocity and acceleration at a point.
#[inline]
fn interpolate(stencil: &Stencil, field: &GridField) -> (DVec2, DVec2) {
    let mut v = DVec2::ZERO;
    let mut a = DVec2::ZERO;
    for (n, w, _) in stencil.iter() {
        v += w * field.velocity[n];
        a += w * field.acceleration[n];
    }
    (v, a)
}

/// FLIP velocity update blended with PIC by `flip`.
#[inline]
fn new_velocity(v: DVec2, v_grid: DVec2, a_grid: DVec2, dt: f64, flip: f64) -> DVec2 {
    flip * (v + dt * a_grid) + (1.0 - flip) * v_grid
}

/// Moves a point by its advection velocity and updates its volume from `tr L`.
#[inline]
fn advance(grid: &GridGeometry, x: &mut DVec2, vol: &mut f64, v_grid: DVec2, l: DMat2, dt: f64) {
    *x = grid.wrap(*x + dt * v_grid);
    *vol *= (dt * (l.x_axis.x + l.y_axis.y)).exp();
}

/// USL: FLIP velocity update, advection with the new grid velocity, velocity gradient
/// `L = sum v_i (outer) grad S`, and volume `V *= exp(dt tr L)`, in one pass.
pub fn grid_to_particle<S: Scheme>(
    grid: Res<GridGeometry>,
    clock: Res<Clock>,
    flip: Res<FlipRatio>,
    mut bodies: Query<(&mut Points, &GridField)>,
) {
    let (dt, flip, grid) = (clock.dt, flip.0, &*grid);
    for (mut points, field) in &mut bodies {
        let points = &mut *points;
        points
            .position
            .par_iter_mut()
            .zip(points.velocity.par_iter_mut())
            .zip(points.velocity_gradient.par_iter_mut())
            .zip(points.volume.par_iter_mut())
            .zip(
                points
                    .half_width
                    .par_iter()
                    .zip(points.advection.par_iter_mut()),
            )
            .for_each(|((((x, v), l), vol), (&a, adv))| {
                let stencil = Stencil::new::<S>(grid, *x, a);
                let (v_grid, a_grid) = interpolate(&stencil, field);
                *v = new_velocity(*v, v_grid, a_grid, dt, flip);
                *adv = v_grid;
                *l = velocity_gradient(&stencil, &field.velocity);
                advance(grid, x, vol, v_grid, *l, dt);
            });
    }
}

/// MUSL pass 1: the FLIP velocity update; the advection velocity is kept for pass 3.
pub fn musl_velocity<S: Scheme>(
    grid: Res<GridGeometry>,
    clock: Res<Clock>,
    flip: Res<FlipRatio>,
    mut bodies: Query<(&mut Points, &GridField)>,
) {
    let (dt, flip, grid) = (clock.dt, flip.0, &*grid);
    for (mut points, field) in &mut bodies {
        let points = &mut *points;
        points
            .position
            .par_iter()
            .zip(points.half_width.par_iter())
            .zip(points.velocity.par_iter_mut())
            .zip(points.advection.par_iter_mut())
            .for_each(|(((x, &a), v), adv)| {
                let stencil = Stencil::new::<S>(grid, *x, a);
                let (v_grid, a_grid) = interpolate(&stencil, field);
                *v = new_velocity(*v, v_grid, a_grid, dt, flip);
                *adv = v_grid;
            });
    }
}

/// MUSL pass 2: nodal velocities from the updated point momenta, walls applied.
pub fn musl_remap<S: Scheme>(
    grid: Res<GridGeometry>,
    walls: Res<Boundaries>,
    mut bodies: Query<(&Points, &mut GridField)>,
) {
    for (points, mut field) in &mut bodies {
        let field = &mut *field;
        field.momentum.fill(DVec2::ZERO);
        for p in 0..points.len() {
            let stencil = Stencil::new::<S>(&grid, points.position[p], points.half_width[p]);
            let mv = points.mass[p] * points.velocity[p];
            for (n, w, _) in stencil.iter() {
                field.momentum[n] += w * mv;
            }
        }
        for n in 0..field.mass.len() {
            let m = field.mass[n];
            field.velocity[n] = if m > 0.0 {
                field.momentum[n] / m
            } else {
                DVec2::ZERO
            };
        }
        apply_walls(&grid, &walls.0, field);
    }
}

/// MUSL pass 3: `L` from the remapped velocities, then position and volume.
pub fn musl_gradient<S: Scheme>(
    grid: Res<GridGeometry>,
    clock: Res<Clock>,
    mut bodies: Query<(&mut Points, &GridField)>,
) {
    let (dt, grid) = (clock.dt, &*grid);
    for (mut points, field) in &mut bodies {
        let points = &mut *points;
        points
            .position
            .par_iter_mut()
            .zip(points.velocity_gradient.par_iter_mut())
            .zip(points.volume.par_iter_mut())
            .zip(
                points
                    .half_width
                    .par_iter()
                    .zip(points.advection.par_iter()),
            )
            .for_each(|(((x, l), vol), (&a, &adv))| {
                let stencil = Stencil::new::<S>(grid, *x, a);
                *l = velocity_gradient(&stencil, &field.velocity);
                advance(grid, x, vol, adv, *l, dt);
            });
    }
}
