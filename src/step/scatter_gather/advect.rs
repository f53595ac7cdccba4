//! The move: positions by the advection velocity, volumes by `exp(dt tr L)`, walls and open
//! sides, and the per-point density.
//!
//! Most points in most steps meet no wall: with AVX2 (`Kernels::avx2`) such points go four at
//! a time through `avx2::move_four`, the per-point rule's operations in its order, so the
//! state is the same to the bit (docs/BENCHMARKS.md, "Lanes over points where a pass is a
//! batch").

use bevy_ecs::prelude::*;
use glam::{DMat2, DVec2};
use rayon::prelude::*;

use crate::body::Points;
use crate::grid::GridGeometry;
use crate::kernels::Kernels;
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
    kernels: Res<Kernels>,
    mut bodies: Query<&mut Points>,
) {
    let (dt, grid) = (clock.dt, &*grid);
    let w = &walls.0;
    let obstacles = &*obstacles;
    if !w.segments.is_empty() {
        return move_points(&mut bodies, grid, dt, obstacles, None, |p| {
            cross_segments(grid, w, p)
        });
    }
    let (min, max) = kept_box(grid, w);
    // The lanes move a point only where nothing but the advection and the volume apply: no
    // obstacle, and (checked per group) no side reached and no period crossed.
    let lanes = (kernels.avx2() && obstacles.is_empty()).then_some(KeptBox {
        min,
        max,
        periodic: grid.periodic,
        origin: grid.origin,
        size: grid.size(),
    });
    // Per axis: whether leaving through the low / high side retires the point.
    let open = [
        [w.left == Wall::Open, w.right == Wall::Open],
        [w.bottom == Wall::Open, w.top == Wall::Open],
    ];
    move_points(&mut bodies, grid, dt, obstacles, lanes, |p| {
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

/// The box a point stays in, strictly inside which the walls change nothing
/// ([`kept_box`]), and the grid's periods ([`GridGeometry::wrap`]); made for the lanes only
/// where `Kernels::avx2` is true.
#[derive(Clone, Copy)]
struct KeptBox {
    min: DVec2,
    max: DVec2,
    periodic: [bool; 2],
    origin: DVec2,
    size: DVec2,
}

/// Points per parallel task of the move.
const CHUNK: usize = 512;

/// Moves every live point of every body by `dt` times its advection velocity, updates its
/// volume, hands it to `walls` to place it (set `x`) against the sides, then stops it at the
/// obstacles; retired points stay parked. With `lanes`, four points at a time go through
/// [`avx2::move_four`] instead where all four have mass, a volume change below `1e-3` and a
/// new position strictly inside the box and within one period: the same operations, so the
/// same bits.
fn move_points(
    bodies: &mut Query<&mut Points>,
    grid: &GridGeometry,
    dt: f64,
    obstacles: &Obstacles,
    lanes: Option<KeptBox>,
    walls: impl Fn(&mut Moving) + Send + Sync,
) {
    let one = |x: &mut DVec2,
               v: &mut DVec2,
               vol: &mut f64,
               m: &mut f64,
               t: &mut Stress,
               adv: DVec2,
               l: &DMat2| {
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
    };
    for mut points in bodies.iter_mut() {
        let points = &mut *points;
        points
            .position
            .par_chunks_mut(CHUNK)
            .zip(points.velocity.par_chunks_mut(CHUNK))
            .zip(points.volume.par_chunks_mut(CHUNK))
            .zip(
                points
                    .mass
                    .par_chunks_mut(CHUNK)
                    .zip(points.stress.par_chunks_mut(CHUNK)),
            )
            .zip(
                points
                    .advection
                    .par_chunks(CHUNK)
                    .zip(points.velocity_gradient.par_chunks(CHUNK)),
            )
            .for_each(|((((x, v), vol), (m, t)), (adv, l))| {
                // Groups of four, the last one shorter; a group the lanes decline (or any
                // group without them) is moved point by point.
                let mut k = 0;
                while k < x.len() {
                    let group = k..(k + 4).min(x.len());
                    k = group.end;
                    #[cfg(target_arch = "x86_64")]
                    if let Some(kept) = lanes.filter(|_| group.len() == 4) {
                        // SAFETY: `lanes` is made only where `Kernels::avx2` is true, after
                        // the processor was found to have AVX2.
                        let moved = unsafe {
                            avx2::move_four(
                                dt,
                                kept,
                                four(&mut x[group.clone()]),
                                four(&mut vol[group.clone()]),
                                four(&m[group.clone()]),
                                four(&adv[group.clone()]),
                                four(&l[group.clone()]),
                            )
                        };
                        if moved {
                            continue;
                        }
                    }
                    for j in group {
                        one(
                            &mut x[j],
                            &mut v[j],
                            &mut vol[j],
                            &mut m[j],
                            &mut t[j],
                            adv[j],
                            &l[j],
                        );
                    }
                }
            });
    }
}

/// Four consecutive entries as an array (the lanes' unit).
#[cfg(target_arch = "x86_64")]
fn four<S: TryInto<T>, T>(slice: S) -> T {
    slice.try_into().ok().expect("four entries")
}

#[cfg(target_arch = "x86_64")]
mod avx2 {
    use super::*;
    use std::arch::x86_64::*;

    /// Moves four points (two per 256-bit register: `[x0, y0, x1, y1]`) and updates their
    /// volumes, if all four have mass, a volume increment `dt tr L` below `1e-3` in magnitude
    /// (the polynomial branch of [`exp_of_increment`]) and a new position strictly inside
    /// `kept` (where the walls' clamp is the identity and no velocity is stopped), on a
    /// periodic axis within the period that starts at the origin (where `GridGeometry::wrap`
    /// gives `origin + (x - origin)`, its remainder being the identity); returns whether it
    /// did. Every operation is the scalar path's, in its order.
    #[target_feature(enable = "avx2")]
    pub(super) fn move_four(
        dt: f64,
        kept: KeptBox,
        x: &mut [DVec2; 4],
        vol: &mut [f64; 4],
        m: &[f64; 4],
        adv: &[DVec2; 4],
        l: &[DMat2; 4],
    ) -> bool {
        let zero = _mm256_setzero_pd();
        let massless = _mm256_cmp_pd::<_CMP_EQ_OQ>(_mm256_setr_pd(m[0], m[1], m[2], m[3]), zero);
        if _mm256_movemask_pd(massless) != 0 {
            return false;
        }
        let pair = |a: DVec2, b: DVec2| _mm256_setr_pd(a.x, a.y, b.x, b.y);
        let step = _mm256_set1_pd(dt);
        let moved = [
            _mm256_add_pd(pair(x[0], x[1]), _mm256_mul_pd(step, pair(adv[0], adv[1]))),
            _mm256_add_pd(pair(x[2], x[3]), _mm256_mul_pd(step, pair(adv[2], adv[3]))),
        ];
        let (lo, hi) = (pair(kept.min, kept.min), pair(kept.max, kept.max));
        let (origin, size) = (pair(kept.origin, kept.origin), pair(kept.size, kept.size));
        let [px, py] = kept
            .periodic
            .map(|p| if p { f64::from_bits(u64::MAX) } else { 0.0 });
        let periodic = _mm256_setr_pd(px, py, px, py);
        // Each lane's place after the wrap, or `None` if a lane leaves the box or its period.
        let placed = |p: __m256d| {
            let d = _mm256_sub_pd(p, origin);
            let within_period = _mm256_and_pd(
                _mm256_cmp_pd::<_CMP_GE_OQ>(d, _mm256_setzero_pd()),
                _mm256_cmp_pd::<_CMP_LT_OQ>(d, size),
            );
            let inside = _mm256_and_pd(
                _mm256_cmp_pd::<_CMP_GT_OQ>(p, lo),
                _mm256_cmp_pd::<_CMP_LT_OQ>(p, hi),
            );
            let ok = _mm256_blendv_pd(inside, within_period, periodic);
            (_mm256_movemask_pd(ok) == 0b1111)
                .then(|| _mm256_blendv_pd(p, _mm256_add_pd(origin, d), periodic))
        };
        let (Some(first), Some(second)) = (placed(moved[0]), placed(moved[1])) else {
            return false;
        };
        let moved = [first, second];
        let trace = |k: usize| l[k].x_axis.x + l[k].y_axis.y;
        let z = _mm256_mul_pd(step, _mm256_setr_pd(trace(0), trace(1), trace(2), trace(3)));
        let small = _mm256_cmp_pd::<_CMP_LT_OQ>(
            _mm256_andnot_pd(_mm256_set1_pd(-0.0), z),
            _mm256_set1_pd(SHORT_EXP_BELOW),
        );
        if _mm256_movemask_pd(small) != 0b1111 {
            return false;
        }
        // `exp_of_increment`'s polynomial, term by term.
        let c = |v: f64| _mm256_set1_pd(v);
        let mut e = _mm256_add_pd(c(1.0 / 24.0), _mm256_mul_pd(z, c(1.0 / 120.0)));
        e = _mm256_add_pd(c(1.0 / 6.0), _mm256_mul_pd(z, e));
        e = _mm256_add_pd(c(0.5), _mm256_mul_pd(z, e));
        e = _mm256_add_pd(c(1.0), _mm256_mul_pd(z, e));
        e = _mm256_add_pd(c(1.0), _mm256_mul_pd(z, e));
        let v = _mm256_mul_pd(_mm256_setr_pd(vol[0], vol[1], vol[2], vol[3]), e);
        let mut out = [[0.0; 4]; 3];
        // SAFETY: each row of `out` holds four f64.
        unsafe {
            _mm256_storeu_pd(out[0].as_mut_ptr(), moved[0]);
            _mm256_storeu_pd(out[1].as_mut_ptr(), moved[1]);
            _mm256_storeu_pd(out[2].as_mut_ptr(), v);
        }
        for k in 0..4 {
            let row = &out[k / 2];
            x[k] = DVec2::new(row[2 * (k % 2)], row[2 * (k % 2) + 1]);
            vol[k] = out[2][k];
        }
        true
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

/// The magnitude below which [`exp_of_increment`] takes its polynomial (and the move's lanes
/// take a group of points).
const SHORT_EXP_BELOW: f64 = 1e-3;

/// `e^x` for the volume change of one step, which is small: below 1e-3 in magnitude the
/// Taylor polynomial to `x^5` (truncation under `x^6/720 < 2e-21`, beneath f64 round-off),
/// otherwise `exp`. The library call was 4% of a step.
#[inline]
fn exp_of_increment(x: f64) -> f64 {
    if x.abs() < SHORT_EXP_BELOW {
        1.0 + x * (1.0 + x * (0.5 + x * (1.0 / 6.0 + x * (1.0 / 24.0 + x * (1.0 / 120.0)))))
    } else {
        x.exp()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use bevy_ecs::system::RunSystemOnce;

    /// The move with whichever kernels this processor has gives the per-point move's state to
    /// the bit: points crossing a periodic seam (on either side, so the wrap moves them by a
    /// period), reaching and passing slip, no-slip and open walls, massless, with volume
    /// increments on both sides of the polynomial's range, on grids periodic along none, one
    /// or both axes and with an origin off zero (so that `origin + (x - origin)` is not `x`).
    #[test]
    fn the_four_point_move_is_the_per_point_move_to_the_bit() {
        let mut seed = 17u64;
        let mut next = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        for periodic in [[false, false], [true, false], [true, true]] {
            let grid = GridGeometry {
                origin: DVec2::new(-0.37, 0.113),
                cell_size: 0.05,
                cells: [12, 9],
                periodic,
            };
            let side = |a: usize, wall: Wall| if periodic[a] { Wall::Periodic } else { wall };
            let walls = Walls {
                left: side(0, Wall::Slip),
                right: side(0, Wall::Open),
                bottom: side(1, Wall::NoSlip),
                top: side(1, Wall::Free),
                segments: Vec::new(),
            };
            let (lo, size) = (grid.origin, grid.size());
            let mut points = Points::default();
            for k in 0..4001 {
                let u = DVec2::new(next(), next());
                // Most points well inside; some within a step of a side.
                let at = if k % 3 == 0 {
                    DVec2::new(u.x.round(), u.y.round())
                } else {
                    u
                };
                points.position.push(lo + at * size);
                points
                    .advection
                    .push(DVec2::new(next() - 0.5, next() - 0.5) * 40.0);
                points.velocity.push(DVec2::new(next() - 0.5, next() - 0.5));
                points
                    .mass
                    .push(if k % 97 == 5 { 0.0 } else { 1.0 + next() });
                points.volume.push(1e-4 * (1.0 + next()));
                points.stress.push(Stress::isotropic(-next()));
                let rate = if k % 41 == 7 { 30.0 } else { 0.3 } * (next() - 0.5);
                points.velocity_gradient.push(DMat2::from_cols(
                    DVec2::new(rate, next()),
                    DVec2::new(next(), rate * next()),
                ));
            }
            let moved = |kernels: Kernels| {
                let mut world = World::new();
                world.insert_resource(grid.clone());
                world.insert_resource(Clock {
                    dt: 1e-3,
                    ..Clock::start(1.0)
                });
                world.insert_resource(Boundaries(walls.clone()));
                world.insert_resource(Obstacles::default());
                world.insert_resource(kernels);
                let body = world.spawn(points.clone()).id();
                world.run_system_once(advect_points).unwrap();
                let p = world.entity(body).get::<Points>().unwrap().clone();
                format!("{:?}", (p.position, p.velocity, p.volume, p.mass, p.stress))
            };
            assert_eq!(
                moved(Kernels::widest()),
                moved(Kernels::SCALAR),
                "periodic {periodic:?}"
            );
        }
    }

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
