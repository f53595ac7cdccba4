//! Filling a shape with material points on a lattice aligned with the grid.
//!
//! With `n` points per cell per direction the spacing is `h/n` and points sit at the centres
//! of the `n x n` sub-cells (for `n = 2`, the paper's quadrant centres). Each point's fixed
//! CPDI half-width is half the spacing.

use glam::DVec2;

use crate::geometry::Shape;
use crate::grid::GridGeometry;

/// The positions of a filled shape.
pub struct Lattice {
    pub spacing: f64,
    pub positions: Vec<DVec2>,
}

/// Lattice points of spacing `h / points_per_cell` that lie inside `shape` and the domain.
pub fn fill(shape: &dyn Shape, grid: &GridGeometry, points_per_cell: usize) -> Lattice {
    let spacing = grid.cell_size / points_per_cell as f64;
    let (lo, hi) = shape.bounds();
    let (dmin, dmax) = (grid.origin, grid.max());
    let lo = lo.max(dmin);
    let hi = hi.min(dmax);
    let mut positions = Vec::new();
    if lo.x >= hi.x || lo.y >= hi.y {
        return Lattice { spacing, positions };
    }
    let first = ((lo - grid.origin) / spacing).floor();
    let last = ((hi - grid.origin) / spacing).ceil();
    let (i0, j0) = (first.x as i64, first.y as i64);
    let (i1, j1) = (last.x as i64, last.y as i64);
    for j in j0..j1 {
        for i in i0..i1 {
            let p = grid.origin + (DVec2::new(i as f64, j as f64) + 0.5) * spacing;
            if p.cmpge(dmin).all() && p.cmplt(dmax).all() && shape.contains(p) {
                positions.push(p);
            }
        }
    }
    Lattice { spacing, positions }
}
