//! The scatter: points to their body's nodes (mass, momentum, force, normals), band by
//! band without locks.

use bevy_ecs::prelude::*;
use glam::{DMat2, DVec2};

use crate::body::Points;
use crate::grid::{GridField, GridGeometry};
use crate::step::bands::{Bands, Shared};
use crate::step::cell_average::CellDilatation;
use crate::step::locate::Location;

use crate::resources::Gravity;
use crate::shape_functions::Footprint;

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
    field.will_write(bands.node_span(grid));
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
    bands.for_each_phase(|b| {
        // Local copies: the stores below could otherwise alias the captured pointers,
        // which the compiler then reloads for every entry.
        let (mass, momentum, force, gradient) = (mass, momentum, force, gradient);
        let window = bands.node_window(grid, b);
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
                // SAFETY: the footprint lies in the band's window (checked above), which lies
                // inside the field (the four slices have `nodes` entries, asserted above), and
                // bands scattering in one phase have disjoint windows (`BandLayout::check`,
                // which the scene check runs and a unit test runs for every row count).
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
