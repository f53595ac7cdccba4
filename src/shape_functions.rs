//! Shape-function schemes: how a material point's node weights and weight gradients are made.
//!
//! The schemes differ only here; the step is the same for all (docs/model.md §3). A scene
//! picks one with its `integration` item (module `integration`). Every
//! built-in scheme is a tensor product of a 1D rule; two are built on the bilinear hat
//! `N(x) = max(0, 1 - |x|/h)`:
//!
//! * `Linear`: `S_i = N_i(x_p)` (standard MPM, two nodes per axis).
//! * `CpdiFixed`: the paper's fixed-extent CPDI (uGIMP-like). The point owns a square of
//!   half-width `a` that never changes; `S_i` averages `N_i` over its four corners and the
//!   gradient is the corner difference over the extent. Because the corner box is
//!   axis-aligned, the four-corner average factorises into a product of two 1D averages,
//!   which is what is computed (three nodes per axis when `a <= h/2`).
//! * `QuadraticBspline`: the quadratic B-spline centred on each node (three nodes per axis,
//!   weights and gradients continuous everywhere, independent of the point's extent). It is
//!   here as the dense-flow comparison of docs/numerics.md ("Quadratic B-splines"), not as
//!   the paper's scheme. Past a non-periodic edge the third node does not exist; its weight
//!   and gradient are folded onto the edge node, which keeps the weights a partition of
//!   unity (not linearly complete within half a cell of the edge).
//!
//! Near a non-periodic domain edge a CPDI extent is clipped to the grid: the 1D rule then
//! averages over `[max(x - a, 0), min(x + a, L)]` and divides by that clipped width. Weights
//! still sum to one and gradients to zero, but the weighted node position is the centre of
//! the clipped extent, up to `a/2` from the point. Linear weights never reach outside.
//! A point that is itself outside the domain is a fault caught by the diagnostics; here its
//! coordinate is clamped so that indexing never leaves the grid.

use glam::{DMat2, DVec2};
use serde::Deserialize;

use crate::grid::GridGeometry;
use crate::registry::Item;

/// Weights of up to three consecutive nodes along one axis, starting at node `base`.
/// `dw` is the derivative with respect to the coordinate in cell units.
#[derive(Clone, Copy, Debug)]
pub struct AxisWeights {
    pub base: isize,
    pub w: [f64; 3],
    pub dw: [f64; 3],
}

/// A way of producing node weights: a type, so the step is monomorphised per scheme
/// (no dynamic dispatch per point).
pub trait Scheme: Item {
    /// Whether the APIC affine matrix `B D^-1` is exactly the velocity gradient for these
    /// weights (true of bilinear weights, Jiang et al. 2015), so the gradient is taken: the
    /// same matrix, without `D`'s ill-conditioning next to a node line.
    const AFFINE_IS_GRADIENT: bool = false;
    /// 1D weights at coordinate `xi` (cell units from the origin) for a point of half-width
    /// `alpha` (cell units) on an axis of `cells` cells.
    fn axis(xi: f64, alpha: f64, cells: usize, periodic: bool) -> AxisWeights;
}

/// Standard MPM: point-evaluated bilinear weights.
#[derive(Clone, Copy, Debug, Deserialize)]
pub struct Linear;
/// The paper's fixed-extent CPDI (uGIMP-like) weights; the default.
#[derive(Clone, Copy, Debug, Deserialize)]
pub struct CpdiFixed;
/// Quadratic B-spline weights (C1 across cells, three nodes per axis).
#[derive(Clone, Copy, Debug, Deserialize)]
pub struct QuadraticBspline;

impl Item for Linear {
    const NAME: &'static str = "Linear";
    const UNIT: bool = true;
}

impl Item for CpdiFixed {
    const NAME: &'static str = "CpdiFixed";
    const UNIT: bool = true;
}

impl Item for QuadraticBspline {
    const NAME: &'static str = "QuadraticBspline";
    const UNIT: bool = true;
}

#[inline]
fn hat(x: f64) -> f64 {
    (1.0 - x.abs()).max(0.0)
}

/// `x.floor()` for the grid coordinates the schemes see (|x| < 2^52). `f64::floor` is a
/// library call on the baseline x86-64 target (no SSE4.1 rounding instruction), and it was
/// 6% of a step; truncation plus a correction compiles to a few instructions.
#[inline]
pub fn fast_floor(x: f64) -> f64 {
    let t = x as i64 as f64;
    if t > x { t - 1.0 } else { t }
}

impl Scheme for Linear {
    const AFFINE_IS_GRADIENT: bool = true;
    #[inline]
    fn axis(xi: f64, _alpha: f64, cells: usize, periodic: bool) -> AxisWeights {
        let n = cells as f64;
        let xi = if periodic { xi } else { xi.clamp(0.0, n) };
        let mut base = fast_floor(xi);
        if !periodic && base >= n {
            base = n - 1.0;
        }
        let f = xi - base;
        AxisWeights {
            base: base as isize,
            w: [1.0 - f, f, 0.0],
            dw: [-1.0, 1.0, 0.0],
        }
    }
}

impl Scheme for CpdiFixed {
    #[inline]
    fn axis(xi: f64, alpha: f64, cells: usize, periodic: bool) -> AxisWeights {
        let n = cells as f64;
        let (lo, hi) = if periodic {
            (xi - alpha, xi + alpha)
        } else {
            let xi = xi.clamp(0.0, n);
            ((xi - alpha).max(0.0), (xi + alpha).min(n))
        };
        let mut base = fast_floor(lo);
        if !periodic && base >= n {
            base = n - 1.0;
        }
        let inv_width = 1.0 / (hi - lo);
        let mut w = [0.0; 3];
        let mut dw = [0.0; 3];
        for k in 0..3 {
            let node = base + k as f64;
            let (nl, nh) = (hat(lo - node), hat(hi - node));
            w[k] = 0.5 * (nl + nh);
            dw[k] = (nh - nl) * inv_width;
        }
        AxisWeights {
            base: base as isize,
            w,
            dw,
        }
    }
}

impl Scheme for QuadraticBspline {
    #[inline]
    fn axis(xi: f64, _alpha: f64, cells: usize, periodic: bool) -> AxisWeights {
        let n = cells as f64;
        let xi = if periodic { xi } else { xi.clamp(0.0, n) };
        let base = fast_floor(xi - 0.5);
        let f = xi - base;
        let mut w = [
            0.5 * (1.5 - f) * (1.5 - f),
            0.75 - (f - 1.0) * (f - 1.0),
            0.5 * (f - 0.5) * (f - 0.5),
        ];
        let mut dw = [f - 1.5, -2.0 * (f - 1.0), f - 0.5];
        if !periodic {
            // A node past the edge folds onto the edge node.
            if base < 0.0 {
                w[1] += w[0];
                dw[1] += dw[0];
                w[0] = 0.0;
                dw[0] = 0.0;
            }
            if base + 2.0 > n {
                w[1] += w[2];
                dw[1] += dw[2];
                w[2] = 0.0;
                dw[2] = 0.0;
            }
        }
        AxisWeights {
            base: base as isize,
            w,
            dw,
        }
    }
}

/// The 3 x 3 nodes a point touches and their weights, as the tensor product of the two 1D
/// rules: node `(kx, ky)` is `column[kx] + row[ky]` with weight `wx[kx] wy[ky]` and gradient
/// `(gx[kx] wy[ky], wx[kx] gy[ky])`. All nine entries are always used: an entry with no node
/// on the grid (past a non-periodic edge) has zero weight and gradient and points at the
/// nearest node of its own row and column, so loops over a footprint have no branches and a
/// band scatter never writes outside its own rows (`step::bands`).
#[derive(Clone, Copy, Debug, Default)]
pub struct Footprint {
    /// Node column of each x entry.
    pub column: [u32; 3],
    /// Flat index of the first node of each y entry's row.
    pub row: [u32; 3],
    pub wx: [f64; 3],
    pub wy: [f64; 3],
    /// `d wx / dx` and `d wy / dy`, per metre.
    pub gx: [f64; 3],
    pub gy: [f64; 3],
}

impl Footprint {
    /// Bytes per point of a cached footprint (for memory estimates).
    pub const BYTES: usize = std::mem::size_of::<Footprint>();

    /// The footprint of a point at `x` with half-width `a` (metres).
    #[inline]
    pub fn new<S: Scheme>(grid: &GridGeometry, x: DVec2, a: f64) -> Footprint {
        let inv_h = 1.0 / grid.cell_size;
        let rel = (x - grid.origin) * inv_h;
        let alpha = a * inv_h;
        let ax = S::axis(rel.x, alpha, grid.cells[0], grid.periodic[0]);
        let ay = S::axis(rel.y, alpha, grid.cells[1], grid.periodic[1]);
        let nx = grid.nodes_along(0);
        let (column, wx, gx) = entries(ax, inv_h, nx, grid.periodic[0], 1);
        let (row, wy, gy) = entries(ay, inv_h, grid.nodes_along(1), grid.periodic[1], nx);
        Footprint {
            column,
            row,
            wx,
            wy,
            gx,
            gy,
        }
    }

    /// Flat index of node `(kx, ky)`.
    #[inline]
    pub fn node(&self, kx: usize, ky: usize) -> usize {
        (self.column[kx] + self.row[ky]) as usize
    }

    /// Calls `visit(node, weight, gradient)` for all nine entries (zero entries included),
    /// row by row: the scatter's inner loop, written out so that it compiles to straight
    /// code.
    #[inline(always)]
    pub fn for_each_entry(&self, mut visit: impl FnMut(usize, f64, DVec2)) {
        self.for_each_indexed(|_, _, n, w, grad| visit(n, w, grad));
    }

    /// As [`Footprint::for_each_entry`], also passing the entry's `(kx, ky)`.
    #[inline(always)]
    pub fn for_each_indexed(&self, mut visit: impl FnMut(usize, usize, usize, f64, DVec2)) {
        for ky in 0..3 {
            for kx in 0..3 {
                let w = self.wx[kx] * self.wy[ky];
                let grad = DVec2::new(self.gx[kx] * self.wy[ky], self.wx[kx] * self.gy[ky]);
                visit(kx, ky, self.node(kx, ky), w, grad);
            }
        }
    }

    /// Node position minus the point's weighted centre `sum_i S_i x_i`, per entry:
    /// `(dx[kx], dy[ky])` in metres, the nearest image on a periodic axis. Entries past a
    /// non-periodic edge get the offset of the node they point at; their weight is zero.
    ///
    /// The centre is the point's position except where CPDI clips its extent at a wall
    /// (docs/numerics.md, "CPDI near the domain edge"); measuring from it keeps
    /// `sum_i S_i d_i = 0`, without which APIC's affine momentum `m C_p sum_i S_i d_i` would
    /// be created at every step next to a wall (docs/numerics.md, "APIC next to a wall").
    #[inline]
    pub fn offsets(&self, grid: &GridGeometry, x: DVec2) -> ([f64; 3], [f64; 3]) {
        let h = grid.cell_size;
        let nx = grid.nodes_along(0) as u32;
        let image = |d: f64, a: usize| {
            if !grid.periodic[a] {
                return d;
            }
            let span = grid.cells[a] as f64 * h;
            if d > 0.5 * span {
                d - span
            } else if d < -0.5 * span {
                d + span
            } else {
                d
            }
        };
        let rel = x - grid.origin;
        let mut dx = per_entry(|k| image(self.column[k] as f64 * h - rel.x, 0));
        // Row numbers from the rows' flat starts: one division, and another only where a
        // row wraps or is clamped at an edge (a division per entry was most of this call).
        let first = self.row[0] / nx;
        let row_number = |k: usize| {
            if self.row[k] == self.row[0] + k as u32 * nx {
                first + k as u32
            } else {
                self.row[k] / nx
            }
        };
        let mut dy = per_entry(|k| image(row_number(k) as f64 * h - rel.y, 1));
        let centre = |d: &[f64; 3], w: &[f64; 3]| (0..3).map(|k| w[k] * d[k]).sum::<f64>();
        let (cx, cy) = (centre(&dx, &self.wx), centre(&dy, &self.wy));
        dx.iter_mut().for_each(|d| *d -= cx);
        dy.iter_mut().for_each(|d| *d -= cy);
        (dx, dy)
    }

    /// The APIC inertia-like matrix `D = sum_i S_i d_i d_i^T` of the point (`d_i` the node
    /// offsets), from the two 1D rules: the weights factorise, so the diagonal entries are
    /// 1D sums and the off-diagonal one a product of 1D first moments.
    #[inline]
    pub fn affine_inertia(&self, dx: &[f64; 3], dy: &[f64; 3]) -> DMat2 {
        let (mut xx, mut yy, mut x1, mut y1) = (0.0, 0.0, 0.0, 0.0);
        for k in 0..3 {
            xx += self.wx[k] * dx[k] * dx[k];
            yy += self.wy[k] * dy[k] * dy[k];
            x1 += self.wx[k] * dx[k];
            y1 += self.wy[k] * dy[k];
        }
        let xy = x1 * y1;
        DMat2::from_cols(DVec2::new(xx, xy), DVec2::new(xy, yy))
    }

    /// The gather's sums in one pass over the nodes: `sum_i S_i v_i`, `sum_i v_i (outer)
    /// grad S_i`, with `AFFINE` the APIC `B = sum_i S_i v_i (outer) d_i` (offsets `dx`,
    /// `dy`), and with `ACCELERATION` `sum_i S_i a_i`. Each sum is formed in the same order
    /// as by [`Footprint::interpolate`], so fusing them changes no bit.
    #[inline(always)]
    #[allow(clippy::needless_range_loop)] // kx and ky index five arrays and the node
    pub fn gather<const AFFINE: bool, const ACCELERATION: bool>(
        &self,
        velocity: &[DVec2],
        acceleration: &[DVec2],
        dx: &[f64; 3],
        dy: &[f64; 3],
    ) -> Gathered {
        let mut out = Gathered::default();
        let (mut gx, mut gy, mut bx, mut by) = (DVec2::ZERO, DVec2::ZERO, DVec2::ZERO, DVec2::ZERO);
        for ky in 0..3 {
            let (mut along, mut along_dx, mut along_x, mut along_a) =
                (DVec2::ZERO, DVec2::ZERO, DVec2::ZERO, DVec2::ZERO);
            for kx in 0..3 {
                let n = self.node(kx, ky);
                let v = velocity[n];
                along += self.wx[kx] * v;
                along_dx += self.gx[kx] * v;
                if AFFINE {
                    along_x += (self.wx[kx] * dx[kx]) * v;
                }
                if ACCELERATION {
                    along_a += self.wx[kx] * acceleration[n];
                }
            }
            out.value += self.wy[ky] * along;
            gx += self.wy[ky] * along_dx;
            gy += self.gy[ky] * along;
            if AFFINE {
                bx += self.wy[ky] * along_x;
                by += (self.wy[ky] * dy[ky]) * along;
            }
            if ACCELERATION {
                out.acceleration += self.wy[ky] * along_a;
            }
        }
        out.gradient = DMat2::from_cols(gx, gy);
        out.affine_b = DMat2::from_cols(bx, by);
        out
    }

    /// `(node, weight, gradient)` for all nine entries, in `for_each_entry`'s order.
    pub fn iter(&self) -> impl Iterator<Item = (usize, f64, DVec2)> {
        let mut entries = [(0, 0.0, DVec2::ZERO); 9];
        let mut k = 0;
        self.for_each_entry(|n, w, g| {
            entries[k] = (n, w, g);
            k += 1;
        });
        entries.into_iter()
    }

    /// `sum_i S_i u_i`.
    #[inline]
    pub fn interpolate(&self, u: &[DVec2]) -> DVec2 {
        self.gather_velocity::<false>(u, &[]).value
    }

    /// `sum_i S_i u_i` and `sum_i u_i (outer) grad S_i` in one pass over the nodes.
    #[inline]
    pub fn interpolate_with_gradient(&self, u: &[DVec2]) -> (DVec2, DMat2) {
        let g = self.gather_velocity::<false>(u, &[]);
        (g.value, g.gradient)
    }

    /// [`Footprint::gather`] without APIC's `B`: the velocity and its gradient, and with
    /// `ACCELERATION` the acceleration.
    #[inline(always)]
    pub fn gather_velocity<const ACCELERATION: bool>(
        &self,
        velocity: &[DVec2],
        acceleration: &[DVec2],
    ) -> Gathered {
        self.gather::<false, ACCELERATION>(velocity, acceleration, &[0.0; 3], &[0.0; 3])
    }
}

/// What [`Footprint::gather`] sums at a point.
#[derive(Clone, Copy, Debug, Default)]
pub struct Gathered {
    /// `sum_i S_i v_i`.
    pub value: DVec2,
    /// `sum_i v_i (outer) grad S_i`.
    pub gradient: DMat2,
    /// APIC's `B = sum_i S_i v_i (outer) d_i` (zero unless asked for).
    pub affine_b: DMat2,
    /// `sum_i S_i a_i` (zero unless asked for).
    pub acceleration: DVec2,
}

/// `[entry(0), entry(1), entry(2)]`, written out: `[T; 3]::map` was not inlined into the
/// footprint's loops and took 4.6% of a step in calls of its own.
#[inline(always)]
fn per_entry<T>(entry: impl Fn(usize) -> T) -> [T; 3] {
    [entry(0), entry(1), entry(2)]
}

/// One axis of a footprint: each entry's flat index (node number times `stride`), weight and
/// gradient per metre. The fields are built as values and the footprint assembled once: a
/// footprint made with defaults and then filled in was written twice (4% of a step).
#[inline(always)]
fn entries(
    axis: AxisWeights,
    inv_h: f64,
    nodes: usize,
    periodic: bool,
    stride: usize,
) -> ([u32; 3], [f64; 3], [f64; 3]) {
    let mut w = axis.w;
    let mut g = per_entry(|k| axis.dw[k] * inv_h);
    let index = if axis.base >= 0 && (axis.base as usize) + 2 < nodes {
        let (b, step) = ((axis.base as usize * stride) as u32, stride as u32);
        [b, b + step, b + 2 * step]
    } else {
        let nodes = edge_axis(&mut w, &mut g, axis.base, nodes, periodic);
        per_entry(|k| nodes[k] * stride as u32)
    };
    (index, w, g)
}

/// Node indices along one axis for a footprint that reaches an edge: wrapped on a periodic
/// axis; past a non-periodic edge the entry's weight and gradient are zeroed (they already
/// are for both built-in schemes) and its index clamped onto the axis.
fn edge_axis(
    w: &mut [f64; 3],
    g: &mut [f64; 3],
    base: isize,
    nodes: usize,
    periodic: bool,
) -> [u32; 3] {
    let mut out = [0; 3];
    for k in 0..3 {
        let i = base + k as isize;
        out[k] = if periodic {
            i.rem_euclid(nodes as isize) as u32
        } else if i >= 0 && (i as usize) < nodes {
            i as u32
        } else {
            w[k] = 0.0;
            g[k] = 0.0;
            i.clamp(0, nodes as isize - 1) as u32
        };
    }
    out
}
