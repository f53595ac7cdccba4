//! The delta-correction of Baumgarten & Kamrin (2023, Int. J. Numer. Methods Eng., doi
//! 10.1002/nme.7217): after the move, points are shifted off grid nodes that their volumes
//! over-fill, positions only.
//!
//! Why: with the cell-averaged dilatation a cell's sub-cell velocity modes have no volumetric
//! stiffness, so in a long dense flow points drift together while each keeps its volume
//! `V0 det F`; the layer's occupied area shrinks at constant summed volume and nothing pushes
//! back (a 0.1 m chute at 22.5 degrees: top 0.068 m, 15 points in one cell at 20 s;
//! docs/numerics.md, "Points that keep their spacing"). The correction measures crowding on
//! the nodes and moves the crowded points apart:
//!
//! 1. `Vpts_i = sum_p V_p S_i(x_p)` with linear hats, over the points of every body (a node
//!    another body fills is full for this one too), on the step's grid or on one `refinement`
//!    times finer (which sees clumps smaller than a step cell);
//! 2. `Vref_i`, the integral of `S_i` over the domain, the region material may fill: `h^2`
//!    inside, half of it on a wall, a quarter in a corner, nothing special across a periodic
//!    side; without what the obstacles cover (sampled, once a run, for the nodes near one);
//! 3. `H_i = max(0, Vpts_i - Vref_i)`, over-fill only (beyond a round-off tolerance): a free
//!    surface or a void pulls nothing in, and a lattice at rest is not touched. That form
//!    only ever pushes points apart, so position noise ratchets a layer open; the two-sided
//!    form (`pull_above < 1`) also takes `H_i = Vpts_i - Vref_i < 0` at nodes at least
//!    `pull_above` full and more than 1% under-filled (inside the material, where a gap
//!    between points that their volumes do not account for is the same error as a crowd);
//! 4. `g_p = V_p sum_i H_i grad S_i(x_p)`, the gradient of `E = 1/2 sum_i H_i^2` in `x_p`;
//! 5. `delta_p = -alpha beta g_p`, `beta = sum_p |g_p|^2 / sum_i d_i^2` with
//!    `d_i = sum_p V_p grad S_i(x_p) . g_p` (the Gauss-Newton step on `E` along `-g`), each
//!    shift at most `max_shift` step cells long;
//! 6. `x_p += delta_p`, kept inside the walls and out of the obstacles as the move keeps
//!    points. Velocities, affine fields, volumes, stresses and material history are
//!    untouched: mass and momentum are exactly conserved.
//!
//! Only the points of granular bodies move (`MaterialSpec::granular`): their stress
//! keeps no memory of where the points sit, while shifting an elastic body's points would
//! deform it without a stress. The sums run serially in point order, so the result is the same
//! at every thread count; the per-point passes run in parallel.

use bevy_ecs::prelude::*;
use glam::DVec2;
use rayon::prelude::*;
use serde::Deserialize;

use super::scatter_gather::kept_box;
use crate::body::{Body, Points};
use crate::grid::GridGeometry;
use crate::obstacle::Obstacles;
use crate::resources::Boundaries;

/// Over-fill below this fraction of a node's reference volume is round-off, not crowding.
const ROUND_OFF: f64 = 1e-9;

/// With the two-sided form, under-fill within this fraction of a node's reference volume is
/// left alone: it is the elastic compression of a dense material (`p / K`, 1.5e-4 at the
/// bottom of a 1 m PS-1 bed), which the points' volumes carry and their spacing need not.
const SLACK: f64 = 0.01;

/// The scene's `spacing` setting: `Off` (the default) or `DeltaCorrection(..)`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Deserialize)]
#[serde(try_from = "SpacingParams")]
pub enum Spacing {
    /// Points keep the positions the move gives them.
    #[default]
    Off,
    /// Baumgarten & Kamrin's delta-correction after every move (module docs).
    DeltaCorrection(DeltaCorrection),
}

/// The constants of the delta-correction.
#[derive(Clone, Copy, Debug, PartialEq, Resource)]
pub struct DeltaCorrection {
    /// Fraction of the Gauss-Newton step taken, in (0, 1].
    pub alpha: f64,
    /// Longest shift of one point in one step, in cells, in (0, 0.5].
    pub max_shift: f64,
    /// The correction grid's cells per step cell along each axis: 1 (the paper's, the step's
    /// own grid) or more (finer; 2 sees clumps smaller than a step cell).
    pub refinement: usize,
    /// From which fill (a fraction of the reference volume) an under-filled node counts as
    /// inside the material and pulls points in, as an over-filled one pushes them out: in
    /// (0, 1]; 1 is the paper's one-sided form (no node pulls). A node at a free surface is
    /// about half full, so a value above 1/2 leaves surfaces, voids and loose material alone.
    pub pull_above: f64,
}

impl Default for DeltaCorrection {
    fn default() -> Self {
        DeltaCorrection {
            alpha: 1.0,
            max_shift: 0.1,
            refinement: 1,
            pull_above: 1.0,
        }
    }
}

/// `spacing` as written: the constants optional.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
enum SpacingParams {
    Off,
    DeltaCorrection {
        alpha: Option<f64>,
        max_shift: Option<f64>,
        refinement: Option<usize>,
        pull_above: Option<f64>,
    },
}

impl TryFrom<SpacingParams> for Spacing {
    type Error = String;
    fn try_from(p: SpacingParams) -> Result<Self, String> {
        let SpacingParams::DeltaCorrection {
            alpha,
            max_shift,
            refinement,
            pull_above,
        } = p
        else {
            return Ok(Spacing::Off);
        };
        let d = DeltaCorrection::default();
        let c = DeltaCorrection {
            alpha: alpha.unwrap_or(d.alpha),
            max_shift: max_shift.unwrap_or(d.max_shift),
            refinement: refinement.unwrap_or(d.refinement),
            pull_above: pull_above.unwrap_or(d.pull_above),
        };
        if !(c.alpha > 0.0 && c.alpha <= 1.0) {
            return Err(format!(
                "DeltaCorrection: alpha (the fraction of the Gauss-Newton step taken) must lie in (0, 1], got {}",
                c.alpha
            ));
        }
        if !(c.max_shift > 0.0 && c.max_shift <= 0.5) {
            return Err(format!(
                "DeltaCorrection: max_shift (the longest shift in one step, in cells) must lie in (0, 0.5], got {}",
                c.max_shift
            ));
        }
        if !(1..=4).contains(&c.refinement) {
            return Err(format!(
                "DeltaCorrection: refinement (the correction grid's cells per step cell) must be 1, 2, 3 or 4, got {}",
                c.refinement
            ));
        }
        if !(c.pull_above > 0.0 && c.pull_above <= 1.0) {
            return Err(format!(
                "DeltaCorrection: pull_above (the fill from which an under-filled node pulls points in) must lie in (0, 1], got {}",
                c.pull_above
            ));
        }
        Ok(Spacing::DeltaCorrection(c))
    }
}

/// Where a point sits on the correction grid: its cell and its offsets in it (cells), found
/// once a step; 24 bytes, from which [`corners`] and [`gradients`] rebuild its four nodes,
/// weights and gradients.
#[derive(Clone, Copy, Debug, Default)]
struct Place {
    /// Column and row of the cell; `u32::MAX` for a point outside the grid (past a `Free`
    /// side, about to stop the run).
    cell: [u32; 2],
    offset: [f64; 2],
}

impl Place {
    const OUTSIDE: Place = Place {
        cell: [u32::MAX; 2],
        offset: [0.0; 2],
    };
}

/// Bytes per point the correction keeps (its place and its gradient), for memory estimates.
pub const BYTES_PER_POINT: usize = std::mem::size_of::<Place>() + std::mem::size_of::<DVec2>();
/// Bytes per correction-grid node (its fill and its slope).
pub const BYTES_PER_NODE: usize = 16;

/// The correction's arrays, kept between steps so that a step allocates nothing.
#[derive(Resource, Default)]
pub struct SpacingScratch {
    /// `Vpts_i`, then `H_i`.
    fill: Vec<f64>,
    /// `d_i`.
    slope: Vec<f64>,
    /// The bodies in scene order (`Body::index`), so that the sums run in a fixed order.
    order: Vec<(usize, Entity)>,
    /// Per body (in `order`), per point: its place, found once a step.
    places: Vec<Vec<Place>>,
    /// Per body, per point: `g_p` (empty for a body whose points do not move).
    gradient: Vec<Vec<DVec2>>,
    /// `Vref_i` of every node (`reference_volumes`), found at the first correction:
    /// obstacles and grid are fixed for the run.
    reference: Vec<f64>,
}

/// The place of a point at `x` on `grid`.
fn place(grid: &GridGeometry, x: DVec2) -> Place {
    let rel = (x - grid.origin) / grid.cell_size;
    let inside = |a: usize| rel[a] >= 0.0 && rel[a] <= grid.cells[a] as f64;
    if !(inside(0) && inside(1)) {
        return Place::OUTSIDE;
    }
    let [i, j] = grid.cell_at(x, 1.0 / grid.cell_size);
    Place {
        cell: [i as u32, j as u32],
        offset: [rel.x - i as f64, rel.y - j as f64],
    }
}

/// A point's four linear-hat nodes (flat indices) and weights, or `None` for a point outside
/// the grid. The fill needs no more; [`gradients`] gives the slopes, from the place's
/// offsets, where they are needed.
#[inline]
fn corners(grid: &GridGeometry, place: &Place) -> Option<([usize; 4], [f64; 4])> {
    if place.cell[0] == u32::MAX {
        return None;
    }
    let [i, j] = place.cell.map(|c| c as usize);
    let [fx, fy] = place.offset;
    let (nx, ny) = (grid.nodes_along(0), grid.nodes_along(1));
    let (i1, j1) = ((i + 1) % nx, (j + 1) % ny);
    let node = |a: usize, b: usize| grid.index(a, b);
    Some((
        [node(i, j), node(i1, j), node(i, j1), node(i1, j1)],
        [
            (1.0 - fx) * (1.0 - fy),
            fx * (1.0 - fy),
            (1.0 - fx) * fy,
            fx * fy,
        ],
    ))
}

/// The gradients of the four hats of [`corners`] at offsets `[fx, fy]` in a cell.
#[inline]
fn gradients(grid: &GridGeometry, [fx, fy]: [f64; 2]) -> [DVec2; 4] {
    let h = grid.cell_size;
    [
        DVec2::new(-(1.0 - fy), -(1.0 - fx)) / h,
        DVec2::new(1.0 - fy, -fx) / h,
        DVec2::new(-fy, 1.0 - fx) / h,
        DVec2::new(fy, fx) / h,
    ]
}

/// `Vref_i` of node `(i, j)`: the integral of its hat over the domain.
fn reference_volume(grid: &GridGeometry, i: usize, j: usize) -> f64 {
    let share = |k: usize, a: usize| {
        if !grid.periodic[a] && (k == 0 || k == grid.cells[a]) {
            0.5
        } else {
            1.0
        }
    };
    grid.cell_size * grid.cell_size * share(i, 0) * share(j, 1)
}

/// Midpoints per cell and axis of the sampled reference volumes: the midpoint rule is exact
/// for a hat on each cell, so only the obstacles' edges are approximated (to about
/// `h / SAMPLES`).
const SAMPLES: usize = 32;

/// `Vref_i` of every node of `grid`, into `out`: [`reference_volume`], except at the nodes
/// whose hat reaches an obstacle's bounding box, where the hat is integrated over the domain
/// outside the obstacles by sampling (so a node half inside an obstacle wants half the volume,
/// one deep inside none).
fn reference_volumes(grid: &GridGeometry, obstacles: &Obstacles, out: &mut Vec<f64>) {
    let nx = grid.nodes_along(0);
    out.clear();
    out.extend((0..grid.node_count()).map(|k| reference_volume(grid, k % nx, k / nx)));
    let h = grid.cell_size;
    let (lo, hi) = (grid.origin, grid.max());
    let step = 1.0 / SAMPLES as f64;
    let weight = (h * step) * (h * step);
    for (min, max) in obstacles.bounds() {
        let range = |a: usize| {
            let first = ((min[a] - grid.origin[a]) / h).floor() - 1.0;
            let last = ((max[a] - grid.origin[a]) / h).ceil() + 1.0;
            let end = grid.nodes_along(a) as f64 - 1.0;
            first.clamp(0.0, end) as usize..=last.clamp(0.0, end) as usize
        };
        for j in range(1) {
            for i in range(0) {
                let node = grid.node_position(i, j);
                let mut sum = 0.0;
                for b in 0..2 * SAMPLES {
                    let v = (b as f64 + 0.5) * step - 1.0;
                    for a in 0..2 * SAMPLES {
                        let u = (a as f64 + 0.5) * step - 1.0;
                        let x = node + h * DVec2::new(u, v);
                        let outside =
                            |a: usize| !grid.periodic[a] && (x[a] < lo[a] || x[a] > hi[a]);
                        if outside(0) || outside(1) || obstacles.contains(grid.wrap(x)) {
                            continue;
                        }
                        sum += (1.0 - u.abs()) * (1.0 - v.abs());
                    }
                }
                out[grid.index(i, j)] = sum * weight;
            }
        }
    }
}

/// The delta-correction, once, after the move (before the density the constitutive update
/// reads). Added to the step only when the scene's `spacing` is a `DeltaCorrection`.
pub fn correct_spacing(
    grid: Res<GridGeometry>,
    walls: Res<Boundaries>,
    obstacles: Res<Obstacles>,
    constants: Res<DeltaCorrection>,
    mut scratch: ResMut<SpacingScratch>,
    mut bodies: Query<(Entity, &Body, &mut Points)>,
) {
    let step_grid = &*grid;
    let r = constants.refinement;
    let grid = &GridGeometry {
        origin: step_grid.origin,
        cell_size: step_grid.cell_size / r as f64,
        cells: step_grid.cells.map(|c| c * r),
        periodic: step_grid.periodic,
    };
    let SpacingScratch {
        fill,
        slope,
        order,
        places,
        gradient,
        reference,
    } = &mut *scratch;
    if reference.len() != grid.node_count() {
        reference_volumes(grid, &obstacles, reference);
    }
    order.clear();
    order.extend(bodies.iter().map(|(e, b, _)| (b.index, e)));
    order.sort_unstable();
    places.resize_with(order.len(), Vec::new);
    gradient.resize_with(order.len(), Vec::new);
    // 1. Each point's place (in parallel), then Vpts over every body, serially in body and
    //    point order (deterministic sums).
    let nodes = grid.node_count();
    fill.clear();
    fill.resize(nodes, 0.0);
    for (&(_, entity), places_of) in order.iter().zip(places.iter_mut()) {
        let (_, _, points) = bodies.get(entity).expect("a body just listed");
        points
            .position
            .par_iter()
            .map(|&x| place(grid, x))
            .collect_into_vec(places_of);
        for (at, &v) in places_of.iter().zip(&points.volume) {
            if let Some((n, w)) = corners(grid, at) {
                for k in 0..4 {
                    fill[n[k]] += v * w[k];
                }
            }
        }
    }
    // 2-3. H_i = Vpts_i - Vref_i where over-filled beyond round-off, or (two-sided)
    // under-filled beyond the slack but at least `pull_above` full; 0 elsewhere.
    let mut active = false;
    for (node, &reference) in fill.iter_mut().zip(&*reference) {
        let over = *node - reference;
        let pulls = *node >= constants.pull_above * reference && over < -SLACK * reference;
        *node = if over > ROUND_OFF * reference || pulls {
            active = true;
            over
        } else {
            0.0
        };
    }
    if !active {
        return;
    }
    // 4. g_p for the points of the corrected bodies, in parallel (zero for a point none of
    //    whose nodes is over- or under-filled).
    let over = &*fill;
    for ((&(_, entity), places_of), g) in order.iter().zip(&*places).zip(gradient.iter_mut()) {
        g.clear();
        let (_, body, points) = bodies.get(entity).expect("a body just listed");
        if !body.granular {
            continue;
        }
        places_of
            .par_iter()
            .zip(points.volume.par_iter())
            .map(|(at, &v)| {
                let Some((n, _)) = corners(grid, at) else {
                    return DVec2::ZERO;
                };
                if n.iter().all(|&i| over[i] == 0.0) {
                    return DVec2::ZERO;
                }
                let grads = gradients(grid, at.offset);
                v * (0..4).fold(DVec2::ZERO, |s, k| s + over[n[k]] * grads[k])
            })
            .collect_into_vec(g);
    }
    // 5. beta = sum |g|^2 / sum_i d_i^2, serially over the points that have a gradient.
    slope.clear();
    slope.resize(nodes, 0.0);
    let mut squared = 0.0;
    for ((&(_, entity), places_of), g) in order.iter().zip(&*places).zip(&*gradient) {
        let (_, _, points) = bodies.get(entity).expect("a body just listed");
        for ((at, &v), &gp) in places_of.iter().zip(&points.volume).zip(g) {
            if gp == DVec2::ZERO {
                continue;
            }
            squared += gp.length_squared();
            if let Some((n, _)) = corners(grid, at) {
                for (i, grad) in n.into_iter().zip(gradients(grid, at.offset)) {
                    slope[i] += v * grad.dot(gp);
                }
            }
        }
    }
    let curvature: f64 = slope.iter().map(|d| d * d).sum();
    if !(squared > 0.0 && curvature > 0.0) {
        return;
    }
    let beta = constants.alpha * squared / curvature;
    let longest = constants.max_shift * step_grid.cell_size;
    let (min, max) = kept_box(grid, &walls.0);
    // 6. The shifts, clamped, kept inside the walls and out of the obstacles.
    for (&(_, entity), g) in order.iter().zip(&*gradient) {
        if g.is_empty() {
            continue;
        }
        let (_, _, mut points) = bodies.get_mut(entity).expect("a body just listed");
        points
            .position
            .par_iter_mut()
            .zip(g.par_iter())
            .for_each(|(x, &gp)| {
                if gp == DVec2::ZERO {
                    return;
                }
                let shift = -beta * gp;
                let length = shift.length();
                let shift = if length > longest {
                    shift * (longest / length)
                } else {
                    shift
                };
                let to = grid.wrap(*x + shift).clamp(min, max);
                // Positions only: the velocity the stop would change is a throwaway.
                *x = obstacles.stop(*x, to, &mut DVec2::new(0.0, 0.0));
            });
    }
}

#[cfg(test)]
mod tests {
    use bevy_ecs::system::RunSystemOnce;

    use super::*;
    use crate::resources::{Wall, Walls};

    const H: f64 = 0.01;

    fn body(index: usize, granular: bool) -> Body {
        Body {
            name: format!("b{index}"),
            index,
            tracked: false,
            material: "test",
            wave_speed: 1.0,
            inertial_scale: None,
            granular,
        }
    }

    /// 2 x 2 points per cell over cells `[x0, x1) x [y0, y1)`, each of volume `h^2 / 4`,
    /// with velocities that a correction must leave alone.
    fn lattice(x: [usize; 2], y: [usize; 2]) -> Points {
        let mut p = Points::default();
        for j in 2 * y[0]..2 * y[1] {
            for i in 2 * x[0]..2 * x[1] {
                let at = DVec2::new(i as f64 + 0.5, j as f64 + 0.5) * (0.5 * H);
                p.position.push(at);
                p.volume.push(0.25 * H * H);
                p.mass.push(1.0);
                p.velocity.push(DVec2::new(at.y, -at.x));
            }
        }
        p
    }

    fn world(cells: [usize; 2], walls: Walls, bodies: Vec<(Body, Points)>) -> World {
        let periodic = [walls.left == Wall::Periodic, walls.bottom == Wall::Periodic];
        let mut world = World::new();
        world.insert_resource(GridGeometry {
            origin: DVec2::ZERO,
            cell_size: H,
            cells,
            periodic,
        });
        world.insert_resource(Boundaries(walls));
        world.insert_resource(Obstacles::default());
        world.insert_resource(DeltaCorrection::default());
        world.insert_resource(SpacingScratch::default());
        for b in bodies {
            world.spawn(b);
        }
        world
    }

    fn walls(side: Wall, floor: Wall) -> Walls {
        Walls {
            left: side,
            right: side,
            bottom: floor,
            top: Wall::Free,
            segments: Vec::new(),
        }
    }

    fn positions(world: &mut World) -> Vec<Vec<DVec2>> {
        let mut q = world.query::<(&Body, &Points)>();
        let mut all: Vec<_> = q.iter(world).map(|(b, p)| (b.index, p.clone())).collect();
        all.sort_by_key(|(i, _)| *i);
        all.into_iter().map(|(_, p)| p.position).collect()
    }

    fn correct(world: &mut World) {
        world.run_system_once(correct_spacing).unwrap();
    }

    /// A body that fills its region exactly over-fills no node, on walls of every kind and
    /// across periodic sides: no point moves, to the bit.
    #[test]
    fn a_full_lattice_is_not_moved() {
        for (side, floor) in [
            (Wall::Slip, Wall::NoSlip),
            (Wall::Periodic, Wall::NoSlip),
            (Wall::Open, Wall::Slip),
        ] {
            let mut w = world(
                [8, 6],
                walls(side, floor),
                vec![(body(0, true), lattice([0, 8], [0, 4]))],
            );
            let before = positions(&mut w);
            correct(&mut w);
            assert_eq!(positions(&mut w), before, "{side:?} sides, {floor:?} floor");
        }
    }

    /// A layer whose points sit further apart than their volumes say (every node 90% full):
    /// the one-sided form leaves it, the two-sided form pulls it together (its top comes
    /// down), and neither touches a layer that is full.
    #[test]
    fn the_two_sided_form_closes_a_gap_and_only_it_does() {
        let top = |pull_above: f64, fill: f64| {
            let mut p = lattice([0, 8], [0, 4]);
            for v in &mut p.volume {
                *v *= fill;
            }
            let mut w = world(
                [8, 6],
                walls(Wall::Periodic, Wall::NoSlip),
                vec![(body(0, true), p)],
            );
            w.insert_resource(DeltaCorrection {
                pull_above,
                ..DeltaCorrection::default()
            });
            let before = positions(&mut w).remove(0);
            correct(&mut w);
            let after = positions(&mut w).remove(0);
            let highest = |x: &[DVec2]| x.iter().map(|x| x.y).fold(f64::MIN, f64::max);
            (highest(&after) - highest(&before)) / H
        };
        assert_eq!(top(1.0, 0.9), 0.0);
        assert_eq!(top(0.75, 1.0), 0.0);
        assert_eq!(
            top(0.75, 0.995),
            0.0,
            "an under-fill within the slack pulls"
        );
        let pulled = top(0.75, 0.9);
        assert!(pulled < -1e-3, "the top moved by {pulled} cells");
    }

    /// A layer resting on an obstacle whose top lies half way up a cell (its own top on a cell
    /// boundary) fills the nodes at
    /// the obstacle's surface only partly, as much as the obstacle leaves them: the two-sided
    /// form does not pull it (on the obstacle) and the one-sided form does not push it. Before
    /// the obstacles' inside was taken out of the reference volume, the two-sided form pulled
    /// the layer down onto the obstacle (the node above the surface, 87.5% full, counted as
    /// under-filled).
    #[test]
    fn a_layer_on_an_obstacle_is_not_moved() {
        use crate::geometry::builtin::Rectangle;
        use crate::obstacle::ObstacleSpec;
        use crate::registry::Named;

        for pull_above in [1.0, 0.75] {
            // Rows of points from 2.5 to 5 cells up: the top on a cell boundary.
            let mut layer = lattice([0, 8], [3, 5]);
            for k in 0..16 {
                layer
                    .position
                    .push(DVec2::new(k as f64 + 0.5, 5.5) * (0.5 * H));
                layer.volume.push(0.25 * H * H);
                layer.mass.push(1.0);
                layer.velocity.push(DVec2::ZERO);
            }
            let mut w = world(
                [8, 6],
                walls(Wall::Periodic, Wall::NoSlip),
                vec![(body(0, true), layer)],
            );
            let grid = w.resource::<GridGeometry>().clone();
            let spec = ObstacleSpec {
                shape: Named(Box::new(Rectangle {
                    min: DVec2::new(0.0, 0.0),
                    max: DVec2::new(8.0 * H, 2.5 * H),
                })),
                wall: Wall::NoSlip,
            };
            w.insert_resource(Obstacles::new(&[spec], &grid));
            w.insert_resource(DeltaCorrection {
                pull_above,
                ..DeltaCorrection::default()
            });
            let before = positions(&mut w);
            correct(&mut w);
            assert_eq!(positions(&mut w), before, "pull_above {pull_above}");
        }
    }

    /// Two bodies that meet fill the nodes they share together, so neither is pushed.
    #[test]
    fn bodies_that_meet_are_not_pushed_apart() {
        let mut w = world(
            [8, 6],
            walls(Wall::Slip, Wall::NoSlip),
            vec![
                (body(0, true), lattice([0, 4], [0, 4])),
                (body(1, false), lattice([4, 8], [0, 4])),
            ],
        );
        let before = positions(&mut w);
        correct(&mut w);
        assert_eq!(positions(&mut w), before);
    }

    /// The clump: a lattice whose middle points are squeezed towards the centre of the body.
    fn squeezed(x: [usize; 2], y: [usize; 2], centre: DVec2) -> Points {
        let mut p = lattice(x, y);
        for at in &mut p.position {
            if (*at - centre).length() < 1.5 * H {
                *at = centre + 0.6 * (*at - centre);
            }
        }
        p
    }

    fn over_fill(world: &mut World) -> f64 {
        let grid = world.resource::<GridGeometry>().clone();
        let mut fill = vec![0.0; grid.node_count()];
        let mut q = world.query::<&Points>();
        for p in q.iter(world) {
            for (&x, &v) in p.position.iter().zip(&p.volume) {
                if let Some((n, w)) = corners(&grid, &place(&grid, x)) {
                    for (i, w) in n.into_iter().zip(w) {
                        fill[i] += v * w;
                    }
                }
            }
        }
        let nx = grid.nodes_along(0);
        fill.iter()
            .enumerate()
            .map(|(k, f)| {
                (f - reference_volume(&grid, k % nx, k / nx))
                    .max(0.0)
                    .powi(2)
            })
            .sum::<f64>()
            / 2.0
    }

    /// A clump is spread: the over-fill energy falls, every shift is at most `max_shift`
    /// cells, velocities, volumes and masses are untouched (momentum exact), and an elastic
    /// body's points are never moved.
    #[test]
    fn a_clump_spreads_and_nothing_but_positions_changes() {
        let centre = DVec2::new(3.0, 2.0) * H;
        let mut w = world(
            [10, 6],
            walls(Wall::Slip, Wall::NoSlip),
            vec![
                (body(0, true), squeezed([0, 6], [0, 4], centre)),
                (body(1, false), lattice([6, 10], [0, 4])),
            ],
        );
        let mut q = w.query::<(&Body, &Points)>();
        let before: Vec<(usize, Points)> = q.iter(&w).map(|(b, p)| (b.index, p.clone())).collect();
        let energy = over_fill(&mut w);
        correct(&mut w);
        let after_energy = over_fill(&mut w);
        assert!(
            after_energy < 0.5 * energy,
            "over-fill energy {energy:e} -> {after_energy:e}"
        );
        let mut q = w.query::<(&Body, &Points)>();
        for (b, p) in q.iter(&w) {
            let old = &before.iter().find(|(i, _)| *i == b.index).unwrap().1;
            assert_eq!(p.velocity, old.velocity);
            assert_eq!(p.volume, old.volume);
            assert_eq!(p.mass, old.mass);
            let moved = p
                .position
                .iter()
                .zip(&old.position)
                .map(|(a, b)| (*a - *b).length())
                .fold(0.0, f64::max);
            if b.granular {
                assert!(
                    moved > 0.0 && moved <= 0.1 * H * (1.0 + 1e-12),
                    "moved {moved:e}"
                );
            } else {
                assert_eq!(moved, 0.0, "the elastic body moved");
            }
        }
    }

    /// Across a periodic side the correction sees the same clump as inside: a clump moved
    /// by whole cells across the seam gets the same shifts.
    #[test]
    fn a_clump_across_a_periodic_side_is_spread_as_inside() {
        let shifts = |offset: usize| {
            let centre = DVec2::new(4.0, 2.0) * H;
            let mut p = squeezed([0, 8], [0, 4], centre);
            let size = 8.0 * H;
            for x in &mut p.position {
                x.x = (x.x + offset as f64 * H).rem_euclid(size);
            }
            let start = p.position.clone();
            let mut w = world(
                [8, 6],
                walls(Wall::Periodic, Wall::NoSlip),
                vec![(body(0, true), p)],
            );
            correct(&mut w);
            let end = positions(&mut w).remove(0);
            start
                .iter()
                .zip(&end)
                .map(|(a, b)| {
                    let mut d = *b - *a;
                    d.x -= size * (d.x / size).round();
                    d
                })
                .collect::<Vec<DVec2>>()
        };
        let inside = shifts(0);
        let across = shifts(4);
        for (a, b) in inside.iter().zip(&across) {
            assert!((*a - *b).length() < 1e-12 * H, "{a} against {b}");
        }
        assert!(inside.iter().any(|d| d.length() > 1e-4 * H));
    }
}
