//! The move: positions by the advection velocity, volumes by `exp(dt tr L)`, walls and open
//! sides, and the per-point density.

use bevy_ecs::prelude::*;
use glam::DVec2;
use rayon::prelude::*;

use crate::body::Points;
use crate::grid::GridGeometry;
use crate::obstacle::Obstacles;

use crate::resources::{Boundaries, Clock, Side, Wall, Walls};
use crate::stress::Stress;

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

/// The box the walls keep points in: a `Slip`, `NoSlip`, `Frictional` or `Open` side bounds it, a `Free` or
/// periodic one does not (a point past a free side stops the run; periodic sides wrap).
/// Segments are not looked at: the box is what the sides' own conditions bound.
pub(crate) fn kept_box(grid: &GridGeometry, w: &Walls) -> (DVec2, DVec2) {
    let (lo, hi) = (grid.origin, grid.max());
    let kept = |wall: Wall| {
        matches!(
            wall,
            Wall::Slip | Wall::NoSlip | Wall::Frictional { .. } | Wall::Open
        )
    };
    let bound = |wall: Wall, at: f64, far: f64| if kept(wall) { at } else { far };
    let min = DVec2::new(
        bound(w.left, lo.x, f64::NEG_INFINITY),
        bound(w.bottom, lo.y, f64::NEG_INFINITY),
    );
    let max = DVec2::new(
        bound(w.right, hi.x, f64::INFINITY),
        bound(w.top, hi.y, f64::INFINITY),
    );
    (min, max)
}

/// Moves every point by its advection velocity and updates its volume, `V *= exp(dt tr L)`.
/// A point is kept on the domain side of a `Slip` or `NoSlip` wall: interpolating between
/// the wall's fixed nodes and moving interior nodes can carry a point a fraction of a step
/// past the wall, which the material cannot do. A point stopped at a wall loses its velocity
/// into the wall (otherwise FLIP would keep it for ever, since the wall's nodes have no
/// acceleration). A point crossing an `Open` side is retired: parked on the boundary with
/// no mass, velocity or stress, and a negligible volume, so it no longer takes part. Past a
/// `Free` side a point leaves, and the health check stops the run. Where a side has segments
/// the condition is the one at the place the point crosses it. A point whose move ends inside
/// an obstacle is stopped where its path enters it (`Obstacles::stop`).
pub fn advect_points(
    grid: Res<GridGeometry>,
    clock: Res<Clock>,
    walls: Res<Boundaries>,
    obstacles: Res<Obstacles>,
    mut bodies: Query<&mut Points>,
) {
    let (dt, grid) = (clock.dt, &*grid);
    let w = &walls.0;
    let obstacles = &*obstacles;
    if !w.segments.is_empty() {
        return move_points(&mut bodies, grid, dt, obstacles, |p| {
            cross_segments(grid, w, p)
        });
    }
    let (min, max) = kept_box(grid, w);
    // Per axis: whether leaving through the low / high side retires the point.
    let open = [
        [w.left == Wall::Open, w.right == Wall::Open],
        [w.bottom == Wall::Open, w.top == Wall::Open],
    ];
    move_points(&mut bodies, grid, dt, obstacles, |p| {
        *p.x = p.moved.clamp(min, max);
        for a in 0..2 {
            let (below, above) = (p.moved[a] < min[a], p.moved[a] > max[a]);
            if (below && open[a][0]) || (above && open[a][1]) {
                p.retire();
                return;
            }
            if (below && p.v[a] < 0.0) || (above && p.v[a] > 0.0) {
                p.v[a] = 0.0;
            }
        }
    });
}

/// One point in the move: where the advection takes it (`moved`, wrapped on periodic axes)
/// and what the walls may change.
struct Moving<'a> {
    moved: DVec2,
    x: &'a mut DVec2,
    v: &'a mut DVec2,
    vol: &'a mut f64,
    m: &'a mut f64,
    t: &'a mut Stress,
}

impl Moving<'_> {
    /// Parks the point where it stands (on the boundary) with no mass, velocity or stress
    /// and a negligible volume.
    fn retire(&mut self) {
        *self.m = 0.0;
        *self.v = DVec2::ZERO;
        *self.t = Stress::ZERO;
        *self.vol *= 1e-12;
    }
}

/// Moves every live point of every body by `dt` times its advection velocity, updates its
/// volume, hands it to `walls` to place it (set `x`) against the sides, then stops it at the
/// obstacles; retired points stay parked.
fn move_points(
    bodies: &mut Query<&mut Points>,
    grid: &GridGeometry,
    dt: f64,
    obstacles: &Obstacles,
    walls: impl Fn(&mut Moving) + Send + Sync,
) {
    for mut points in bodies.iter_mut() {
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
                    *t = Stress::ZERO;
                    return;
                }
                let from = *x;
                let moved = grid.wrap(from + dt * adv);
                *vol *= exp_of_increment(dt * (l.x_axis.x + l.y_axis.y));
                walls(&mut Moving {
                    moved,
                    x,
                    v,
                    vol,
                    m,
                    t,
                });
                if !obstacles.is_empty() && *m != 0.0 {
                    *x = obstacles.stop(from, *x, v);
                }
            });
    }
}

/// The walls with segments: a point that crosses a side meets the condition at the place it
/// crosses (kept in by `Slip` and `NoSlip`, retired by `Open`, let go by `Free`).
fn cross_segments(grid: &GridGeometry, w: &Walls, p: &mut Moving) {
    let (lo, hi) = (grid.origin, grid.max());
    let mut kept = p.moved;
    for a in 0..2 {
        let (below, above) = (p.moved[a] < lo[a], p.moved[a] > hi[a]);
        if !(below || above) {
            continue;
        }
        match w.at(Side::of(a, above), p.moved[1 - a]) {
            Wall::Free | Wall::Periodic => {}
            Wall::Open => {
                *p.x = p.moved.clamp(lo, hi);
                p.retire();
                return;
            }
            Wall::Slip | Wall::NoSlip | Wall::Frictional { .. } => {
                kept[a] = if below { lo[a] } else { hi[a] };
                if (below && p.v[a] < 0.0) || (above && p.v[a] > 0.0) {
                    p.v[a] = 0.0;
                }
            }
        }
    }
    *p.x = kept;
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
