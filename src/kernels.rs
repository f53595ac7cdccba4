//! Vector kernels: which one this processor runs, the gather over packed nodes, and the
//! per-point passes over four points at a time.
//!
//! The step's per-point work is written per point, and the compiler fills the baseline
//! target's 128-bit registers with a point's two components. Wider registers need the data
//! laid out for them. Two layouts were prototyped on the affine gather (docs/BENCHMARKS.md,
//! "Vector kernels"): four points per 256-bit lane group, bitwise equal to the scalar gather
//! but only 5% faster, its gain eaten by transposing each point's nodes and weights into
//! lanes; and the one kept here, each node's velocity and acceleration packed side by side
//! (`[v_x, v_y, a_x, a_y]`), so that one 256-bit load fetches a footprint entry and one
//! multiply-add pair does the work of four scalar ones (1.3x on the gather, 1.7x fewer
//! instructions).
//!
//! The scatter has a vector kernel too, in `step::scatter_gather::scatter` (it writes through
//! the bands' shared pointers, which live in the step's layer): a footprint row's three
//! nodes are neighbours in memory, so the first two take one 256-bit read-modify-write per
//! nodal array.
//!
//! Lanes over points do pay where a pass reads only each point's own columns, in memory
//! order, and writes only its own results: no transposes of node data. The footprints
//! ([`Kernels::footprints`]) and the cell search ([`Kernels::cells`]) run so here, and the
//! move in `step::scatter_gather::advect` (docs/BENCHMARKS.md, "Lanes over points where a
//! pass is a batch").
//!
//! Every kernel forms each value with the scalar path's operations in its order (the packed
//! gather its sums in the order of [`Footprint::gather`]), with no fused multiply-add, so
//! the state is the same to the last bit whichever kernel runs
//! (`tests/invariants/determinism.rs` runs every shipped scene both ways). The choice is the
//! world's [`Kernels`] resource: the widest the processor has, unless the environment
//! variable `REGOLITH_KERNELS=scalar` asks for the reference path (for comparisons and
//! benchmarks).

use bevy_ecs::prelude::*;
use glam::{DMat2, DVec2};

use crate::grid::{BandLayout, GridField, GridGeometry, NodeMotion};
use crate::shape_functions::{CpdiFixed, Footprint, Gathered, Scheme};

/// Which kernels the step runs. Made only by [`Kernels::widest`] (and so
/// [`Kernels::detect`]) or as [`Kernels::SCALAR`]: the vector kernels' `unsafe` relies on
/// the processor having what they were chosen for, which safe code cannot then break.
#[derive(Resource, Clone, Copy, Debug, PartialEq, Eq)]
pub struct Kernels(Width);

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Width {
    /// The per-point reference path, on any processor.
    Scalar,
    /// The packed gather and the scatter's row kernel, with 256-bit registers (x86-64
    /// with AVX2).
    Avx2,
}

impl Kernels {
    /// The per-point reference path, on any processor.
    pub const SCALAR: Kernels = Kernels(Width::Scalar);

    /// The widest kernels this processor runs, or [`Kernels::SCALAR`] if the environment
    /// variable `REGOLITH_KERNELS` is `scalar`.
    pub fn detect() -> Kernels {
        if std::env::var("REGOLITH_KERNELS").is_ok_and(|v| v == "scalar") {
            return Kernels::SCALAR;
        }
        Kernels::widest()
    }

    /// The widest kernels this processor runs.
    pub fn widest() -> Kernels {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            return Kernels(Width::Avx2);
        }
        Kernels::SCALAR
    }

    /// Whether the AVX2 kernels run: true only on a processor found to have AVX2.
    pub fn avx2(self) -> bool {
        self.0 == Width::Avx2
    }

    /// Whether the gathers read the packed nodes ([`GridField::pack_motion`]).
    pub fn packs(self) -> bool {
        self.avx2()
    }

    /// Every point's footprint: `out[p]` is `Footprint::new::<S>(grid, positions[p],
    /// half_widths[p])` to the bit. With AVX2, fixed-extent CPDI's are built four points at
    /// a time (`avx2_points::cpdi_footprints`); the other schemes, per point.
    pub fn footprints<S: Scheme>(
        self,
        grid: &GridGeometry,
        positions: &[DVec2],
        half_widths: &[f64],
        out: &mut [Footprint],
    ) {
        assert!(positions.len() == out.len() && half_widths.len() == out.len());
        #[cfg(target_arch = "x86_64")]
        if self.avx2() && std::any::TypeId::of::<S>() == std::any::TypeId::of::<CpdiFixed>() {
            // SAFETY: `Kernels::avx2` is true only after the processor was found to have
            // AVX2 (`Kernels::widest`).
            unsafe { avx2_points::cpdi_footprints(grid, positions, half_widths, out) };
            return;
        }
        for ((f, x), &a) in out.iter_mut().zip(positions).zip(half_widths) {
            *f = Footprint::new::<S>(grid, *x, a);
        }
    }

    /// Every point's cell (flat index) and band: `cells[p]` and `bands[p]` as
    /// [`GridGeometry::cell_at`] and [`BandLayout::band_of_row`] give them for
    /// `positions[p]`, four points at a time with AVX2.
    pub fn cells(
        self,
        grid: &GridGeometry,
        layout: &BandLayout,
        positions: &[DVec2],
        cells: &mut [u32],
        bands: &mut [u32],
    ) {
        assert!(positions.len() == cells.len() && positions.len() == bands.len());
        let inv_h = 1.0 / grid.cell_size;
        #[cfg(target_arch = "x86_64")]
        if self.avx2() {
            // SAFETY: `Kernels::avx2` is true only after the processor was found to have
            // AVX2 (`Kernels::widest`).
            unsafe { avx2_points::cells(grid, inv_h, layout, positions, cells, bands) };
            return;
        }
        for ((c, b), x) in cells.iter_mut().zip(bands.iter_mut()).zip(positions) {
            (*c, *b) = cell_and_band(grid, inv_h, layout, *x);
        }
    }

    /// Name for reports (`regolith check`, summary.json's `kernels`).
    pub fn name(self) -> &'static str {
        match self.0 {
            Width::Scalar => "scalar",
            Width::Avx2 => "avx2",
        }
    }
}

/// Where a gather reads its nodes' velocity and acceleration: the field's own arrays, and
/// with vector kernels their packed copy, made this step.
#[derive(Clone, Copy)]
pub struct NodeSource<'a> {
    velocity: &'a [DVec2],
    acceleration: &'a [DVec2],
    packed: Option<(&'a [NodeMotion], Kernels)>,
}

impl<'a> NodeSource<'a> {
    /// The field's velocities and accelerations, read by the scalar gather.
    pub fn unpacked(velocity: &'a [DVec2], acceleration: &'a [DVec2]) -> Self {
        NodeSource {
            velocity,
            acceleration,
            packed: None,
        }
    }

    /// `field`'s nodes, packed if `kernels` read packed nodes; the field must have been
    /// packed since its velocities last changed ([`GridField::pack_motion`]).
    pub fn of(field: &'a GridField, kernels: Kernels) -> Self {
        let packed = kernels.packs().then_some((&field.motion[..], kernels));
        NodeSource {
            packed,
            ..NodeSource::unpacked(&field.velocity, &field.acceleration)
        }
    }

    /// [`Footprint::gather`] over these nodes, with whichever kernel they are for: the same
    /// sums to the last bit.
    #[inline(always)]
    pub fn gather<const AFFINE: bool, const ACCELERATION: bool>(
        &self,
        f: &Footprint,
        dx: &[f64; 3],
        dy: &[f64; 3],
    ) -> Gathered {
        match self.packed {
            #[cfg(target_arch = "x86_64")]
            Some((motion, kernels)) if kernels.avx2() => {
                // SAFETY: `Kernels::avx2` is true only after the processor was found to have
                // AVX2 (`Kernels::widest`).
                unsafe { avx2::gather::<AFFINE, ACCELERATION>(f, motion, dx, dy) }
            }
            _ => f.gather::<AFFINE, ACCELERATION>(self.velocity, self.acceleration, dx, dy),
        }
    }

    /// [`NodeSource::gather`] without APIC's `B`.
    #[inline(always)]
    pub fn gather_velocity<const ACCELERATION: bool>(&self, f: &Footprint) -> Gathered {
        self.gather::<false, ACCELERATION>(f, &[0.0; 3], &[0.0; 3])
    }
}

#[cfg(target_arch = "x86_64")]
mod avx2 {
    use super::*;
    use std::arch::x86_64::*;

    /// The gather of one point over packed nodes, lanes over a node's four numbers.
    /// `[v, a]` weighted by `S` fills one register: lanes 0-1 the velocity's sums, lanes 2-3
    /// the acceleration's; the gradient's and `B`'s two columns share one register each.
    #[target_feature(enable = "avx2")]
    pub(super) fn gather<const AFFINE: bool, const ACCELERATION: bool>(
        f: &Footprint,
        motion: &[NodeMotion],
        dx: &[f64; 3],
        dy: &[f64; 3],
    ) -> Gathered {
        let zero = _mm256_setzero_pd();
        let (mut value, mut gradient, mut b) = (zero, zero, zero);
        let wx = f.wx.map(|w| _mm256_set1_pd(w));
        let gx = f.gx.map(|g| _mm256_set1_pd(g));
        let wxd: [__m256d; 3] = std::array::from_fn(|k| _mm256_set1_pd(f.wx[k] * dx[k]));
        for ky in 0..3 {
            let (mut along, mut along_dx, mut along_x) = (zero, zero, zero);
            for kx in 0..3 {
                let node = &motion[f.node(kx, ky)];
                // SAFETY: `node` is a reference to 32 readable bytes (four f64).
                let q = unsafe { _mm256_loadu_pd(node.0.as_ptr()) };
                along = _mm256_add_pd(along, _mm256_mul_pd(wx[kx], q));
                along_dx = _mm256_add_pd(along_dx, _mm256_mul_pd(gx[kx], q));
                if AFFINE {
                    along_x = _mm256_add_pd(along_x, _mm256_mul_pd(wxd[kx], q));
                }
            }
            let (wy, gy) = (f.wy[ky], f.gy[ky]);
            value = _mm256_add_pd(value, _mm256_mul_pd(_mm256_set1_pd(wy), along));
            // (wy along_dx | gy along), velocity lanes only.
            let columns = _mm256_permute2f128_pd(along_dx, along, 0x20);
            let weights = _mm256_setr_pd(wy, wy, gy, gy);
            gradient = _mm256_add_pd(gradient, _mm256_mul_pd(weights, columns));
            if AFFINE {
                let wyd = wy * dy[ky];
                let columns = _mm256_permute2f128_pd(along_x, along, 0x20);
                let weights = _mm256_setr_pd(wy, wy, wyd, wyd);
                b = _mm256_add_pd(b, _mm256_mul_pd(weights, columns));
            }
        }
        let lanes = |x: __m256d| {
            let mut out = [0.0; 4];
            // SAFETY: `out` holds four f64.
            unsafe { _mm256_storeu_pd(out.as_mut_ptr(), x) };
            out
        };
        let (value, gradient, b) = (lanes(value), lanes(gradient), lanes(b));
        let pair = |l: &[f64; 4], k: usize| DVec2::new(l[k], l[k + 1]);
        Gathered {
            value: pair(&value, 0),
            gradient: DMat2::from_cols(pair(&gradient, 0), pair(&gradient, 2)),
            affine_b: if AFFINE {
                DMat2::from_cols(pair(&b, 0), pair(&b, 2))
            } else {
                DMat2::ZERO
            },
            acceleration: if ACCELERATION {
                pair(&value, 2)
            } else {
                DVec2::ZERO
            },
        }
    }
}

/// The cell (flat index) and band of the point at `x`.
#[inline]
fn cell_and_band(grid: &GridGeometry, inv_h: f64, layout: &BandLayout, x: DVec2) -> (u32, u32) {
    let [i, j] = grid.cell_at(x, inv_h);
    ((j * grid.cells[0] + i) as u32, layout.band_of_row(j))
}

/// The per-point passes, four points at a time: lane `j` of a register is point `j` of a
/// group.
#[cfg(target_arch = "x86_64")]
mod avx2_points {
    use super::*;
    use std::arch::x86_64::*;

    /// One axis of the grid as `CpdiFixed::axis` and the footprint's `entries` see it.
    struct Axis {
        origin: f64,
        cells: f64,
        nodes: i32,
        stride: u32,
        periodic: bool,
    }

    /// One axis of four points' footprints, lane `j` for point `j`: each point's first node
    /// and its three weights and gradients (per metre).
    struct Lanes {
        base: [i32; 4],
        w: [[f64; 4]; 3],
        g: [[f64; 4]; 3],
    }

    impl Axis {
        fn of(grid: &GridGeometry, a: usize) -> Axis {
            let nodes = grid.nodes_along(a);
            Axis {
                origin: grid.origin[a],
                cells: grid.cells[a] as f64,
                nodes: i32::try_from(nodes).unwrap_or(i32::MAX),
                stride: if a == 0 {
                    1
                } else {
                    grid.nodes_along(0) as u32
                },
                periodic: grid.periodic[a],
            }
        }

        /// `CpdiFixed::axis` and the interior branch of `entries` for four points, each
        /// operation the scalar one (no fused multiply-add; `max`/`min` with their operands
        /// placed so that ties and NaN give the scalar result). `None` where a footprint
        /// reaches past an edge of the axis, the caller then building those four points with
        /// the scalar rule. A coordinate the 32-bit truncation cannot hold (NaN, infinite, or
        /// 2^31 cells or more, where the scalar truncates to 64 bits) converts to `i32::MIN`
        /// and is declined with them.
        #[target_feature(enable = "avx2")]
        fn lanes(&self, x: __m256d, alpha: __m256d, inv_h: __m256d) -> Option<Lanes> {
            let zero = _mm256_setzero_pd();
            let one = _mm256_set1_pd(1.0);
            let n = _mm256_set1_pd(self.cells);
            let xi = _mm256_mul_pd(_mm256_sub_pd(x, _mm256_set1_pd(self.origin)), inv_h);
            let (lo, hi) = if self.periodic {
                (_mm256_sub_pd(xi, alpha), _mm256_add_pd(xi, alpha))
            } else {
                // `clamp(0, n)`: max(0, x) is `0 > x ? 0 : x`, min(n, x) is `n < x ? n : x`.
                let xi = _mm256_min_pd(n, _mm256_max_pd(zero, xi));
                (
                    _mm256_max_pd(_mm256_sub_pd(xi, alpha), zero),
                    _mm256_min_pd(_mm256_add_pd(xi, alpha), n),
                )
            };
            let abs = |v: __m256d| _mm256_andnot_pd(_mm256_set1_pd(-0.0), v);
            // `fast_floor`: truncate, and one less where that rounded up. Exact below 2^31
            // cells; beyond, the truncation gives `i32::MIN` and the group is declined below.
            let t = _mm256_cvtepi32_pd(_mm256_cvttpd_epi32(lo));
            let mut base =
                _mm256_blendv_pd(t, _mm256_sub_pd(t, one), _mm256_cmp_pd::<_CMP_GT_OQ>(t, lo));
            if !self.periodic {
                let last = _mm256_sub_pd(n, one);
                base = _mm256_blendv_pd(base, last, _mm256_cmp_pd::<_CMP_GE_OQ>(base, n));
            }
            let mut first = [0i32; 4];
            // SAFETY: `first` holds four i32.
            unsafe { _mm_storeu_si128(first.as_mut_ptr().cast(), _mm256_cvttpd_epi32(base)) };
            if first.iter().any(|&b| b < 0 || b >= self.nodes - 2) {
                return None;
            }
            let inv_width = _mm256_div_pd(one, _mm256_sub_pd(hi, lo));
            let hat = |d: __m256d| _mm256_max_pd(_mm256_sub_pd(one, abs(d)), zero);
            let mut out = Lanes {
                base: first,
                w: [[0.0; 4]; 3],
                g: [[0.0; 4]; 3],
            };
            for k in 0..3 {
                let node = _mm256_add_pd(base, _mm256_set1_pd(k as f64));
                let (nl, nh) = (hat(_mm256_sub_pd(lo, node)), hat(_mm256_sub_pd(hi, node)));
                let w = _mm256_mul_pd(_mm256_set1_pd(0.5), _mm256_add_pd(nl, nh));
                let dw = _mm256_mul_pd(_mm256_sub_pd(nh, nl), inv_width);
                let g = _mm256_mul_pd(dw, inv_h);
                // SAFETY: each destination holds four f64.
                unsafe {
                    _mm256_storeu_pd(out.w[k].as_mut_ptr(), w);
                    _mm256_storeu_pd(out.g[k].as_mut_ptr(), g);
                }
            }
            Some(out)
        }
    }

    /// [`Kernels::footprints`] for `CpdiFixed`, four points per lane group; a group that
    /// [`Axis::lanes`] declines, and the last `len % 4` points, go through the scalar rule.
    #[target_feature(enable = "avx2")]
    pub(super) fn cpdi_footprints(
        grid: &GridGeometry,
        positions: &[DVec2],
        half_widths: &[f64],
        out: &mut [Footprint],
    ) {
        let inv_h = 1.0 / grid.cell_size;
        let (x_axis, y_axis) = (Axis::of(grid, 0), Axis::of(grid, 1));
        let lanes_of = |v: [f64; 4]| _mm256_setr_pd(v[0], v[1], v[2], v[3]);
        let inv = _mm256_set1_pd(inv_h);
        let mut groups = out.chunks_exact_mut(4);
        let mut sources = positions.chunks_exact(4).zip(half_widths.chunks_exact(4));
        for (f, (x, a)) in (&mut groups).zip(&mut sources) {
            let alpha = _mm256_mul_pd(lanes_of([a[0], a[1], a[2], a[3]]), inv);
            let xs = lanes_of([x[0].x, x[1].x, x[2].x, x[3].x]);
            let ys = lanes_of([x[0].y, x[1].y, x[2].y, x[3].y]);
            match (x_axis.lanes(xs, alpha, inv), y_axis.lanes(ys, alpha, inv)) {
                (Some(lx), Some(ly)) => {
                    for (j, f) in f.iter_mut().enumerate() {
                        let (bx, by) = (lx.base[j] as u32, ly.base[j] as u32 * y_axis.stride);
                        let step = y_axis.stride;
                        *f = Footprint {
                            column: [bx, bx + 1, bx + 2],
                            row: [by, by + step, by + 2 * step],
                            wx: [lx.w[0][j], lx.w[1][j], lx.w[2][j]],
                            wy: [ly.w[0][j], ly.w[1][j], ly.w[2][j]],
                            gx: [lx.g[0][j], lx.g[1][j], lx.g[2][j]],
                            gy: [ly.g[0][j], ly.g[1][j], ly.g[2][j]],
                        };
                    }
                }
                _ => {
                    for j in 0..4 {
                        f[j] = Footprint::new::<CpdiFixed>(grid, x[j], a[j]);
                    }
                }
            }
        }
        let rest = positions.len() - positions.len() % 4;
        for (j, f) in groups.into_remainder().iter_mut().enumerate() {
            *f = Footprint::new::<CpdiFixed>(grid, positions[rest + j], half_widths[rest + j]);
        }
    }

    /// [`Kernels::cells`] four points at a time: `GridGeometry::cell_at`'s saturating
    /// truncation and clamp per lane (the minimum with the last cell taken in floating
    /// point, so that a coordinate beyond `i32` or NaN gives what the scalar cast gives),
    /// the bands per point from the rows.
    #[target_feature(enable = "avx2")]
    pub(super) fn cells(
        grid: &GridGeometry,
        inv_h: f64,
        layout: &BandLayout,
        positions: &[DVec2],
        cells: &mut [u32],
        bands: &mut [u32],
    ) {
        let last = |a: usize| (grid.cells[a] - 1).min(i32::MAX as usize) as i32;
        let (last_x, last_y) = (last(0), last(1));
        let inv = _mm256_set1_pd(inv_h);
        let along = |r: __m256d, last: i32| {
            // `r as i32` saturates (NaN to 0); the clamp then keeps [0, last]. Taking the
            // minimum with `last` first (NaN passes through, `min(a, b)` returning `b`)
            // leaves only values the 32-bit truncation holds, or NaN and large negatives,
            // which truncate to `i32::MIN` and are clamped to 0 like the scalar's.
            let r = _mm256_min_pd(_mm256_set1_pd(last as f64), r);
            _mm_max_epi32(_mm256_cvttpd_epi32(r), _mm_setzero_si128())
        };
        let columns = _mm_set1_epi32(grid.cells[0] as i32);
        let mut groups = cells.chunks_exact_mut(4).zip(bands.chunks_exact_mut(4));
        let mut sources = positions.chunks_exact(4);
        for ((c, b), x) in (&mut groups).zip(&mut sources) {
            let rel = |a: usize, origin: f64| {
                let v = _mm256_setr_pd(x[0][a], x[1][a], x[2][a], x[3][a]);
                _mm256_mul_pd(_mm256_sub_pd(v, _mm256_set1_pd(origin)), inv)
            };
            let i = along(rel(0, grid.origin.x), last_x);
            let j = along(rel(1, grid.origin.y), last_y);
            let flat = _mm_add_epi32(_mm_mullo_epi32(j, columns), i);
            let mut rows = [0i32; 4];
            // SAFETY: `c` and `rows` hold four 32-bit integers each.
            unsafe {
                _mm_storeu_si128(c.as_mut_ptr().cast(), flat);
                _mm_storeu_si128(rows.as_mut_ptr().cast(), j);
            }
            for (b, row) in b.iter_mut().zip(rows) {
                *b = layout.band_of_row(row as usize);
            }
        }
        let rest = positions.len() - positions.len() % 4;
        for (k, x) in positions[rest..].iter().enumerate() {
            (cells[rest + k], bands[rest + k]) = super::cell_and_band(grid, inv_h, layout, *x);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::GridGeometry;
    use crate::shape_functions::{CpdiFixed, QuadraticBspline};

    /// A small deterministic generator (no dependency for a test's numbers).
    fn numbers(mut seed: u64) -> impl FnMut() -> f64 {
        move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    fn field(nodes: usize, next: &mut impl FnMut() -> f64) -> GridField {
        let mut field = GridField::new(nodes, 0.0, false);
        for n in 0..nodes {
            field.velocity[n] = DVec2::new(next() - 0.5, next() - 0.5);
            field.acceleration[n] = DVec2::new(next() - 0.5, 100.0 * (next() - 0.5));
        }
        field.pack_motion();
        field
    }

    /// Every kernel this processor runs gives the scalar gather's sums to the bit, for
    /// points anywhere on a grid with one periodic axis (footprints clipped at the walls and
    /// wrapped across the period), for CPDI and B-spline weights, with and without the
    /// affine and acceleration sums.
    #[test]
    fn the_packed_gather_is_the_scalar_gather_to_the_bit() {
        let grid = GridGeometry {
            origin: DVec2::new(-0.1, 0.2),
            cell_size: 0.05,
            cells: [12, 9],
            periodic: [true, false],
        };
        let mut next = numbers(7);
        let field = field(grid.node_count(), &mut next);
        let kernels = Kernels::widest();
        let (scalar, packed) = (
            NodeSource::of(&field, Kernels::SCALAR),
            NodeSource::of(&field, kernels),
        );
        let size = grid.size();
        let mut compared = 0;
        for _ in 0..2000 {
            let x = grid.origin + DVec2::new(next() * size.x, next() * size.y);
            let a = 0.25 * grid.cell_size * next();
            for f in [
                Footprint::new::<CpdiFixed>(&grid, x, a),
                Footprint::new::<QuadraticBspline>(&grid, x, a),
            ] {
                let (dx, dy) = f.offsets(&grid, x);
                let same = |a: Gathered, b: Gathered| format!("{a:?}") == format!("{b:?}");
                assert!(same(
                    scalar.gather::<true, true>(&f, &dx, &dy),
                    packed.gather::<true, true>(&f, &dx, &dy)
                ));
                assert!(same(
                    scalar.gather::<true, false>(&f, &dx, &dy),
                    packed.gather::<true, false>(&f, &dx, &dy)
                ));
                assert!(same(
                    scalar.gather_velocity::<true>(&f),
                    packed.gather_velocity::<true>(&f)
                ));
                assert!(same(
                    scalar.gather_velocity::<false>(&f),
                    packed.gather_velocity::<false>(&f)
                ));
                compared += 1;
            }
        }
        assert_eq!(compared, 4000);
        eprintln!("compared the scalar gather with {:?}", kernels);
    }

    /// Every kernel this processor runs builds the scalar rule's footprints to the bit, for
    /// each scheme, on grids periodic along neither, one or both axes, for points inside,
    /// on and next to the edges (footprints clipped, clamped or wrapped), outside the grid
    /// and at non-finite or huge coordinates, in runs that are not a multiple of four.
    #[test]
    fn the_vector_footprints_are_the_scalar_footprints_to_the_bit() {
        fn compare<S: Scheme>(grid: &GridGeometry, x: &[DVec2], a: &[f64]) -> usize {
            let scalar: Vec<Footprint> = x
                .iter()
                .zip(a)
                .map(|(&x, &a)| Footprint::new::<S>(grid, x, a))
                .collect();
            let mut built = vec![Footprint::default(); x.len()];
            Kernels::widest().footprints::<S>(grid, x, a, &mut built);
            for (p, (s, v)) in scalar.iter().zip(&built).enumerate() {
                assert_eq!(
                    format!("{s:?}"),
                    format!("{v:?}"),
                    "point {p} at {:?}",
                    x[p]
                );
            }
            x.len()
        }
        let mut next = numbers(11);
        let mut compared = 0;
        for periodic in [[false, false], [true, false], [false, true], [true, true]] {
            let grid = GridGeometry {
                origin: DVec2::new(-0.1, 0.2),
                cell_size: 0.05,
                cells: [12, 9],
                periodic,
            };
            let size = grid.size();
            let mut x = Vec::new();
            let mut a = Vec::new();
            for k in 0..4003 {
                // Most points anywhere in the grid; some within a cell of an edge, on a node
                // line or outside the grid.
                let u = DVec2::new(next(), next());
                let along = match k % 5 {
                    0 => u * 0.02,
                    1 => DVec2::ONE - u * 0.02,
                    2 => (u * 12.0).floor() / 12.0,
                    3 => u * 1.4 - DVec2::splat(0.2),
                    _ => u,
                };
                x.push(grid.origin + along * size);
                a.push(0.5 * grid.cell_size * next());
            }
            for (k, odd) in [f64::NAN, f64::INFINITY, -1e12, 3e9]
                .into_iter()
                .enumerate()
            {
                x[40 * k + 1].x = odd;
                x[40 * k + 22].y = odd;
            }
            compared += compare::<CpdiFixed>(&grid, &x, &a);
            compared += compare::<QuadraticBspline>(&grid, &x, &a);
            compared += compare::<crate::shape_functions::Linear>(&grid, &x[..7], &a[..7]);
        }
        assert_eq!(compared, 4 * (2 * 4003 + 7));
    }

    /// Every kernel this processor runs finds the scalar rule's cells and bands, for points
    /// inside, on cell lines, next to and beyond the edges, and at non-finite or huge
    /// coordinates, on grids periodic or not, in runs that are not a multiple of four.
    #[test]
    fn the_vector_cells_are_the_scalar_cells() {
        let mut next = numbers(5);
        for periodic in [[false, false], [true, true]] {
            let grid = GridGeometry {
                origin: DVec2::new(0.3, -0.2),
                cell_size: 0.04,
                cells: [13, 22],
                periodic,
            };
            let layout = BandLayout::of(&grid);
            let size = grid.size();
            let mut x: Vec<DVec2> = (0..2003)
                .map(|k| {
                    let u = DVec2::new(next(), next());
                    let along = match k % 3 {
                        0 => (u * 13.0).floor() / 13.0,
                        1 => u * 1.6 - DVec2::splat(0.3),
                        _ => u,
                    };
                    grid.origin + along * size
                })
                .collect();
            let odd = [
                f64::NAN,
                f64::INFINITY,
                f64::NEG_INFINITY,
                3e9,
                -3e9,
                1e300,
                -0.5,
            ];
            for (k, v) in odd.into_iter().enumerate() {
                x[30 * k + 2].x = v;
                x[30 * k + 13].y = v;
            }
            let n = x.len();
            let (mut cells, mut bands) = (vec![0; n], vec![0; n]);
            Kernels::widest().cells(&grid, &layout, &x, &mut cells, &mut bands);
            let inv_h = 1.0 / grid.cell_size;
            for p in 0..n {
                let expected = cell_and_band(&grid, inv_h, &layout, x[p]);
                assert_eq!((cells[p], bands[p]), expected, "point {p} at {:?}", x[p]);
            }
        }
    }

    /// Packing copies the active nodes and nothing else.
    #[test]
    fn packing_copies_velocity_and_acceleration_of_the_active_nodes() {
        let mut next = numbers(3);
        let mut field = field(40, &mut next);
        field.clear();
        field.will_write(10..20);
        field.clear();
        field.will_write(12..22);
        field.velocity[5] = DVec2::new(9.0, 9.0);
        field.velocity[15] = DVec2::new(1.0, 2.0);
        field.acceleration[15] = DVec2::new(3.0, 4.0);
        field.pack_motion();
        assert_eq!(field.motion[15], NodeMotion([1.0, 2.0, 3.0, 4.0]));
        assert_ne!(field.motion[5].0[0], 9.0);
    }
}
