//! Shape-function schemes: how a material point's node weights and weight gradients are made.
//!
//! The schemes differ only here; the step is the same for all (SCIENCE.md 3). Both built-in
//! schemes are tensor products of a 1D rule on the bilinear hat `N(x) = max(0, 1 - |x|/h)`:
//!
//! * `Linear`: `S_i = N_i(x_p)` (standard MPM, two nodes per axis).
//! * `CpdiFixed`: the paper's fixed-extent CPDI (uGIMP-like). The point owns a square of
//!   half-width `a` that never changes; `S_i` averages `N_i` over its four corners and the
//!   gradient is the corner difference over the extent. Because the corner box is
//!   axis-aligned, the four-corner average factorises into a product of two 1D averages,
//!   which is what is computed (three nodes per axis when `a <= h/2`).
//!
//! Near a non-periodic domain edge a CPDI extent is clipped to the grid: the 1D rule then
//! averages over `[max(x - a, 0), min(x + a, L)]` and divides by that clipped width. Weights
//! still sum to one and gradients to zero, but the weighted node position is the centre of
//! the clipped extent, up to `a/2` from the point. Linear weights never reach outside.
//! A point that is itself outside the domain is a fault caught by the diagnostics; here its
//! coordinate is clamped so that indexing never leaves the grid.

use glam::DVec2;
use serde::Deserialize;

use crate::grid::GridGeometry;

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
pub trait Scheme: Send + Sync + 'static {
    /// The scheme's name in a scene file.
    const NAME: &'static str;
    /// 1D weights at coordinate `xi` (cell units from the origin) for a point of half-width
    /// `alpha` (cell units) on an axis of `cells` cells.
    fn axis(xi: f64, alpha: f64, cells: usize, periodic: bool) -> AxisWeights;
}

/// The scheme a scene selects.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
pub enum Integration {
    /// Standard MPM: point-evaluated bilinear shape functions.
    Linear,
    /// The paper's fixed-extent CPDI (uGIMP-like) integration.
    #[default]
    CpdiFixed,
}

/// Standard MPM weights.
pub struct Linear;
/// Fixed-extent CPDI weights.
pub struct CpdiFixed;

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
    const NAME: &'static str = "Linear";
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
    const NAME: &'static str = "CpdiFixed";
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
        let width = hi - lo;
        let mut w = [0.0; 3];
        let mut dw = [0.0; 3];
        for k in 0..3 {
            let node = base + k as f64;
            let (nl, nh) = (hat(lo - node), hat(hi - node));
            w[k] = 0.5 * (nl + nh);
            dw[k] = (nh - nl) / width;
        }
        AxisWeights {
            base: base as isize,
            w,
            dw,
        }
    }
}

/// The nodes a point touches, with weights `S_ip` and gradients `grad S_ip` (per metre).
#[derive(Clone, Copy, Debug)]
pub struct Stencil {
    pub len: usize,
    pub node: [usize; 9],
    pub weight: [f64; 9],
    pub gradient: [DVec2; 9],
}

impl Stencil {
    /// Builds the stencil of a point at `x` with half-width `a` (metres).
    #[inline]
    pub fn new<S: Scheme>(grid: &GridGeometry, x: DVec2, a: f64) -> Stencil {
        let rel = (x - grid.origin) / grid.cell_size;
        let alpha = a / grid.cell_size;
        let ax = S::axis(rel.x, alpha, grid.cells[0], grid.periodic[0]);
        let ay = S::axis(rel.y, alpha, grid.cells[1], grid.periodic[1]);
        let inv_h = 1.0 / grid.cell_size;
        let (nx, ny) = (grid.nodes_along(0), grid.nodes_along(1));
        // Node index along each axis, or usize::MAX for an entry with no node or no weight.
        let index = |w: &AxisWeights, nodes: usize, periodic: bool| {
            let mut out = [usize::MAX; 3];
            for (k, slot) in out.iter_mut().enumerate() {
                if (w.w[k] != 0.0 || w.dw[k] != 0.0)
                    && let Some(i) = node_on_axis(w.base + k as isize, nodes, periodic)
                {
                    *slot = i;
                }
            }
            out
        };
        let ix = index(&ax, nx, grid.periodic[0]);
        let iy = index(&ay, ny, grid.periodic[1]);
        let mut s = Stencil {
            len: 0,
            node: [0; 9],
            weight: [0.0; 9],
            gradient: [DVec2::ZERO; 9],
        };
        for (ky, &jy) in iy.iter().enumerate() {
            if jy == usize::MAX {
                continue;
            }
            let row = jy * nx;
            for (kx, &jx) in ix.iter().enumerate() {
                if jx == usize::MAX {
                    continue;
                }
                let w = ax.w[kx] * ay.w[ky];
                let g = DVec2::new(ax.dw[kx] * ay.w[ky], ax.w[kx] * ay.dw[ky]) * inv_h;
                if w == 0.0 && g == DVec2::ZERO {
                    continue;
                }
                s.node[s.len] = row + jx;
                s.weight[s.len] = w;
                s.gradient[s.len] = g;
                s.len += 1;
            }
        }
        s
    }

    /// `(node, weight, gradient)` for each touched node.
    #[inline]
    pub fn iter(&self) -> impl Iterator<Item = (usize, f64, DVec2)> + '_ {
        (0..self.len).map(|k| (self.node[k], self.weight[k], self.gradient[k]))
    }
}

#[inline]
fn node_on_axis(k: isize, nodes: usize, periodic: bool) -> Option<usize> {
    if periodic {
        Some(k.rem_euclid(nodes as isize) as usize)
    } else if k >= 0 && (k as usize) < nodes {
        Some(k as usize)
    } else {
        None
    }
}
