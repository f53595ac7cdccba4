//! Where each point sits on the grid this step, computed once and shared by the transfers.
//!
//! Points do not move between the scatter and the gather (they move last, in
//! `transfer::advect_points`), so each point's footprint — its nine nodes, weights and
//! gradients — is built once per step, in parallel, and read by the scatter, the gather and
//! MUSL's remap. Building it in each transfer was a third of the step (docs/BENCHMARKS.md).
//! Each point's cell (for the band bucketing of the lock-free scatter and for the cell
//! averages) is found here too, and found again once the points have moved when the cell
//! averages need it (`cell_average::cell_density`); the next step's `locate_points` then reuses
//! those cells and bands instead of finding them again (the points do not move in between).

use bevy_ecs::prelude::*;
use glam::DVec2;
use rayon::prelude::*;

use super::bands::{BAND_ROWS, Bands};
use crate::body::Points;
use crate::grid::GridGeometry;
use crate::integration::{Footprint, Scheme};

/// Where a body's points are (index = point index).
#[derive(Component, Clone, Debug, Default)]
pub struct Location {
    /// Footprints at the start of the step (positions before this step's move).
    pub footprint: Vec<Footprint>,
    /// The cell of each point's current position.
    pub cell: Vec<u32>,
    /// The band of each point's current position (`bands`).
    band: Vec<u32>,
    /// `cell`, `band` and the body's `Bands` are those of the points' current positions:
    /// set when the cells are found after the move, spent by the next `locate_points`, and
    /// cleared by whoever hands out the positions for writing (`Simulation::points_mut`).
    current: bool,
}

impl Location {
    /// Finds the cells of `positions` and rebuckets `bands` by them.
    pub fn find_cells(&mut self, grid: &GridGeometry, positions: &[DVec2], bands: &mut Bands) {
        let inv_h = 1.0 / grid.cell_size;
        self.cell.resize(positions.len(), 0);
        self.band.resize(positions.len(), 0);
        self.cell
            .par_iter_mut()
            .zip(self.band.par_iter_mut())
            .zip(positions.par_iter())
            .for_each(|((c, b), x)| {
                let [i, j] = grid.cell_at(*x, inv_h);
                *c = (j * grid.cells[0] + i) as u32;
                *b = (j / BAND_ROWS) as u32;
            });
        bands.rebuild(grid, &self.band);
    }

    /// Finds the cells after the points moved; the next step's `locate_points` reuses them.
    pub fn find_cells_after_move(
        &mut self,
        grid: &GridGeometry,
        positions: &[DVec2],
        bands: &mut Bands,
    ) {
        self.find_cells(grid, positions, bands);
        self.current = true;
    }

    /// The positions may have changed outside the step: the cells must be found again.
    pub fn invalidate(&mut self) {
        self.current = false;
    }
}

/// Rebuilds every body's footprints, cells and bands from the points' current positions.
pub fn locate_points<S: Scheme>(
    grid: Res<GridGeometry>,
    mut bodies: Query<(&Points, &mut Location, &mut Bands)>,
) {
    let grid = &*grid;
    for (points, mut location, mut bands) in &mut bodies {
        let location = &mut *location;
        if !std::mem::take(&mut location.current) {
            location.find_cells(grid, &points.position, &mut bands);
        }
        location
            .footprint
            .resize(points.len(), Footprint::default());
        location
            .footprint
            .par_iter_mut()
            .zip(points.position.par_iter().zip(points.half_width.par_iter()))
            .for_each(|(f, (x, &a))| *f = Footprint::new::<S>(grid, *x, a));
    }
}
