//! Shape-function schemes: partition of unity, zero-sum gradients, linear completeness, and
//! the documented clipping at the domain edge (CPDI) and folding at it (B-spline).

use proptest::prelude::*;
use regolith::glam::{DMat2, DVec2};
use regolith::grid::GridGeometry;
use regolith::shape_functions::{CpdiFixed, Footprint, Linear, QuadraticBspline, Scheme};

fn grid(periodic: [bool; 2]) -> GridGeometry {
    GridGeometry {
        origin: DVec2::new(-0.3, 0.2),
        cell_size: 0.05,
        cells: [20, 12],
        periodic,
    }
}

/// Node position of a flat index (unwrapped for non-periodic grids).
fn node_pos(g: &GridGeometry, n: usize) -> DVec2 {
    let nx = g.nodes_along(0);
    g.node_position(n % nx, n / nx)
}

struct Sums {
    weight: f64,
    gradient: DVec2,
    position: DVec2,
    position_gradient: DMat2,
}

fn sums<S: Scheme>(g: &GridGeometry, x: DVec2, a: f64) -> Sums {
    let st = Footprint::new::<S>(g, x, a);
    let mut s = Sums {
        weight: 0.0,
        gradient: DVec2::ZERO,
        position: DVec2::ZERO,
        position_gradient: DMat2::ZERO,
    };
    for (n, w, grad) in st.iter() {
        let xi = node_pos(g, n);
        s.weight += w;
        s.gradient += grad;
        s.position += w * xi;
        s.position_gradient += DMat2::from_cols(xi * grad.x, xi * grad.y);
    }
    s
}

fn check_completeness<S: Scheme>(g: &GridGeometry, x: DVec2, a: f64) -> Result<(), TestCaseError> {
    let s = sums::<S>(g, x, a);
    prop_assert!(
        (s.weight - 1.0).abs() < 1e-14,
        "{}: sum S = {}",
        S::NAME,
        s.weight
    );
    prop_assert!(
        s.gradient.length() < 1e-12,
        "{}: sum grad S = {}",
        S::NAME,
        s.gradient
    );
    prop_assert!(
        (s.position - x).length() < 1e-14,
        "{}: sum S x_i = {} at {x}",
        S::NAME,
        s.position
    );
    let id = s.position_gradient - DMat2::IDENTITY;
    prop_assert!(
        id.x_axis.length() + id.y_axis.length() < 1e-12,
        "{}: sum x_i grad S = {:?}",
        S::NAME,
        s.position_gradient
    );
    Ok(())
}

proptest! {
    #![proptest_config(crate::property::config(5000, file!()))]

    /// Away from the edges every scheme is a partition of unity with zero-sum gradients and
    /// reproduce linear fields: sum S x_i = x_p and sum x_i (outer) grad S = 1.
    #[test]
    fn interior_points_are_complete(fx in 0.0f64..1.0, fy in 0.0f64..1.0, ppc in 1usize..6) {
        let g = grid([false, false]);
        let a = 0.5 * g.cell_size / ppc as f64;
        // at least a + one cell from every edge
        let x = g.origin + DVec2::new(0.06 + fx * 0.88, 0.06 + fy * 0.48);
        check_completeness::<Linear>(&g, x, a)?;
        check_completeness::<CpdiFixed>(&g, x, a)?;
        check_completeness::<QuadraticBspline>(&g, x, a)?;
    }

    /// On periodic axes the same holds everywhere, the wrapped nodes standing in for the
    /// missing ones (positions compared modulo the period).
    #[test]
    fn periodic_points_are_a_partition_of_unity(fx in 0.0f64..1.0, fy in 0.0f64..1.0) {
        let g = grid([true, true]);
        let x = g.origin + DVec2::new(fx, fy) * g.size();
        for s in [
            sums::<Linear>(&g, x, 0.0125),
            sums::<CpdiFixed>(&g, x, 0.0125),
            sums::<QuadraticBspline>(&g, x, 0.0125),
        ] {
            prop_assert!((s.weight - 1.0).abs() < 1e-14);
            prop_assert!(s.gradient.length() < 1e-12);
        }
    }

    /// Within `a` of a non-periodic edge the CPDI extent is clipped to the grid: the weights
    /// still sum to one and the gradients to zero, and the weighted node position is the centre
    /// of the clipped extent (docs/numerics.md).
    #[test]
    fn clipped_extents_keep_unity(fx in 0.0f64..1.0, side in 0usize..4) {
        let g = grid([false, false]);
        let a = 0.02;
        let (lo, hi) = (g.origin, g.max());
        let along = fx;
        let depth = fx * a;
        let x = match side {
            0 => DVec2::new(lo.x + depth, lo.y + 0.1 + along * 0.3),
            1 => DVec2::new(hi.x - depth, lo.y + 0.1 + along * 0.3),
            2 => DVec2::new(lo.x + 0.1 + along * 0.7, lo.y + depth),
            _ => DVec2::new(lo.x + 0.1 + along * 0.7, hi.y - depth),
        };
        let s = sums::<CpdiFixed>(&g, x, a);
        prop_assert!((s.weight - 1.0).abs() < 1e-14);
        prop_assert!(s.gradient.length() < 1e-12);
        let clip = |v: f64, l: f64, h: f64| 0.5 * ((v - a).max(l) + (v + a).min(h));
        let centre = DVec2::new(clip(x.x, lo.x, hi.x), clip(x.y, lo.y, hi.y));
        prop_assert!((s.position - centre).length() < 1e-14, "{} vs {centre}", s.position);
        let l = sums::<Linear>(&g, x, a);
        prop_assert!((l.weight - 1.0).abs() < 1e-14 && (l.position - x).length() < 1e-14);
    }

    /// Within half a cell of a non-periodic edge a B-spline point's third node would lie
    /// past the edge; its weight is folded onto the edge node, so the weights still sum to
    /// one and the gradients to zero.
    #[test]
    fn folded_bspline_weights_keep_unity(fx in 0.0f64..1.0, side in 0usize..4) {
        let g = grid([false, false]);
        let (lo, hi) = (g.origin, g.max());
        let depth = fx * 0.5 * g.cell_size;
        let x = match side {
            0 => DVec2::new(lo.x + depth, lo.y + 0.1 + fx * 0.3),
            1 => DVec2::new(hi.x - depth, lo.y + 0.1 + fx * 0.3),
            2 => DVec2::new(lo.x + 0.1 + fx * 0.7, lo.y + depth),
            _ => DVec2::new(lo.x + 0.1 + fx * 0.7, hi.y - depth),
        };
        let s = sums::<QuadraticBspline>(&g, x, 0.0);
        prop_assert!((s.weight - 1.0).abs() < 1e-14, "sum S = {}", s.weight);
        prop_assert!(s.gradient.length() < 1e-12, "sum grad S = {}", s.gradient);
    }
}

/// CPDI's and the B-spline's gradients are continuous across a node (the point of both
/// schemes); linear's jumps.
#[test]
fn cpdi_gradient_is_continuous_across_a_node() {
    let g = grid([false, false]);
    let node = g.node_position(8, 5);
    let eps = 1e-9;
    let grad_of = |x: DVec2, scheme: &str| {
        let st = match scheme {
            "CpdiFixed" => Footprint::new::<CpdiFixed>(&g, x, 0.0125),
            "QuadraticBspline" => Footprint::new::<QuadraticBspline>(&g, x, 0.0125),
            _ => Footprint::new::<Linear>(&g, x, 0.0125),
        };
        st.iter()
            .find(|(n, _, _)| *n == g.index(8, 5))
            .map(|(_, _, gr)| gr.x)
            .unwrap_or(0.0)
    };
    let at = |dx: f64| node + DVec2::new(dx, 0.013);
    let jump = |scheme| (grad_of(at(eps), scheme) - grad_of(at(-eps), scheme)).abs();
    let (cpdi_jump, linear_jump) = (jump("CpdiFixed"), jump("Linear"));
    // Across a cell's midpoint, where the B-spline changes its nodes, too.
    let mid = |dx: f64| node + DVec2::new(0.5 * g.cell_size + dx, 0.013);
    let bspline_jump = (grad_of(at(eps), "QuadraticBspline")
        - grad_of(at(-eps), "QuadraticBspline"))
    .abs()
    .max((grad_of(mid(eps), "QuadraticBspline") - grad_of(mid(-eps), "QuadraticBspline")).abs());
    // Its second derivative is bounded by 2/h^2 = 800 /m^2 per axis: ~2e-6 across 2e-9 m.
    assert!(
        bspline_jump < 1e-4,
        "B-spline gradient jumps by {bspline_jump}"
    );
    // Continuous: across 2e-9 m the CPDI gradient changes by its slope (~1/(2 a h^2) =
    // 1.6e4 /m^2) times the distance, ~3e-5; the linear one jumps by 2/h = 40 /m.
    assert!(cpdi_jump < 1e-4, "CPDI gradient jumps by {cpdi_jump}");
    assert!(
        linear_jump > 1.0,
        "linear gradient should jump, got {linear_jump}"
    );
}

proptest! {
    #![proptest_config(crate::property::config(3000, file!()))]

    /// Every footprint entry, zero or not, names a node on the grid in the rows from one below
    /// the point's cell to two above (what the lock-free band scatter relies on). Entries
    /// clamped at a non-periodic edge carry no weight: the unity tests above include them.
    #[test]
    fn footprints_stay_in_their_rows(fx in -0.01f64..1.01, fy in -0.01f64..1.01, ppc in 1usize..4) {
        let g = grid([false, false]);
        let a = 0.5 * g.cell_size / ppc as f64;
        let x = g.origin + DVec2::new(fx, fy) * g.size();
        let nx = g.nodes_along(0);
        let row = (g.cell_of(x) / g.cells[0]) as isize;
        for f in [
            Footprint::new::<Linear>(&g, x, a),
            Footprint::new::<CpdiFixed>(&g, x, a),
            Footprint::new::<QuadraticBspline>(&g, x, a),
        ] {
            for (n, w, grad) in f.iter() {
                prop_assert!(n < g.node_count(), "node {n} off the grid");
                let r = (n / nx) as isize;
                prop_assert!((row - 1..=row + 2).contains(&r), "row {r} for a point in cell row {row}");
                prop_assert!(w.is_finite() && grad.is_finite());
            }
        }
    }
}
