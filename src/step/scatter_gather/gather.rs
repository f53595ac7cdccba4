//! The USL gathers: each point's velocity update, advection velocity and velocity gradient
//! (and affine field) from its body's nodes, in one pass.

use bevy_ecs::prelude::*;
use bevy_ecs::system::SystemParam;
use glam::{DMat2, DVec2};
use rayon::prelude::*;

use crate::body::{Body, Points};
use crate::grid::{GridField, GridGeometry};
use crate::kernels::{Kernels, NodeSource};
use crate::step::locate::Location;

use crate::resources::{Clock, VelocityRule};
use crate::shape_functions::{Footprint, Gathered, Scheme};

/// A point's new velocity: its FLIP update `v + dt a_grid` pulled the fraction `pull` of the
/// way to the grid's velocity `v_grid` at the point ([`crate::transfer::Transfer::pull`]): 0 is
/// FLIP, 1 takes the grid's velocity (PIC, or APIC with the affine field).
#[inline]
pub(super) fn new_velocity(v: DVec2, v_grid: DVec2, a_grid: DVec2, dt: f64, pull: f64) -> DVec2 {
    if pull == 1.0 {
        return v_grid;
    }
    let flip = v + dt * a_grid;
    flip + pull * (v_grid - flip)
}

/// What every velocity update reads: the step, the grid, the scene's rule, the kernels and
/// the bodies.
#[derive(SystemParam)]
pub struct VelocityUpdate<'w, 's> {
    clock: Res<'w, Clock>,
    grid: Res<'w, GridGeometry>,
    rule: Res<'w, VelocityRule>,
    kernels: Res<'w, Kernels>,
    bodies: Query<
        'w,
        's,
        (
            &'static Body,
            &'static mut Points,
            &'static Location,
            &'static mut GridField,
        ),
    >,
}

impl VelocityUpdate<'_, '_> {
    /// Runs `update(grid, points, location, nodes, dt, pull)` for every body, with the
    /// body's nodes as its kernels read them (packed first if they read packed nodes) and
    /// its pull ([`VelocityRule::pull`]) for this step.
    pub(super) fn each(
        &mut self,
        mut update: impl FnMut(&GridGeometry, &mut Points, &Location, NodeSource, f64, f64),
    ) {
        let (dt, grid, kernels) = (self.clock.dt, &*self.grid, *self.kernels);
        for (body, mut points, location, mut field) in &mut self.bodies {
            if kernels.packs() {
                field.pack_motion();
            }
            let pull = self.rule.pull(dt, grid.cell_size, body.wave_speed);
            let nodes = NodeSource::of(&field, kernels);
            update(grid, &mut points, location, nodes, dt, pull);
        }
    }
}

/// USL without an affine field: the FLIP/PIC velocity update, advection velocity and
/// velocity gradient `L = sum v_i (outer) grad S`, in one pass.
pub fn grid_to_particle(mut bodies: VelocityUpdate) {
    bodies.each(|_, points, location, nodes, dt, pull| {
        location
            .footprints()
            .par_iter()
            .zip(points.velocity.par_iter_mut())
            .zip(points.advection.par_iter_mut())
            .zip(points.velocity_gradient.par_iter_mut())
            .for_each(|(((f, v), adv), l)| {
                let g = nodes.gather_velocity::<true>(f);
                let (v_grid, grad, a_grid) = (g.value, g.gradient, g.acceleration);
                *v = new_velocity(*v, v_grid, a_grid, dt, pull);
                *adv = v_grid;
                *l = grad;
            });
    });
}

/// The APIC gather at one point: the grid velocity `v`, the velocity gradient `L` and the
/// affine matrix `C = B D^-1` (Jiang et al. 2015), with `B = sum S_i v_i d_i^T` and
/// `D = sum S_i d_i d_i^T`. For bilinear weights `B D^-1` is `L` itself, which is taken
/// (`Scheme::AFFINE_IS_GRADIENT`): their `D` vanishes on node lines. CPDI's `D` has a
/// diagonal of at least `a^2/3`, so it is always invertible.
#[inline]
pub fn apic_gather<S: Scheme>(
    f: &Footprint,
    grid: &GridGeometry,
    x: DVec2,
    velocity: &[DVec2],
) -> (DVec2, DMat2, DMat2) {
    let (g, c) = apic_sums::<S, false>(f, grid, x, &NodeSource::unpacked(velocity, &[]));
    (g.value, g.gradient, c)
}

/// [`apic_gather`]'s sums and `C`, with `ACCELERATION` also the grid acceleration at the
/// point, in the same pass over the nodes.
#[inline(always)]
fn apic_sums<S: Scheme, const ACCELERATION: bool>(
    f: &Footprint,
    grid: &GridGeometry,
    x: DVec2,
    nodes: &NodeSource,
) -> (Gathered, DMat2) {
    if S::AFFINE_IS_GRADIENT {
        let g = nodes.gather_velocity::<ACCELERATION>(f);
        return (g, g.gradient);
    }
    let (dx, dy) = f.offsets(grid, x);
    let g = nodes.gather::<true, ACCELERATION>(f, &dx, &dy);
    (g, g.affine_b * f.affine_inertia(&dx, &dy).inverse())
}

/// USL with an affine field (APIC, affine FLIP): the point's velocity update, its affine
/// field and the velocity gradient, in one pass.
pub fn affine_to_particle<S: Scheme>(mut bodies: VelocityUpdate) {
    bodies.each(|grid, points, location, nodes, dt, pull| {
        gather_affine::<S>(grid, points, location, nodes, Some((dt, pull)));
    });
}

/// `L` and the affine field `C_p` of every point from the velocities of `nodes`, and with
/// `update = Some((dt, pull))` the point's velocity ([`new_velocity`]) and advection velocity
/// too.
pub(super) fn gather_affine<S: Scheme>(
    grid: &GridGeometry,
    points: &mut Points,
    location: &Location,
    nodes: NodeSource,
    update: Option<(f64, f64)>,
) {
    location
        .footprints()
        .par_iter()
        .zip(points.position.par_iter())
        .zip(points.velocity.par_iter_mut())
        .zip(points.advection.par_iter_mut())
        .zip(
            points
                .velocity_gradient
                .par_iter_mut()
                .zip(points.affine.par_iter_mut()),
        )
        .for_each(|((((f, &x), v), adv), (l, c))| {
            let (g, affine) = match update {
                // Pulled all the way to the grid (APIC): the acceleration is not needed.
                Some((dt, pull)) if pull != 1.0 => {
                    let (g, affine) = apic_sums::<S, true>(f, grid, x, &nodes);
                    *v = new_velocity(*v, g.value, g.acceleration, dt, pull);
                    (g, affine)
                }
                Some(_) => {
                    let (g, affine) = apic_sums::<S, false>(f, grid, x, &nodes);
                    *v = g.value;
                    (g, affine)
                }
                None => apic_sums::<S, false>(f, grid, x, &nodes),
            };
            if update.is_some() {
                *adv = g.value;
            }
            *l = g.gradient;
            *c = affine;
        });
}
