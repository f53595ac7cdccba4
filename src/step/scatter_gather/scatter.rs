//! The scatter: points to their body's nodes (mass, momentum, force, normals), band by
//! band without locks.

use bevy_ecs::prelude::*;
use glam::{DMat2, DVec2};

use crate::body::Points;
use crate::grid::{GridField, GridGeometry};
use crate::kernels::Kernels;
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
    kernels: Res<Kernels>,
    mut bodies: Query<(
        &Points,
        &Location,
        &mut GridField,
        &Bands,
        Option<&CellDilatation>,
    )>,
) {
    for (points, location, mut field, bands, cells) in &mut bodies {
        // Monomorphised on the transfer, so FLIP's scatter carries no affine work, and on
        // the kernels, so the scalar path asks nothing per point.
        let scatter = match (points.affine.is_empty(), kernels.avx2()) {
            (true, false) => scatter_body::<false, false>,
            (false, false) => scatter_body::<true, false>,
            (true, true) => scatter_body::<false, true>,
            (false, true) => scatter_body::<true, true>,
        };
        scatter(&grid, gravity.0, points, location, &mut field, bands, cells);
    }
}

/// One body's scatter for `particle_to_grid`; `APIC` says whether its points carry an
/// affine field, `AVX2` whether the row kernel runs (`Kernels::avx2`: true only after the
/// processor was found to have AVX2).
fn scatter_body<const APIC: bool, const AVX2: bool>(
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
    let targets = Targets {
        mass: Shared::new(&mut field.mass),
        momentum: Shared::new(&mut field.momentum),
        force: Shared::new(&mut field.force),
        gradient: Shared::new(&mut field.mass_gradient),
        normals,
    };
    bands.for_each_phase(|b| {
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
            let vol = points.volume[p];
            let mut t = points.stress[p];
            if let Some(cells) = cells {
                let shift = 0.5 * (cells.stress_trace(location.cells()[p]) - t.xx - t.yy);
                t.xx += shift;
                t.yy += shift;
            }
            let load = PointLoad {
                m,
                momentum: NodeMomentum::of(points, p, f, grid),
                mg: m * g,
                // V T . grad S for grad S = (gx wy, wx gy): the stress columns scaled.
                tx: vol * t.traction(DVec2::X),
                ty: vol * t.traction(DVec2::Y),
            };
            // SAFETY: the footprint lies in the band's window (checked above), which lies
            // inside the field (the four slices have `nodes` entries, asserted above), and
            // bands scattering in one phase have disjoint windows (`BandLayout::check`,
            // which the scene check runs and a unit test runs for every row count).
            // `AVX2` is set only where `Kernels::avx2` is true, after the processor was found
            // to have AVX2.
            unsafe {
                #[cfg(target_arch = "x86_64")]
                if AVX2 && rows_are_consecutive(f) {
                    avx2::scatter_rows::<APIC>(f, &load, &targets);
                    continue;
                }
                scatter_entries(f, &load, &targets);
            }
        }
    });
}

/// The nodal arrays a band's scatter adds to.
#[derive(Clone, Copy)]
struct Targets<'a> {
    mass: Shared<'a, f64>,
    momentum: Shared<'a, DVec2>,
    force: Shared<'a, DVec2>,
    gradient: Shared<'a, DVec2>,
    /// Whether the mass gradient is kept (contact needs normals).
    normals: bool,
}

impl<'a> Targets<'a> {
    /// The four arrays, as locals for the caller: stores through them could otherwise
    /// alias the struct's fields, which the compiler then reloads for every entry.
    #[inline(always)]
    #[allow(clippy::type_complexity)] // four named handles, unpacked at once
    fn arrays(
        &self,
    ) -> (
        Shared<'a, f64>,
        Shared<'a, DVec2>,
        Shared<'a, DVec2>,
        Shared<'a, DVec2>,
    ) {
        (self.mass, self.momentum, self.force, self.gradient)
    }
}

/// What a point hands its nodes, before each entry's weight and gradient: its mass, its
/// momentum, its weight `m g` and its stress as the tractions `V T . x` and `V T . y`.
struct PointLoad<const APIC: bool> {
    m: f64,
    momentum: NodeMomentum<APIC>,
    mg: DVec2,
    tx: DVec2,
    ty: DVec2,
}

/// Whether the footprint's three columns are consecutive nodes, so that each row's entries
/// are three neighbouring nodes in memory (everywhere but across a periodic seam).
#[inline]
fn rows_are_consecutive(f: &Footprint) -> bool {
    f.column[1] == f.column[0] + 1 && f.column[2] == f.column[0] + 2
}

/// The scatter of one point, entry by entry: `m_i += S m`, `(mv)_i += S (m v)_i`,
/// `f_i += S m g - V T . grad S` and, with normals, `g_i += m grad S`.
///
/// # Safety
/// Every node of `f` must be inside the targets and written by no other thread meanwhile.
#[inline(always)]
unsafe fn scatter_entries<const APIC: bool>(
    f: &Footprint,
    load: &PointLoad<APIC>,
    targets: &Targets,
) {
    let (m, mg, tx, ty, node_momentum) = (load.m, load.mg, load.tx, load.ty, load.momentum);
    let (mass, momentum, force, gradient) = targets.arrays();
    let normals = targets.normals;
    f.for_each_indexed(|kx, ky, n, w, grad| {
        // SAFETY: per the function's contract.
        unsafe {
            mass.add_at(n, w * m);
            momentum.add_at(n, w * node_momentum.at(kx, ky));
            force.add_at(n, w * mg - grad.x * tx - grad.y * ty);
            if normals {
                gradient.add_at(n, m * grad);
            }
        }
    });
}

/// The row kernel: each footprint row's three consecutive nodes, the first two in one
/// 256-bit register (lanes: node 0 x, node 0 y, node 1 x, node 1 y) and the third in a
/// 128-bit one, with each lane's products and sums formed as [`scatter_entries`] forms them
/// (no fused multiply-add), so the nodes receive the same bits.
#[cfg(target_arch = "x86_64")]
mod avx2 {
    use super::*;
    use std::arch::x86_64::*;

    /// `[a, b, a, b]`.
    #[inline(always)]
    fn twice(v: DVec2) -> __m256d {
        // SAFETY: AVX is part of AVX2, which the caller has.
        unsafe { _mm256_setr_pd(v.x, v.y, v.x, v.y) }
    }

    /// [`scatter_entries`] for a footprint whose rows are consecutive nodes.
    ///
    /// # Safety
    /// As for [`scatter_entries`], and the processor must have AVX2.
    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn scatter_rows<const APIC: bool>(
        f: &Footprint,
        load: &PointLoad<APIC>,
        targets: &Targets,
    ) {
        let (wx, gx) = (&f.wx, &f.gx);
        let wx01 = _mm256_setr_pd(wx[0], wx[0], wx[1], wx[1]);
        let gxwx01 = _mm256_setr_pd(gx[0], wx[0], gx[1], wx[1]);
        let (wx2, gxwx2) = (_mm_set1_pd(wx[2]), _mm_setr_pd(gx[2], wx[2]));
        let (m4, m2) = (_mm256_set1_pd(load.m), _mm_set1_pd(load.m));
        let (mg4, tx4, ty4) = (twice(load.mg), twice(load.tx), twice(load.ty));
        let (mg2, tx2, ty2) = (half(mg4), half(tx4), half(ty4));
        let mv4 = twice(load.momentum.mv);
        // `m C d` per entry is `x_axis dx + y_axis dy` (glam's order): the first term per
        // column, the second's matrix column per lane.
        let NodeMomentum { mc, dx, dy, .. } = load.momentum;
        let (cx, cy) = (mc.x_axis, twice(mc.y_axis));
        let x01 = _mm256_setr_pd(cx.x * dx[0], cx.y * dx[0], cx.x * dx[1], cx.y * dx[1]);
        let x2 = _mm_setr_pd(cx.x * dx[2], cx.y * dx[2]);
        let (mass, momentum, force, gradient) = targets.arrays();
        let normals = targets.normals;
        for (ky, dy) in dy.into_iter().enumerate() {
            let n = f.node(0, ky);
            let (wy, gy) = (f.wy[ky], f.gy[ky]);
            // Nodes n and n + 1.
            let w = _mm256_mul_pd(wx01, _mm256_set1_pd(wy));
            // [gx0 wy, wx0 gy, gx1 wy, wx1 gy]: each entry's grad S.
            let grad = _mm256_mul_pd(gxwx01, _mm256_setr_pd(wy, gy, wy, gy));
            let at = if APIC {
                let y = _mm256_mul_pd(cy, _mm256_set1_pd(dy));
                _mm256_add_pd(mv4, _mm256_add_pd(x01, y))
            } else {
                mv4
            };
            let forces = _mm256_sub_pd(
                _mm256_sub_pd(
                    _mm256_mul_pd(w, mg4),
                    _mm256_mul_pd(_mm256_permute_pd(grad, 0b0000), tx4),
                ),
                _mm256_mul_pd(_mm256_permute_pd(grad, 0b1111), ty4),
            );
            let wm = _mm256_mul_pd(w, m4);
            let wm = _mm_unpacklo_pd(_mm256_castpd256_pd128(wm), _mm256_extractf128_pd(wm, 1));
            // SAFETY: nodes n and n + 1 are the row's first two entries (consecutive), in
            // the targets and this thread's alone (the contract).
            unsafe {
                add2(mass, n, wm);
                add4(momentum, n, _mm256_mul_pd(w, at));
                add4(force, n, forces);
                if normals {
                    add4(gradient, n, _mm256_mul_pd(m4, grad));
                }
            }
            // Node n + 2.
            let w = _mm_mul_pd(wx2, _mm_set1_pd(wy));
            let grad = _mm_mul_pd(gxwx2, _mm_setr_pd(wy, gy));
            let at = if APIC {
                let y = _mm_mul_pd(half(cy), _mm_set1_pd(dy));
                _mm_add_pd(half(mv4), _mm_add_pd(x2, y))
            } else {
                half(mv4)
            };
            let forces = _mm_sub_pd(
                _mm_sub_pd(
                    _mm_mul_pd(w, mg2),
                    _mm_mul_pd(_mm_unpacklo_pd(grad, grad), tx2),
                ),
                _mm_mul_pd(_mm_unpackhi_pd(grad, grad), ty2),
            );
            // SAFETY: as above, for the row's third entry.
            unsafe {
                mass.add_at(n + 2, _mm_cvtsd_f64(_mm_mul_pd(w, m2)));
                add2(momentum, n + 2, _mm_mul_pd(w, at));
                add2(force, n + 2, forces);
                if normals {
                    add2(gradient, n + 2, _mm_mul_pd(m2, grad));
                }
            }
        }
    }

    /// The low half, `[a, b]` of `[a, b, c, d]`.
    #[inline(always)]
    fn half(v: __m256d) -> __m128d {
        // SAFETY: AVX is part of AVX2, which the caller has.
        unsafe { _mm256_castpd256_pd128(v) }
    }

    /// Adds `v` to the 16 bytes at `slice[i]`: `slice[i]` and `slice[i + 1]` of a slice of
    /// f64, `slice[i]` of a slice of 2-vectors.
    ///
    /// # Safety
    /// As for [`Shared::add_at`], for every element those 16 bytes cover.
    #[inline(always)]
    unsafe fn add2<T: Copy>(target: Shared<T>, i: usize, v: __m128d) {
        // SAFETY: per the contract.
        unsafe {
            let p = target.at(i).cast::<f64>();
            _mm_storeu_pd(p, _mm_add_pd(_mm_loadu_pd(p), v));
        }
    }

    /// `slice[i] += (v[0], v[1]); slice[i + 1] += (v[2], v[3])` for a slice of 2-vectors.
    ///
    /// # Safety
    /// As for [`Shared::add_at`], at `i` and `i + 1`.
    #[inline(always)]
    unsafe fn add4(target: Shared<DVec2>, i: usize, v: __m256d) {
        // SAFETY: per the contract.
        unsafe {
            let p = target.at(i).cast::<f64>();
            _mm256_storeu_pd(p, _mm256_add_pd(_mm256_loadu_pd(p), v));
        }
    }
}

/// The momentum a point hands to the nodes of its footprint: `m v`, plus with APIC the
/// momentum of its affine field, `m C_p d_i` at the node of offset `d_i`.
#[derive(Clone, Copy)]
struct NodeMomentum<const APIC: bool> {
    mv: DVec2,
    /// `m C_p` and the node offsets (zero with FLIP, and not read).
    mc: DMat2,
    dx: [f64; 3],
    dy: [f64; 3],
}

impl<const APIC: bool> NodeMomentum<APIC> {
    /// Point `k`'s, with its affine field if `APIC`.
    #[inline(always)]
    fn of(points: &Points, k: usize, f: &Footprint, grid: &GridGeometry) -> Self {
        let m = points.mass[k];
        let (mc, (dx, dy)) = if APIC {
            (m * points.affine[k], f.offsets(grid, points.position[k]))
        } else {
            (DMat2::ZERO, ([0.0; 3], [0.0; 3]))
        };
        NodeMomentum {
            mv: m * points.velocity[k],
            mc,
            dx,
            dy,
        }
    }

    /// The momentum at entry `(kx, ky)`, before the entry's weight.
    #[inline(always)]
    fn at(&self, kx: usize, ky: usize) -> DVec2 {
        if APIC {
            self.mv + self.mc * DVec2::new(self.dx[kx], self.dy[ky])
        } else {
            self.mv
        }
    }
}
