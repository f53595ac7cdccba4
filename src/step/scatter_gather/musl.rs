//! MUSL's three passes: the velocity update, the remap of the new momenta to the grid, and
//! the velocity gradient from the remapped velocities.

use bevy_ecs::prelude::*;
use glam::DVec2;
use rayon::prelude::*;

use crate::body::Points;
use crate::grid::{GridField, GridGeometry};
use crate::kernels::NodeSource;
use crate::obstacle::Obstacles;
use crate::step::grid_update::apply_walls;
use crate::step::locate::Location;

use super::gather::{VelocityUpdate, gather_affine, new_velocity};
use crate::resources::Boundaries;
use crate::shape_functions::Scheme;

/// MUSL pass 1: every point's velocity update ([`new_velocity`]) and its advection
/// velocity. With an affine transfer the affine field is taken in pass 3 from the remapped
/// velocities, like `L` and for the same reason (nodes of tiny mass).
pub fn musl_velocity(mut bodies: VelocityUpdate) {
    bodies.each(|_, points, location, nodes, dt, pull| {
        location
            .footprints()
            .par_iter()
            .zip(points.velocity.par_iter_mut())
            .zip(points.advection.par_iter_mut())
            .for_each(|((f, v), adv)| {
                let g = nodes.gather_velocity::<true>(f);
                *v = new_velocity(*v, g.value, g.acceleration, dt, pull);
                *adv = g.value;
            });
    });
}

/// MUSL pass 2: nodal velocities from the updated point momenta `m v`, walls applied.
///
/// The remap leaves out APIC's affine term on purpose. It reproduces affine fields exactly,
/// so the previous step's `C` would pass through it untouched into the gradient pass 3
/// takes the new `C` from: `C` would integrate itself step after step (a bar's compression
/// pulse diverged within 111 steps that way).
pub fn musl_remap(
    grid: Res<GridGeometry>,
    walls: Res<Boundaries>,
    obstacles: Res<Obstacles>,
    mut bodies: Query<(&Points, &Location, &mut GridField)>,
) {
    for (points, location, mut field) in &mut bodies {
        let field = &mut *field;
        field.momentum.fill(DVec2::ZERO);
        for (k, f) in location.footprints().iter().enumerate() {
            let mv = points.mass[k] * points.velocity[k];
            f.for_each_indexed(|_, _, n, w, _| field.momentum[n] += w * mv);
        }
        for n in 0..field.mass.len() {
            let m = field.mass[n];
            field.velocity[n] = if m > 0.0 {
                field.momentum[n] / m
            } else {
                DVec2::ZERO
            };
        }
        apply_walls(&grid, &walls.0, &obstacles, field, None);
    }
}

/// MUSL pass 3: `L` from the remapped velocities.
pub fn musl_gradient(mut bodies: Query<(&mut Points, &Location, &GridField)>) {
    for (mut points, location, field) in &mut bodies {
        location
            .footprints()
            .par_iter()
            .zip(points.velocity_gradient.par_iter_mut())
            .for_each(|(f, l)| *l = f.interpolate_with_gradient(&field.velocity).1);
    }
}

/// MUSL pass 3 with APIC: `L` and the affine field from the remapped velocities.
pub fn musl_apic_gradient<S: Scheme>(
    grid: Res<GridGeometry>,
    mut bodies: Query<(&mut Points, &Location, &GridField)>,
) {
    for (mut points, location, field) in &mut bodies {
        let nodes = NodeSource::unpacked(&field.velocity, &field.acceleration);
        gather_affine::<S>(&grid, &mut points, location, nodes, None);
    }
}
