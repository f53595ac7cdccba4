//! Where each point sits on the grid this step, computed once and shared by the transfers.
//!
//! Points do not move between the scatter and the gather (they move last, in
//! `scatter_gather::advect_points`), so each point's footprint — its nine nodes, weights and
//! gradients — is built once per step, in parallel, and read by the scatter, the gather and
//! MUSL's remap. Building it in each transfer was a third of the step (docs/BENCHMARKS.md).
//! Each point's cell (for the band bucketing of the lock-free scatter and for the cell
//! averages) is found here too, and found again once the points have moved when the cell
//! averages need it (`cell_average::cell_density`); the next step's `locate_points` then reuses
//! those cells and bands instead of finding them again, unless the points were written in
//! between (bevy's change detection; the stress update writes them without marking them).
//! Nothing here is trusted by the lock-free scatter: it checks each point against its band
//! (`bands::NodeWindow`), so a stale cell is a panic, never a data race.

use bevy_ecs::change_detection::Tick;
use bevy_ecs::prelude::*;
use glam::DVec2;
use rayon::prelude::*;

use super::bands::Bands;
use crate::body::Points;
use crate::grid::BandLayout;
use crate::grid::GridGeometry;
use crate::kernels::Kernels;
use crate::shape_functions::{Footprint, Scheme};

/// Points per parallel task of the per-point passes here: enough to amortise the split, and
/// a multiple of the vector kernels' four lanes.
const CHUNK: usize = 512;

/// Where a body's points are (index = point index).
#[derive(Component, Clone, Debug, Default)]
pub struct Location {
    /// Footprints at the start of the step (positions before this step's move).
    footprint: Vec<Footprint>,
    /// The cell of each point's current position.
    cell: Vec<u32>,
    /// The band of each point's current position (`bands`).
    band: Vec<u32>,
    /// The change tick of the body's `Points` when `cell`, `band` and its `Bands` were found
    /// after the move: the next `locate_points` reuses them only if `Points` has not been
    /// written since (a plugin system that moves points marks it, as any `Mut` does).
    found_for: Option<Tick>,
}

impl Location {
    /// Bytes per point besides the footprint ([`Footprint::BYTES`]): its cell and band
    /// here, and its slot in the body's [`Bands`].
    pub const BYTES_PER_POINT: usize = 4 + 4 + 4;

    /// Each point's footprint, built by this step's `locate_points`.
    pub fn footprints(&self) -> &[Footprint] {
        &self.footprint
    }

    /// Each point's cell (flat index).
    pub fn cells(&self) -> &[u32] {
        &self.cell
    }

    /// Finds the cells of `positions` and rebuckets `bands` by them.
    fn find_cells(
        &mut self,
        grid: &GridGeometry,
        kernels: Kernels,
        positions: &[DVec2],
        bands: &mut Bands,
    ) {
        let layout = BandLayout::of(grid);
        self.cell.resize(positions.len(), 0);
        self.band.resize(positions.len(), 0);
        self.cell
            .par_chunks_mut(CHUNK)
            .zip(self.band.par_chunks_mut(CHUNK))
            .zip(positions.par_chunks(CHUNK))
            .for_each(|((c, b), x)| kernels.cells(grid, &layout, x, c, b));
        bands.rebuild(layout, &self.band);
    }

    /// Finds the cells after the points moved; the next step's `locate_points` reuses them
    /// unless `points` is written again first.
    pub fn find_cells_after_move(
        &mut self,
        grid: &GridGeometry,
        kernels: Kernels,
        points: &Mut<Points>,
        bands: &mut Bands,
    ) {
        self.find_cells(grid, kernels, &points.position, bands);
        self.found_for = Some(points.last_changed());
    }

    /// The positions may have changed outside the schedule: the cells must be found again.
    pub fn invalidate(&mut self) {
        self.found_for = None;
    }
}

/// Rebuilds every body's footprints, and its cells and bands unless those found after the
/// last move are still current.
pub fn locate_points<S: Scheme>(
    grid: Res<GridGeometry>,
    kernels: Res<Kernels>,
    mut bodies: Query<(Ref<Points>, &mut Location, &mut Bands)>,
) {
    let grid = &*grid;
    for (points, mut location, mut bands) in &mut bodies {
        let location = &mut *location;
        if location.found_for.take() != Some(points.last_changed()) {
            location.find_cells(grid, *kernels, &points.position, &mut bands);
        }
        location
            .footprint
            .resize(points.len(), Footprint::default());
        location
            .footprint
            .par_chunks_mut(CHUNK)
            .zip(points.position.par_chunks(CHUNK))
            .zip(points.half_width.par_chunks(CHUNK))
            .for_each(|((f, x), a)| kernels.footprints::<S>(grid, x, a, f));
    }
}
