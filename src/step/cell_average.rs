//! The cell-averaged dilatation and density (`dilatation: CellAveraged`, the default;
//! docs/numerics.md, "The disconnected phase and sub-cell noise").
//!
//! Each point's dilatation `tr L` is replaced by the volume-weighted mean over the points in
//! its cell, which removes the checkerboard pressure mode of several points per cell; the
//! scatter uses the cell mean of the stress trace, the force conjugate to that dilatation
//! (the B-bar pairing); and the constitutive update sees the cell density, so the
//! dense/disconnected decision is made at the grid's resolution.

use bevy_ecs::prelude::*;
use rayon::prelude::*;

use super::bands::{Bands, Shared};
use super::locate::Location;
use crate::body::Points;
use crate::grid::GridGeometry;
use crate::kernels::Kernels;

/// Cells per block of the parallel per-cell passes.
const CELL_BLOCK: usize = 4096;

/// Per-cell sums for the cell-averaged dilatation and density.
#[derive(Component, Clone, Debug, Default)]
pub struct CellDilatation {
    volume: Vec<f64>,
    weighted: Vec<f64>,
    /// Volume-weighted mean of `T_xx + T_yy` per cell, for the scatter.
    trace_mean: Vec<f64>,
}

impl CellDilatation {
    /// Bytes held per cell (for memory estimates).
    pub const BYTES_PER_CELL: usize = 3 * 8;

    pub fn new(cells: usize) -> Self {
        CellDilatation {
            volume: vec![0.0; cells],
            weighted: vec![0.0; cells],
            trace_mean: vec![0.0; cells],
        }
    }

    /// Per-cell sums of the points' volumes and of `value(k)`, band by band in parallel (a
    /// cell lies in exactly one band, so bands never share a sum; `bands` and `cell` must
    /// be current).
    fn sum(
        &mut self,
        grid: &GridGeometry,
        points: &Points,
        cell: &[u32],
        bands: &Bands,
        value: impl Fn(usize) -> f64 + Sync,
    ) {
        self.volume.fill(0.0);
        self.weighted.fill(0.0);
        let cells = self.volume.len();
        assert!(
            self.weighted.len() == cells && grid.cells[0] * grid.cells[1] == cells,
            "a body's cell sums do not match the grid ({cells} cells)"
        );
        let volume = Shared::new(&mut self.volume);
        let weighted = Shared::new(&mut self.weighted);
        bands.for_each(|b| {
            let (volume, weighted) = (volume, weighted); // see `particle_to_grid`
            let own = bands.cells_of(grid, b);
            for &k in bands.points(b) {
                let k = k as usize;
                let c = cell[k] as usize;
                assert!(
                    own.contains(&c),
                    "point {k}'s cell {c} is not in its band {b}: cells and bands disagree"
                );
                // SAFETY: `c` is one of band b's own cells (checked above). A band's cells are
                // the cells of its rows, inside the grid's `cells` (asserted above to be the
                // length of both sums), and the bands tile the rows without overlap
                // (`BandLayout::rows`, tested for every row count), so no other band running
                // now sums into `c`.
                unsafe {
                    volume.add_at(c, points.volume[k]);
                    weighted.add_at(c, value(k));
                }
            }
        });
    }

    /// The cell mean of the in-plane stress trace that point `p` of cell `c` scatters in
    /// place of its own.
    #[inline]
    pub fn stress_trace(&self, c: u32) -> f64 {
        self.trace_mean[c as usize]
    }

    /// Turns the sums of `value` into means per volume, `sum value / sum V`, cell by cell:
    /// one division per cell instead of one per point (a cell holds about four points). An
    /// empty cell's mean is NaN, and no point reads it.
    fn finish_means(&mut self) {
        self.weighted
            .par_chunks_mut(CELL_BLOCK)
            .zip(self.volume.par_chunks(CELL_BLOCK))
            .for_each(|(w, v)| w.iter_mut().zip(v).for_each(|(w, &v)| *w /= v));
    }

    /// The mean per volume of cell `c` (after [`CellDilatation::finish_means`]).
    fn mean(&self, c: u32) -> f64 {
        self.weighted[c as usize]
    }
}

/// The cell means of the stress's in-plane trace `T_xx + T_yy` that the scatter uses in
/// place of each point's own (the force conjugate to `average_dilatation`).
pub fn average_stress_trace(
    grid: Res<GridGeometry>,
    mut bodies: Query<(&Points, &mut CellDilatation, &Bands, &Location)>,
) {
    let grid = &*grid;
    for (points, mut cells, bands, location) in &mut bodies {
        let cells = &mut *cells;
        cells.sum(grid, points, location.cells(), bands, |k| {
            let t = points.stress[k];
            points.volume[k] * (t.xx + t.yy)
        });
        let CellDilatation {
            volume,
            weighted,
            trace_mean,
        } = cells;
        trace_mean
            .par_iter_mut()
            .zip(volume.par_iter().zip(weighted.par_iter()))
            .for_each(|(mean, (&v, &w))| *mean = if v > 0.0 { w / v } else { 0.0 });
    }
}

/// Replaces each point's dilatation `tr L` by the volume-weighted mean over the points in
/// its cell, keeping the deviatoric part: `L += (mean - tr L)/2 * 1`. With several points
/// per cell and bilinear nodes, per-point dilatations carry a checkerboard pressure mode
/// (docs/numerics.md); the cell mean removes it, as selective reduced integration does for
/// finite elements.
pub fn average_dilatation(
    grid: Res<GridGeometry>,
    mut bodies: Query<(&mut Points, &mut CellDilatation, &Bands, &Location)>,
) {
    let grid = &*grid;
    for (mut points, mut cells, bands, location) in &mut bodies {
        let points = &mut *points;
        let cells = &mut *cells;
        // The points have not moved since `locate_points` found their cells.
        cells.sum(grid, points, location.cells(), bands, |k| {
            let l = points.velocity_gradient[k];
            points.volume[k] * (l.x_axis.x + l.y_axis.y)
        });
        cells.finish_means();
        location
            .cells()
            .par_iter()
            .zip(points.velocity_gradient.par_iter_mut())
            .for_each(|(&c, l)| {
                let mean = cells.mean(c);
                let shift = 0.5 * (mean - (l.x_axis.x + l.y_axis.y));
                l.x_axis.x += shift;
                l.y_axis.y += shift;
            });
    }
}

/// The density the constitutive update sees: the mean `sum m / sum V` of the points in the
/// point's cell (after they moved). The disconnected phase is then decided at the grid's
/// resolution: a point that dilated on its own inside a dense cell (a sub-cell pore the grid
/// cannot close) is not a granular gas, and rejoins the dense phase as soon as the cell is
/// compressed (docs/numerics.md).
pub fn cell_density(
    grid: Res<GridGeometry>,
    kernels: Res<Kernels>,
    mut bodies: Query<(&mut Points, &mut CellDilatation, &mut Bands, &mut Location)>,
) {
    let grid = &*grid;
    for (mut points, mut cells, mut bands, mut location) in &mut bodies {
        let cells = &mut *cells;
        // Marked first, so that the tick the cells are found for is this system's own.
        points.set_changed();
        location.find_cells_after_move(grid, *kernels, &points, &mut bands);
        let points = &mut *points;
        cells.sum(grid, points, location.cells(), &bands, |k| points.mass[k]);
        cells.finish_means();
        location
            .cells()
            .par_iter()
            .zip(points.density.par_iter_mut())
            .for_each(|(&c, rho)| *rho = cells.mean(c));
    }
}
