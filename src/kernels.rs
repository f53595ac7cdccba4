//! Vector kernels: which one this processor runs, and the gather over packed nodes.
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
//! The packed kernel forms every sum in the same order as [`Footprint::gather`], with no
//! fused multiply-add, so the state is the same to the last bit whichever kernel runs
//! (`tests/invariants/determinism.rs` runs every shipped scene both ways). The choice is the
//! world's [`Kernels`] resource: the widest the processor has, unless the environment
//! variable `REGOLITH_KERNELS=scalar` asks for the reference path (for comparisons and
//! benchmarks).

use bevy_ecs::prelude::*;
use glam::{DMat2, DVec2};

use crate::grid::{GridField, NodeMotion};
use crate::shape_functions::{Footprint, Gathered};

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
