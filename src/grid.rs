//! The background grid: its geometry (a resource), one body's nodal field (a component), and
//! how the lock-free scatter cuts the grid's rows into bands (`BandLayout`: a function of the
//! geometry alone, kept here so that the scene check can prove it race-free before a run
//! without depending on the step).
//!
//! Every body keeps its own nodal field so that contact can compare bodies node by node
//! (docs/model.md §2 and §5). Fields are struct-of-arrays so the scatter and gather loops run over
//! plain slices.

use bevy_ecs::prelude::*;
use std::ops::Range;

use glam::DVec2;
use rayon::prelude::*;

/// Cartesian grid of square cells covering the rectangular domain.
///
/// Along an axis with periodic walls the last node column is identified with the first, so
/// that axis has `cells` nodes; otherwise it has `cells + 1`.
#[derive(Resource, Clone, Debug)]
pub struct GridGeometry {
    pub origin: DVec2,
    pub cell_size: f64,
    pub cells: [usize; 2],
    pub periodic: [bool; 2],
}

impl GridGeometry {
    /// Nodes along axis `a`.
    pub fn nodes_along(&self, a: usize) -> usize {
        if self.periodic[a] {
            self.cells[a]
        } else {
            self.cells[a] + 1
        }
    }

    pub fn node_count(&self) -> usize {
        self.nodes_along(0) * self.nodes_along(1)
    }

    /// Flat index of node `(i, j)`.
    #[inline]
    pub fn index(&self, i: usize, j: usize) -> usize {
        j * self.nodes_along(0) + i
    }

    /// The nodes on one side, in order: along `axis` 0 the left (`low`) or right column, along
    /// 1 the bottom or top row.
    pub fn side_nodes(&self, axis: usize, low: bool) -> impl Iterator<Item = usize> + use<> {
        let (nx, ny) = (self.nodes_along(0), self.nodes_along(1));
        let (count, first, stride) = if axis == 0 {
            (ny, if low { 0 } else { nx - 1 }, nx)
        } else {
            (nx, if low { 0 } else { (ny - 1) * nx }, 1)
        };
        (0..count).map(move |k| first + k * stride)
    }

    /// Position of node `(i, j)`.
    pub fn node_position(&self, i: usize, j: usize) -> DVec2 {
        self.origin + DVec2::new(i as f64, j as f64) * self.cell_size
    }

    /// Coordinate along `axis` of the node of flat index `n` (the place of a side's node
    /// along that side, for wall segments).
    pub fn node_coordinate(&self, n: usize, axis: usize) -> f64 {
        let nx = self.nodes_along(0);
        self.node_position(n % nx, n / nx)[axis]
    }

    /// Flat index of the cell holding `x` (clamped into the grid).
    pub fn cell_of(&self, x: DVec2) -> usize {
        let [i, j] = self.cell_at(x, 1.0 / self.cell_size);
        j * self.cells[0] + i
    }

    /// Column and row of the cell holding `x` (clamped into the grid), given `1/h` (loops
    /// over many points pass it in: a division costs several multiplications).
    #[inline]
    pub fn cell_at(&self, x: DVec2, inv_h: f64) -> [usize; 2] {
        let rel = (x - self.origin) * inv_h;
        // Truncation equals the floor wherever the clamp keeps it: at and above zero, and
        // below zero both clamp to the first cell (NaN too). One 32-bit conversion per axis,
        // where a floor and a saturating cast to usize took several (the post-move cell search
        // was 5% of a step).
        let along = |r: f64, cells: usize| {
            let last = (cells - 1).min(i32::MAX as usize) as i32;
            (r as i32).clamp(0, last) as usize
        };
        [along(rel.x, self.cells[0]), along(rel.y, self.cells[1])]
    }

    /// Upper corner of the domain.
    pub fn max(&self) -> DVec2 {
        self.origin + DVec2::new(self.cells[0] as f64, self.cells[1] as f64) * self.cell_size
    }

    /// Domain extent.
    pub fn size(&self) -> DVec2 {
        self.max() - self.origin
    }

    /// Wraps a position back into the domain along periodic axes.
    pub fn wrap(&self, mut x: DVec2) -> DVec2 {
        let size = self.size();
        for a in 0..2 {
            if self.periodic[a] {
                let rel = (x[a] - self.origin[a]).rem_euclid(size[a]);
                x[a] = self.origin[a] + rel;
            }
        }
        x
    }
}

/// One body's nodal field, struct-of-arrays over all grid nodes.
#[derive(Component, Clone, Debug, Default)]
pub struct GridField {
    pub mass: Vec<f64>,
    /// Momentum at the start of the step, then the updated momentum.
    pub momentum: Vec<DVec2>,
    /// Total nodal force (gravity + internal + contact).
    pub force: Vec<DVec2>,
    /// Velocity at the end of the step (`v_i^{n+1}`).
    pub velocity: Vec<DVec2>,
    /// Acceleration over the step (`a_i = f_i / m_i`), used by the FLIP update.
    pub acceleration: Vec<DVec2>,
    /// Mass gradient `sum_p m_p grad S_i(x_p)` (out of the body at its surface nodes);
    /// filled only when contact needs normals.
    pub mass_gradient: Vec<DVec2>,
    /// Velocity and acceleration packed per node for the vector gathers, copied from the
    /// two arrays above just before the gathers (`GridField::pack_motion`, module
    /// `kernels`); empty when the scalar kernels run. Never written otherwise.
    pub motion: Vec<NodeMotion>,
    /// Nodes lighter than this drop their internal force (docs/model.md §2, step 3).
    pub mass_tolerance: f64,
    /// Total force the other bodies exert on this one through contact this step (N per
    /// metre of thickness); zero for a lone body.
    pub contact_force: DVec2,
    /// The nodes (flat indices) the last scatter may have written, and those the scatter
    /// before it may have: outside both every node is empty, with zero momentum, force,
    /// velocity and acceleration, so the clear and the grid update skip them. A body that
    /// fills a small part of the domain (an intruder, a bed below open air) no longer costs
    /// a sweep of the whole grid twice a step.
    written: Range<usize>,
    previously: Range<usize>,
}

impl GridField {
    pub fn new(nodes: usize, mass_tolerance: f64, with_normals: bool) -> Self {
        GridField {
            mass: vec![0.0; nodes],
            momentum: vec![DVec2::ZERO; nodes],
            force: vec![DVec2::ZERO; nodes],
            velocity: vec![DVec2::ZERO; nodes],
            acceleration: vec![DVec2::ZERO; nodes],
            mass_gradient: if with_normals {
                vec![DVec2::ZERO; nodes]
            } else {
                Vec::new()
            },
            motion: Vec::new(),
            mass_tolerance,
            contact_force: DVec2::ZERO,
            written: 0..nodes,
            previously: 0..nodes,
        }
    }

    /// Zeroes the accumulated quantities before a new scatter, in parallel over blocks of
    /// nodes (each block a `memset`; a per-element parallel loop is not, and was slower).
    pub fn clear(&mut self) {
        let nodes = self.written.clone();
        zero(&mut self.mass[nodes.clone()]);
        zero(&mut self.momentum[nodes.clone()]);
        zero(&mut self.force[nodes.clone()]);
        if !self.mass_gradient.is_empty() {
            zero(&mut self.mass_gradient[nodes.clone()]);
        }
        self.previously = nodes;
        self.contact_force = DVec2::ZERO;
    }

    /// Records the nodes a scatter is about to write (after [`GridField::clear`]).
    pub fn will_write(&mut self, nodes: Range<usize>) {
        assert!(
            nodes.end <= self.mass.len(),
            "nodes {nodes:?} outside the field"
        );
        self.written = nodes;
    }

    /// The nodes that may be non-empty or hold last step's values: those the last two
    /// scatters wrote. Every other node is empty, at rest and without force, and stays so
    /// only if nothing writes it: a plugin system that changes nodal values must keep to
    /// nodes with mass, as the contact laws and `Driven` do (`tests/step/active_nodes.rs`).
    pub fn active(&self) -> Range<usize> {
        let (a, b) = (&self.written, &self.previously);
        match (a.is_empty(), b.is_empty()) {
            (true, _) => b.clone(),
            (_, true) => a.clone(),
            _ => a.start.min(b.start)..a.end.max(b.end),
        }
    }

    /// Copies each active node's velocity and acceleration into [`GridField::motion`], the
    /// packed layout the vector gathers read; call after the last change to either in a
    /// step and before the gathers. Nodes outside [`GridField::active`] are not read by this
    /// step's footprints and are left as they are.
    pub fn pack_motion(&mut self) {
        let nodes = self.active();
        if self.motion.len() != self.velocity.len() {
            self.motion
                .resize(self.velocity.len(), NodeMotion::default());
        }
        let (v, a) = (
            &self.velocity[nodes.clone()],
            &self.acceleration[nodes.clone()],
        );
        for ((m, v), a) in self.motion[nodes].iter_mut().zip(v).zip(a) {
            *m = NodeMotion([v.x, v.y, a.x, a.y]);
        }
    }

    /// Bytes held per node (for memory estimates).
    pub fn bytes_per_node(with_normals: bool) -> usize {
        8 + 16 * if with_normals { 5 } else { 4 }
    }
}

/// One node's velocity and acceleration, side by side for one 256-bit load (module `kernels`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C, align(32))]
pub struct NodeMotion(pub [f64; 4]);

impl NodeMotion {
    /// Bytes per node (for memory estimates).
    pub const BYTES: usize = std::mem::size_of::<NodeMotion>();
}

/// Nodes per block of the parallel clear.
const CLEAR_BLOCK: usize = 4096;

fn zero<T: Default + Copy + Send>(values: &mut [T]) {
    values
        .par_chunks_mut(CLEAR_BLOCK)
        .for_each(|block| block.fill(T::default()));
}

/// Cell rows per band (at least 3: the lock-free scatter, `step::bands`).
pub const BAND_ROWS: usize = 4;

/// How a grid's cell rows are cut into bands and in which phases the bands scatter (`step::bands`
/// docs). A function of the grid alone, never of the points or the thread count.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BandLayout {
    /// Cell rows of the grid.
    rows: usize,
    /// Node rows of the grid (`rows` on a periodic y axis, else `rows + 1`).
    node_rows: usize,
    periodic: bool,
    count: usize,
}

impl BandLayout {
    pub fn of(grid: &GridGeometry) -> BandLayout {
        let rows = grid.cells[1];
        let periodic = grid.periodic[1];
        let count = if periodic {
            (rows / BAND_ROWS).max(1)
        } else {
            rows.div_ceil(BAND_ROWS)
        };
        BandLayout {
            rows,
            node_rows: grid.nodes_along(1),
            periodic,
            count,
        }
    }

    /// Whether the y axis is periodic (the first and last bands are neighbours).
    pub fn periodic(&self) -> bool {
        self.periodic
    }

    /// Number of bands.
    pub fn count(&self) -> usize {
        self.count
    }

    /// The band of cell row `j`.
    #[inline]
    pub fn band_of_row(&self, j: usize) -> u32 {
        (j / BAND_ROWS).min(self.count.saturating_sub(1)) as u32
    }

    /// The cell rows of band `b`: `BAND_ROWS` of them, the last band the rest.
    pub fn rows(&self, b: usize) -> Range<usize> {
        let first = b * BAND_ROWS;
        let last = if b + 1 >= self.count {
            self.rows
        } else {
            first + BAND_ROWS
        };
        first.min(self.rows)..last
    }

    /// The node rows band `b` may scatter to: from one below its first cell row to two
    /// above its last, as `(first, count)`, `first` wrapped onto the grid on a periodic
    /// axis, `count` at most the grid's node rows.
    pub(crate) fn node_rows(&self, b: usize) -> (usize, usize) {
        let cells = self.rows(b);
        if self.periodic {
            let first = (cells.start + self.node_rows - 1) % self.node_rows;
            (first, (cells.len() + 3).min(self.node_rows))
        } else {
            let first = cells.start.saturating_sub(1);
            (first, (cells.end + 2).min(self.node_rows) - first)
        }
    }

    /// Whether band `b` scatters alone after the two parallel phases: the last of an odd
    /// number of bands on a periodic axis, a neighbour of band 0 of the same parity.
    fn lone(&self, b: usize) -> bool {
        self.periodic && self.count % 2 == 1 && self.count > 1 && b == self.count - 1
    }

    /// The phase band `b` scatters in: 0 (even bands), 1 (odd bands) or 2 (the lone last
    /// band, see [`BandLayout::lone`]).
    pub fn phase(&self, b: usize) -> usize {
        if self.lone(b) { 2 } else { b % 2 }
    }

    /// Checks what the lock-free scatter relies on: no two bands of one phase share a node
    /// row of their windows (the rows their points' stencils can reach). `Err` names the
    /// first pair that would race.
    pub fn check(&self) -> Result<(), String> {
        let mut owner: Vec<Vec<Option<usize>>> = vec![vec![None; self.node_rows]; 3];
        for b in 0..self.count {
            let (first, count) = self.node_rows(b);
            let phase = &mut owner[self.phase(b)];
            for k in 0..count {
                let row = (first + k) % self.node_rows;
                if let Some(other) = phase[row].replace(b) {
                    return Err(format!(
                        "bands {other} and {b} scatter in the same phase and both reach node row {row} \
                         ({} cell rows, y {})",
                        self.rows,
                        if self.periodic { "periodic" } else { "bounded" }
                    ));
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use glam::DVec2;

    use super::{BAND_ROWS, BandLayout, GridGeometry};

    fn grid(rows: usize, periodic: bool) -> GridGeometry {
        GridGeometry {
            origin: DVec2::ZERO,
            cell_size: 1.0,
            cells: [3, rows],
            periodic: [false, periodic],
        }
    }

    /// For every row count up to 1000, bounded or periodic in y: the bands tile the rows,
    /// each cell row's stencil (node rows `j - 1` to `j + 2`) lies in its band's window, and
    /// no two bands of one phase share a node row.
    #[test]
    fn every_layout_is_free_of_races() {
        for periodic in [false, true] {
            for rows in 1..=1000 {
                let layout = BandLayout::of(&grid(rows, periodic));
                let at = format!("{rows} rows, periodic {periodic}");
                layout.check().unwrap_or_else(|e| panic!("{at}: {e}"));
                let nodes = grid(rows, periodic).nodes_along(1) as i64;
                let mut next = 0;
                for b in 0..layout.count() {
                    let cells = layout.rows(b);
                    assert_eq!(cells.start, next, "{at}: band {b} does not follow on");
                    assert!(!cells.is_empty(), "{at}: band {b} is empty");
                    next = cells.end;
                    let (first, span) = layout.node_rows(b);
                    for j in cells {
                        assert_eq!(layout.band_of_row(j), b as u32, "{at}: row {j}");
                        for r in j as i64 - 1..=j as i64 + 2 {
                            let r = if periodic {
                                r.rem_euclid(nodes)
                            } else if (0..nodes).contains(&r) {
                                r
                            } else {
                                continue;
                            };
                            let d = (r - first as i64).rem_euclid(nodes);
                            assert!(d < span as i64, "{at}: row {j} reaches node row {r}");
                        }
                    }
                }
                assert_eq!(next, rows, "{at}: the bands do not cover the rows");
            }
        }
    }

    /// The layout before issue 35 cut a periodic axis into `ceil(rows / BAND_ROWS)` bands,
    /// the last one short: with 54 rows bands 0 and 12 ran in one phase and both reached
    /// the wrapped node row 53. The check finds it.
    #[test]
    fn the_check_finds_the_old_periodic_race() {
        let fixed = BandLayout::of(&grid(54, true));
        assert_eq!(fixed.count(), 13);
        let old = BandLayout {
            count: 54usize.div_ceil(BAND_ROWS),
            ..fixed
        };
        let err = old.check().expect_err("the old layout races");
        assert!(
            err.contains("bands 0 and 12") && err.contains("row 53"),
            "{err}"
        );
    }
}
