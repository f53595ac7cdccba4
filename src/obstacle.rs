//! Fixed boundaries of any shape inside the domain: a hopper's inclined walls, a ledge, a
//! post. A scene lists them as `obstacles: [(shape: Polygon(..), wall: Frictional(friction:
//! 0.3))]`, with any registered [`Shape`] and a `Slip`, `NoSlip` or `Frictional` surface.
//!
//! Why at the grid nodes: the box's sides act on their nodes (`step::grid_update`), and so
//! does this. An obstacle holds the nodes that lie inside it, each with the outward normal
//! `n` of the obstacle's boundary nearest to it ([`Shape::outward_normal`]: at a convex corner
//! the bisector of the two edges' normals for a node on it, the nearer edge's normal
//! elsewhere). A held node's velocity `v` obeys the surface law ([`surface_velocity`]): where
//! `v . n < 0` (moving into the obstacle) the normal part is removed and, for `Frictional`,
//! the tangential part is reduced by `friction |v . n|` (Coulomb, as the contact between
//! bodies; it stops at zero and never reverses), for `NoSlip` set to zero; where
//! `v . n >= 0` the node is left alone, so material may leave the surface (fall off a
//! ledge's underside) as it may leave another body. `step::grid_update` applies it with the
//! box's walls, setting force and acceleration to the change it imposes over the step.
//!
//! The grid alone stops material a fraction of a cell into the obstacle at most; a point
//! the move would still take inside is stopped where its path enters ([`Obstacles::stop`],
//! found by bisection on `contains`, so for any shape) and loses its velocity into the
//! surface, as a point at a box wall does. A point never ends a step inside an obstacle.
//! An obstacle must hold at least one grid node (thinner than a cell, it would let the
//! grid's velocity through while its points stop, which the scene check refuses).

use bevy_ecs::prelude::*;
use glam::DVec2;
use serde::Deserialize;

use crate::geometry::Shape;
use crate::grid::GridGeometry;
use crate::registry::Named;
use crate::resources::Wall;

/// One obstacle as the scene writes it.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObstacleSpec {
    /// Any registered shape: `Polygon(vertices: [..])`, `Rectangle(..)`, `Disc(..)`, a
    /// plugin's.
    pub shape: Named<dyn Shape>,
    /// Its surface: `Slip`, `NoSlip` or `Frictional(friction: mu)`.
    pub wall: Wall,
}

impl ObstacleSpec {
    /// Why this surface cannot be an obstacle's, if it cannot.
    pub fn check(&self) -> Result<(), String> {
        match self.wall {
            Wall::Slip | Wall::NoSlip | Wall::Frictional { .. } => Ok(()),
            other => Err(format!(
                "an obstacle's wall must be Slip, NoSlip or Frictional(friction: mu), got {other:?}"
            )),
        }
    }
}

/// The velocity a surface with outward normal `n` leaves of `v` (module docs): unchanged
/// where `v` leaves the surface or runs along it, otherwise without its normal part and, by
/// the wall, with its tangential part kept (`Slip`), reduced by Coulomb friction
/// (`Frictional`) or removed (`NoSlip`).
pub fn surface_velocity(v: DVec2, n: DVec2, wall: Wall) -> DVec2 {
    let vn = v.dot(n);
    if vn >= 0.0 {
        return v;
    }
    let tangential = v - vn * n;
    match wall {
        Wall::NoSlip => DVec2::ZERO,
        Wall::Frictional { friction } => {
            let speed = tangential.length();
            if speed <= friction * -vn {
                DVec2::ZERO
            } else {
                tangential * (1.0 - friction * -vn / speed)
            }
        }
        _ => tangential,
    }
}

/// A grid node an obstacle holds: its index, the outward normal there and the surface law.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HeldNode {
    pub node: usize,
    pub normal: DVec2,
    pub wall: Wall,
}

/// Whether `shape` contains `x`, its bounding box tested first (a cheap rejection).
fn inside(shape: &dyn Shape, x: DVec2) -> bool {
    let (lo, hi) = shape.bounds();
    !(x.cmplt(lo).any() || x.cmpgt(hi).any()) && shape.contains(x)
}

/// The scene's obstacles and the grid nodes they hold (a resource; empty without obstacles).
#[derive(Resource, Default)]
pub struct Obstacles {
    shapes: Vec<(Box<dyn Shape>, Wall)>,
    nodes: Vec<HeldNode>,
    /// The grid's cell size, the reach of the normals' search.
    reach: f64,
}

impl Obstacles {
    /// The obstacles on this grid: every node inside one is held by it.
    pub fn new(specs: &[ObstacleSpec], grid: &GridGeometry) -> Obstacles {
        let mut nodes = Vec::new();
        for spec in specs {
            for (node, at) in Self::nodes_inside(&*spec.shape.0, grid) {
                nodes.push(HeldNode {
                    node,
                    normal: spec.shape.0.outward_normal(at, grid.cell_size),
                    wall: spec.wall,
                });
            }
        }
        Obstacles {
            shapes: specs.iter().map(|s| (s.shape.0.clone(), s.wall)).collect(),
            nodes,
            reach: grid.cell_size,
        }
    }

    /// The grid nodes (index, place) inside `shape`.
    pub fn nodes_inside(shape: &dyn Shape, grid: &GridGeometry) -> Vec<(usize, DVec2)> {
        let (lo, hi) = shape.bounds();
        let h = grid.cell_size;
        let range = |a: usize| {
            let last = grid.nodes_along(a) - 1;
            let first = ((lo[a] - grid.origin[a]) / h).floor().max(0.0) as usize;
            let end = (((hi[a] - grid.origin[a]) / h).ceil().max(0.0) as usize).min(last);
            first..=end
        };
        let mut inside = Vec::new();
        for j in range(1) {
            for i in range(0) {
                let at = grid.node_position(i, j);
                if shape.contains(at) {
                    inside.push((grid.index(i, j), at));
                }
            }
        }
        inside
    }

    /// Whether the scene has any obstacle.
    pub fn is_empty(&self) -> bool {
        self.shapes.is_empty()
    }

    /// Whether `x` lies inside an obstacle.
    pub fn contains(&self, x: DVec2) -> bool {
        self.shapes.iter().any(|(shape, _)| inside(&**shape, x))
    }

    /// Each obstacle's bounding box (lower and upper corners).
    pub fn bounds(&self) -> impl Iterator<Item = (DVec2, DVec2)> + '_ {
        self.shapes.iter().map(|(shape, _)| shape.bounds())
    }

    /// The held nodes: index, outward normal, surface law (`step::grid_update` applies
    /// them with the box's walls).
    pub fn held(&self) -> impl Iterator<Item = (usize, DVec2, Wall)> + '_ {
        self.nodes.iter().map(|h| (h.node, h.normal, h.wall))
    }

    /// The held nodes as a slice (a grid field's conditions, `grid_field::FieldWalls`).
    pub fn held_nodes(&self) -> &[HeldNode] {
        &self.nodes
    }

    /// Where a point moving from `from` to `to` ends, and its velocity `v`: `to` when no
    /// obstacle contains it; otherwise the place where its path enters the obstacle (found
    /// by bisection to 1e-9 cells), with the part of `v` into the surface removed. A point
    /// already inside at `from` (put there by nothing a valid scene does, but a shape's
    /// `contains` may disagree with itself at round-off) is moved out along the normal.
    pub fn stop(&self, from: DVec2, to: DVec2, v: &mut DVec2) -> DVec2 {
        let mut at = to;
        for (shape, _) in &self.shapes {
            if !inside(&**shape, at) {
                continue;
            }
            let outside = if shape.contains(from) {
                self.step_out(&**shape, at)
            } else {
                from
            };
            at = self.bisect(&**shape, outside, at);
            let n = shape.outward_normal(at, self.reach);
            let vn = v.dot(n);
            if vn < 0.0 {
                *v -= vn * n;
            }
        }
        at
    }

    /// A place outside `shape` along the outward normal from `inside` (steps of an eighth of
    /// a cell, 64 at most; `inside` itself if none is found).
    fn step_out(&self, shape: &dyn Shape, inside: DVec2) -> DVec2 {
        let n = shape.outward_normal(inside, self.reach);
        (1..=64)
            .map(|k| inside + k as f64 * self.reach / 8.0 * n)
            .find(|&q| !shape.contains(q))
            .unwrap_or(inside)
    }

    /// The last place outside `shape` on the segment from `outside` to `inside`.
    fn bisect(&self, shape: &dyn Shape, mut outside: DVec2, mut inside: DVec2) -> DVec2 {
        if shape.contains(outside) {
            return inside;
        }
        let tolerance = 1e-9 * self.reach;
        while outside.distance(inside) > tolerance {
            let mid = 0.5 * (outside + inside);
            if shape.contains(mid) {
                inside = mid;
            } else {
                outside = mid;
            }
        }
        outside
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::builtin::{Disc, Polygon};

    fn grid(cells: usize) -> GridGeometry {
        GridGeometry {
            origin: DVec2::ZERO,
            cell_size: 1.0 / cells as f64,
            cells: [cells, cells],
            periodic: [false, false],
        }
    }

    #[test]
    fn the_surface_law_removes_only_motion_into_the_surface() {
        let n = DVec2::Y;
        let fric = Wall::Frictional { friction: 0.5 };
        // Leaving or sliding: untouched by every law.
        for wall in [Wall::Slip, Wall::NoSlip, fric] {
            for v in [DVec2::new(0.3, 0.2), DVec2::new(-1.0, 0.0)] {
                assert_eq!(surface_velocity(v, n, wall), v);
            }
        }
        let v = DVec2::new(1.0, -1.0);
        assert_eq!(surface_velocity(v, n, Wall::Slip), DVec2::new(1.0, 0.0));
        assert_eq!(surface_velocity(v, n, Wall::NoSlip), DVec2::ZERO);
        // |vt| = 1 reduced by 0.5 x |vn| = 0.5.
        assert_eq!(surface_velocity(v, n, fric), DVec2::new(0.5, 0.0));
        // Friction enough to stop it: stopped, not reversed.
        let sticky = Wall::Frictional { friction: 2.0 };
        assert_eq!(surface_velocity(v, n, sticky), DVec2::ZERO);
    }

    #[test]
    fn an_inclined_wall_holds_its_inside_nodes_with_its_normal() {
        // A wedge under the line y = 0.51 x - 0.01 (a 27 degree slope), as a hopper's wall.
        let wedge = Polygon {
            vertices: vec![
                DVec2::new(0.0, -0.01),
                DVec2::new(1.0, -0.01),
                DVec2::new(1.0, 0.5),
            ],
        };
        let g = grid(20);
        let inside = Obstacles::nodes_inside(&wedge, &g);
        assert!(!inside.is_empty());
        let slope_normal = DVec2::new(-0.51, 1.0).normalize();
        let mut on_slope = 0;
        for &(n, at) in &inside {
            assert!(wedge.contains(at));
            assert_eq!(g.node_position(n % 21, n / 21), at);
            let normal = wedge.outward_normal(at, g.cell_size);
            assert!((normal.length() - 1.0).abs() < 1e-12);
            // Nodes nearer the slope than the floor or the right side take its normal.
            let to_slope = (0.51 * at.x - 0.01 - at.y).abs() / (1.0f64 + 0.51 * 0.51).sqrt();
            if to_slope < (at.y + 0.01).min(1.0 - at.x) - 1e-9 {
                assert!((normal - slope_normal).length() < 1e-12, "{at} {normal}");
                on_slope += 1;
            }
        }
        assert!(on_slope > 10);
        // And the default, sampled normal agrees with the exact one on the slope.
        let at = DVec2::new(0.6, 0.25);
        let sampled = crate::geometry::sampled_normal(|q| wedge.contains(q), at, 0.05);
        assert!(sampled.angle_to(slope_normal).abs() < 0.05, "{sampled}");
    }

    #[test]
    fn a_corner_node_on_the_bisector_takes_the_bisector() {
        let square = Polygon {
            vertices: vec![
                DVec2::new(0.0, 0.0),
                DVec2::new(1.0, 0.0),
                DVec2::new(1.0, 1.0),
                DVec2::new(0.0, 1.0),
            ],
        };
        let n = square.outward_normal(DVec2::new(0.9, 0.9), 0.1);
        assert!((n - DVec2::ONE.normalize()).length() < 1e-12, "{n}");
        // Outside, past the corner: the direction from the corner.
        let n = square.outward_normal(DVec2::new(1.3, 1.4), 0.1);
        assert!(
            (n - DVec2::new(0.3, 0.4).normalize()).length() < 1e-12,
            "{n}"
        );
    }

    #[test]
    fn a_point_is_stopped_where_its_path_enters() {
        let disc = Disc {
            centre: DVec2::new(0.5, 0.5),
            radius: 0.2,
        };
        let spec = ObstacleSpec {
            shape: Named(Box::new(disc.clone())),
            wall: Wall::Slip,
        };
        let obstacles = Obstacles::new(&[spec], &grid(10));
        let mut v = DVec2::new(0.0, -2.0);
        let at = obstacles.stop(DVec2::new(0.5, 0.75), DVec2::new(0.5, 0.65), &mut v);
        assert!((at.y - 0.7).abs() < 1e-9 && !disc.contains(at), "{at}");
        assert_eq!(v, DVec2::ZERO);
        // A point that stays outside is not touched.
        let mut v = DVec2::new(1.0, 0.0);
        let to = DVec2::new(0.1, 0.1);
        assert_eq!(obstacles.stop(DVec2::new(0.05, 0.1), to, &mut v), to);
        assert_eq!(v, DVec2::new(1.0, 0.0));
    }
}
