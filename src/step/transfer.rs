//! Particle-to-grid scatter and grid-to-particle gather (docs/model.md §2, steps 2, 5 and 6).
//!
//! Each body scatters only to its own nodal field and gathers only from it; bodies meet
//! through the Contact set. The gathers are parallel over points; the scatter is parallel
//! over bands of cell rows without locks (`bands`).
//!
//! USL gathers velocity, acceleration and velocity gradient in one pass. MUSL splits it:
//! the velocity pass updates `v_p` and keeps the advection velocity, the remap scatters the
//! new `m_p v_p` back to the grid, and the gradient pass takes `L` from those remapped nodal
//! velocities, which are weighted averages of point velocities and so stay bounded at nodes
//! of tiny mass. Either way the points move (and their volumes change) in a last pass,
//! after the optional cell averaging of the dilatation (`dilatation`).

use bevy_ecs::prelude::*;
use bevy_ecs::system::SystemParam;
use glam::{DMat2, DVec2};
use rayon::prelude::*;

use super::bands::{Bands, Shared};
use super::cell_average::CellDilatation;
use super::grid_update::apply_walls;
use super::locate::Location;
use crate::body::{Body, Points};
use crate::grid::{GridField, GridGeometry};
use crate::scene::Wall;
use crate::shape_functions::{Footprint, Scheme};
use crate::sim::{Boundaries, Clock, Gravity, VelocityRule};

/// `m_i = sum S m`, `(mv)_i = sum S m v`, `f_i = sum [S m g - V T . grad S]`, and, when the
/// field keeps normals, `g_i = sum m grad S`, from the footprints of `locate_points`.
/// The scatter runs band by band in parallel without locks (see `bands`).
///
/// With the cell-averaged dilatation the stress's in-plane trace is replaced by its cell
/// mean (`average_stress_trace`) before it is scattered: that force is the exact conjugate
/// of the averaged `tr L`, so the internal forces' power equals the stress power the points
/// see (the B-bar pairing; docs/numerics.md). Without it the two differ wherever the trace
/// varies within a cell, e.g. next to disconnected points, and the impact gained energy at
/// small steps.
pub fn particle_to_grid(
    grid: Res<GridGeometry>,
    gravity: Res<Gravity>,
    mut bodies: Query<(
        &Points,
        &Location,
        &mut GridField,
        &Bands,
        Option<&CellDilatation>,
    )>,
) {
    for (points, location, mut field, bands, cells) in &mut bodies {
        // Monomorphised on the transfer, so FLIP's scatter carries no affine work.
        let scatter = if points.affine.is_empty() {
            scatter_body::<false>
        } else {
            scatter_body::<true>
        };
        scatter(&grid, gravity.0, points, location, &mut field, bands, cells);
    }
}

/// One body's scatter for `particle_to_grid`; `APIC` says whether its points carry an
/// affine field.
fn scatter_body<const APIC: bool>(
    grid: &GridGeometry,
    g: DVec2,
    points: &Points,
    location: &Location,
    field: &mut GridField,
    bands: &Bands,
    cells: Option<&CellDilatation>,
) {
    let normals = !field.mass_gradient.is_empty();
    let nodes = grid.node_count();
    assert!(
        field.mass.len() == nodes
            && field.momentum.len() == nodes
            && field.force.len() == nodes
            && (!normals || field.mass_gradient.len() == nodes),
        "a body's nodal field does not match the grid ({nodes} nodes)"
    );
    let mass = Shared::new(&mut field.mass);
    let momentum = Shared::new(&mut field.momentum);
    let force = Shared::new(&mut field.force);
    let gradient = Shared::new(&mut field.mass_gradient);
    bands.for_each_phase(grid.periodic[1], |b| {
        // Local copies: the stores below could otherwise alias the captured pointers,
        // which the compiler then reloads for every entry.
        let (mass, momentum, force, gradient) = (mass, momentum, force, gradient);
        let window = Bands::node_window(grid, b);
        for &p in bands.points(b) {
            let p = p as usize;
            let f = &location.footprints()[p];
            // What makes the unsafe writes below sound: checked here, not trusted.
            assert!(
                window.holds(f),
                "point {p} reaches outside the nodes of its band {b}: its cell is stale \
                 (points moved since their cells were found) or its extent exceeds half a cell"
            );
            let m = points.mass[p];
            let momentum_at = NodeMomentum::of::<APIC>(points, p, f, grid);
            let mg = m * g;
            let vol = points.volume[p];
            let mut t = points.stress[p];
            if let Some(cells) = cells {
                let shift = 0.5 * (cells.stress_trace(location.cells()[p]) - t.xx - t.yy);
                t.xx += shift;
                t.yy += shift;
            }
            // V T . grad S for grad S = (gx wy, wx gy): the stress columns scaled.
            let (tx, ty) = (vol * t.traction(DVec2::X), vol * t.traction(DVec2::Y));
            f.for_each_indexed(|kx, ky, n, w, grad| {
                // SAFETY: the footprint lies in the band's window (checked above), inside
                // the field, and bands scattering at the same time have disjoint windows.
                unsafe {
                    mass.add_at(n, w * m);
                    momentum.add_at(n, w * momentum_at.at(kx, ky));
                    force.add_at(n, w * mg - grad.x * tx - grad.y * ty);
                    if normals {
                        gradient.add_at(n, m * grad);
                    }
                }
            });
        }
    });
}

/// The momentum a point hands to the nodes of its footprint: `m v`, plus with APIC the
/// momentum of its affine field, `m C_p d_i` at the node of offset `d_i`.
struct NodeMomentum {
    mv: DVec2,
    /// `m C_p` and the node offsets; `None` with FLIP.
    affine: Option<(DMat2, [f64; 3], [f64; 3])>,
}

impl NodeMomentum {
    /// Point `k`'s, with its affine field if `APIC`.
    #[inline]
    fn of<const APIC: bool>(
        points: &Points,
        k: usize,
        f: &Footprint,
        grid: &GridGeometry,
    ) -> NodeMomentum {
        let m = points.mass[k];
        let affine = APIC.then(|| {
            let (dx, dy) = f.offsets(grid, points.position[k]);
            (m * points.affine[k], dx, dy)
        });
        NodeMomentum {
            mv: m * points.velocity[k],
            affine,
        }
    }

    /// The momentum at entry `(kx, ky)`, before the entry's weight.
    #[inline(always)]
    fn at(&self, kx: usize, ky: usize) -> DVec2 {
        match &self.affine {
            Some((mc, dx, dy)) => self.mv + *mc * DVec2::new(dx[kx], dy[ky]),
            None => self.mv,
        }
    }
}

/// A point's new velocity: its FLIP update `v + dt a_grid` pulled the fraction `pull` of the
/// way to the grid's velocity `v_grid` at the point ([`crate::scene::Transfer::pull`]): 0 is
/// FLIP, 1 takes the grid's velocity (PIC, or APIC with the affine field).
#[inline]
fn new_velocity(v: DVec2, v_grid: DVec2, a_grid: DVec2, dt: f64, pull: f64) -> DVec2 {
    if pull == 1.0 {
        return v_grid;
    }
    let flip = v + dt * a_grid;
    flip + pull * (v_grid - flip)
}

/// What every velocity update reads: the step, the grid, the scene's rule and the bodies.
#[derive(SystemParam)]
pub struct VelocityUpdate<'w, 's> {
    clock: Res<'w, Clock>,
    grid: Res<'w, GridGeometry>,
    rule: Res<'w, VelocityRule>,
    bodies: Query<
        'w,
        's,
        (
            &'static Body,
            &'static mut Points,
            &'static Location,
            &'static GridField,
        ),
    >,
}

impl VelocityUpdate<'_, '_> {
    /// Runs `update(grid, points, location, field, dt, pull)` for every body, with the
    /// body's pull ([`VelocityRule::pull`]) for this step.
    fn each(
        &mut self,
        mut update: impl FnMut(&GridGeometry, &mut Points, &Location, &GridField, f64, f64),
    ) {
        let (dt, grid) = (self.clock.dt, &*self.grid);
        for (body, mut points, location, field) in &mut self.bodies {
            let pull = self.rule.pull(dt, grid.cell_size, body.wave_speed);
            update(grid, &mut points, location, field, dt, pull);
        }
    }
}

/// USL without an affine field: the FLIP/PIC velocity update, advection velocity and
/// velocity gradient `L = sum v_i (outer) grad S`, in one pass.
pub fn grid_to_particle(mut bodies: VelocityUpdate) {
    bodies.each(|_, points, location, field, dt, pull| {
        location
            .footprints()
            .par_iter()
            .zip(points.velocity.par_iter_mut())
            .zip(points.advection.par_iter_mut())
            .zip(points.velocity_gradient.par_iter_mut())
            .for_each(|(((f, v), adv), l)| {
                let (v_grid, grad) = f.interpolate_with_gradient(&field.velocity);
                let a_grid = f.interpolate(&field.acceleration);
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
    if S::AFFINE_IS_GRADIENT {
        let (v, l) = f.interpolate_with_gradient(velocity);
        return (v, l, l);
    }
    let (dx, dy) = f.offsets(grid, x);
    let (v, l, b) = f.interpolate_affine(velocity, &dx, &dy);
    (v, l, b * f.affine_inertia(&dx, &dy).inverse())
}

/// USL with an affine field (APIC, affine FLIP): the point's velocity update, its affine
/// field and the velocity gradient, in one pass.
pub fn affine_to_particle<S: Scheme>(mut bodies: VelocityUpdate) {
    bodies.each(|grid, points, location, field, dt, pull| {
        gather_affine::<S>(grid, points, location, field, Some((dt, pull)));
    });
}

/// `L` and the affine field `C_p` of every point from `field`'s velocities, and with
/// `update = Some((dt, pull))` the point's velocity ([`new_velocity`]) and advection velocity
/// too.
fn gather_affine<S: Scheme>(
    grid: &GridGeometry,
    points: &mut Points,
    location: &Location,
    field: &GridField,
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
            let (v_grid, grad, affine) = apic_gather::<S>(f, grid, x, &field.velocity);
            if let Some((dt, pull)) = update {
                let a_grid = if pull == 1.0 {
                    DVec2::ZERO
                } else {
                    f.interpolate(&field.acceleration)
                };
                *v = new_velocity(*v, v_grid, a_grid, dt, pull);
                *adv = v_grid;
            }
            *l = grad;
            *c = affine;
        });
}

/// MUSL pass 1: every point's velocity update ([`new_velocity`]) and its advection
/// velocity. With an affine transfer the affine field is taken in pass 3 from the remapped
/// velocities, like `L` and for the same reason (nodes of tiny mass).
pub fn musl_velocity(mut bodies: VelocityUpdate) {
    bodies.each(|_, points, location, field, dt, pull| {
        location
            .footprints()
            .par_iter()
            .zip(points.velocity.par_iter_mut())
            .zip(points.advection.par_iter_mut())
            .for_each(|((f, v), adv)| {
                let v_grid = f.interpolate(&field.velocity);
                let a_grid = f.interpolate(&field.acceleration);
                *v = new_velocity(*v, v_grid, a_grid, dt, pull);
                *adv = v_grid;
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
        apply_walls(&grid, &walls.0, field, None);
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
        gather_affine::<S>(&grid, &mut points, location, field, None);
    }
}

/// The density the constitutive update sees: each point's own `m/V`.
pub fn point_density(mut bodies: Query<&mut Points>) {
    for mut points in &mut bodies {
        let points = &mut *points;
        points
            .density
            .par_iter_mut()
            .zip(points.mass.par_iter().zip(points.volume.par_iter()))
            .for_each(|(rho, (&m, &v))| *rho = m / v);
    }
}

/// Moves every point by its advection velocity and updates its volume, `V *= exp(dt tr L)`.
/// A point is kept on the domain side of a `Slip` or `NoSlip` wall: interpolating between
/// the wall's fixed nodes and moving interior nodes can carry a point a fraction of a step
/// past the wall, which the material cannot do. A point stopped at a wall loses its velocity
/// into the wall (otherwise FLIP would keep it for ever, since the wall's nodes have no
/// acceleration). A point crossing an `Open` side is retired: parked on the boundary with
/// no mass, velocity or stress, and a negligible volume, so it no longer takes part. Past a
/// `Free` side a point leaves, and the health check stops the run.
pub fn advect_points(
    grid: Res<GridGeometry>,
    clock: Res<Clock>,
    walls: Res<Boundaries>,
    mut bodies: Query<&mut Points>,
) {
    let (dt, grid) = (clock.dt, &*grid);
    let (lo, hi) = (grid.origin, grid.max());
    let w = walls.0;
    let kept = |wall: Wall| matches!(wall, Wall::Slip | Wall::NoSlip | Wall::Open);
    let bound = |wall: Wall, at: f64, far: f64| if kept(wall) { at } else { far };
    let min = DVec2::new(
        bound(w.left, lo.x, f64::NEG_INFINITY),
        bound(w.bottom, lo.y, f64::NEG_INFINITY),
    );
    let max = DVec2::new(
        bound(w.right, hi.x, f64::INFINITY),
        bound(w.top, hi.y, f64::INFINITY),
    );
    // Per axis: whether leaving through the low / high side retires the point.
    let open = [
        [w.left == Wall::Open, w.right == Wall::Open],
        [w.bottom == Wall::Open, w.top == Wall::Open],
    ];
    for mut points in &mut bodies {
        let points = &mut *points;
        points
            .position
            .par_iter_mut()
            .zip(points.velocity.par_iter_mut())
            .zip(points.volume.par_iter_mut())
            .zip(points.mass.par_iter_mut().zip(points.stress.par_iter_mut()))
            .zip(
                points
                    .advection
                    .par_iter()
                    .zip(points.velocity_gradient.par_iter()),
            )
            .for_each(|((((x, v), vol), (m, t)), (&adv, l))| {
                if *m == 0.0 {
                    // Retired earlier: stays parked.
                    *v = DVec2::ZERO;
                    *t = crate::stress::Stress::ZERO;
                    return;
                }
                let moved = grid.wrap(*x + dt * adv);
                *x = moved.clamp(min, max);
                *vol *= exp_of_increment(dt * (l.x_axis.x + l.y_axis.y));
                for a in 0..2 {
                    let (below, above) = (moved[a] < min[a], moved[a] > max[a]);
                    if (below && open[a][0]) || (above && open[a][1]) {
                        *m = 0.0;
                        *v = DVec2::ZERO;
                        *t = crate::stress::Stress::ZERO;
                        *vol *= 1e-12;
                        return;
                    }
                    if (below && v[a] < 0.0) || (above && v[a] > 0.0) {
                        v[a] = 0.0;
                    }
                }
            });
    }
}

/// `e^x` for the volume change of one step, which is small: below 1e-3 in magnitude the
/// Taylor polynomial to `x^5` (truncation under `x^6/720 < 2e-21`, beneath f64 round-off),
/// otherwise `exp`. The library call was 4% of a step.
#[inline]
fn exp_of_increment(x: f64) -> f64 {
    if x.abs() < 1e-3 {
        1.0 + x * (1.0 + x * (0.5 + x * (1.0 / 6.0 + x * (1.0 / 24.0 + x * (1.0 / 120.0)))))
    } else {
        x.exp()
    }
}

#[cfg(test)]
mod tests {
    use super::exp_of_increment;

    #[test]
    fn the_short_exponential_matches_exp_to_round_off() {
        let mut worst: f64 = 0.0;
        for k in -20_000..=20_000 {
            let x = k as f64 * 1.1e-7;
            worst = worst.max((exp_of_increment(x) / x.exp() - 1.0).abs());
        }
        assert!(worst < 3e-16, "relative error {worst:e}");
        assert_eq!(exp_of_increment(0.5), 0.5f64.exp());
    }
}
