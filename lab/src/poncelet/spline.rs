//! The not-a-knot cubic spline each run's depth is interpolated with, and the tridiagonal
//! solve it needs.

/// An interpolating cubic spline through `(t_i, y_i)` (strictly increasing `t`) with
/// not-a-knot ends: the third derivative is continuous at the second and the next-to-last
/// knot. Unlike a natural spline it does not force `y'' = 0` at the ends, which matters
/// here: the deceleration is largest right at first contact.
#[derive(Clone, Debug)]
pub struct CubicSpline {
    t: Vec<f64>,
    y: Vec<f64>,
    /// Second derivatives at the knots.
    m: Vec<f64>,
}

impl CubicSpline {
    /// The spline; `None` with fewer than 4 knots or `t` not strictly increasing.
    pub fn not_a_knot(t: &[f64], y: &[f64]) -> Option<CubicSpline> {
        let n = t.len();
        if n < 4 || y.len() != n || !t.windows(2).all(|w| w[1] > w[0]) {
            return None;
        }
        let h: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
        // Rows i = 1..n-2 of h_{i-1} m_{i-1} + 2 (h_{i-1} + h_i) m_i + h_i m_{i+1} = r_i,
        // with m_0 and m_{n-1} eliminated through the not-a-knot conditions.
        let k = n - 2;
        let (mut sub, mut diag, mut sup, mut rhs) =
            (vec![0.0; k], vec![0.0; k], vec![0.0; k], vec![0.0; k]);
        for r in 0..k {
            let i = r + 1;
            sub[r] = h[i - 1];
            diag[r] = 2.0 * (h[i - 1] + h[i]);
            sup[r] = h[i];
            rhs[r] = 6.0 * ((y[i + 1] - y[i]) / h[i] - (y[i] - y[i - 1]) / h[i - 1]);
        }
        // m_0 = m_1 (1 + h0/h1) - m_2 h0/h1, and symmetrically at the far end.
        let (h0, h1) = (h[0], h[1]);
        diag[0] += h0 * (1.0 + h0 / h1);
        sup[0] -= h0 * h0 / h1;
        let (ha, hb) = (h[n - 3], h[n - 2]);
        diag[k - 1] += hb * (1.0 + hb / ha);
        sub[k - 1] -= hb * hb / ha;
        let inner = solve_tridiagonal(&sub, &mut diag, &sup, &mut rhs);
        let mut m = vec![0.0; n];
        m[1..n - 1].copy_from_slice(&inner);
        m[0] = m[1] * (1.0 + h0 / h1) - m[2] * h0 / h1;
        m[n - 1] = m[n - 2] * (1.0 + hb / ha) - m[n - 3] * hb / ha;
        Some(CubicSpline {
            t: t.to_vec(),
            y: y.to_vec(),
            m,
        })
    }

    /// The interval `[t_i, t_i+1]` holding `x` (clamped to the ends).
    fn interval(&self, x: f64) -> usize {
        let i = self.t.partition_point(|&ti| ti <= x);
        i.clamp(1, self.t.len() - 1) - 1
    }

    /// Value, first and second derivative at `x`.
    pub fn eval(&self, x: f64) -> (f64, f64, f64) {
        let i = self.interval(x);
        let h = self.t[i + 1] - self.t[i];
        let (a, b) = ((self.t[i + 1] - x) / h, (x - self.t[i]) / h);
        let (m0, m1) = (self.m[i], self.m[i + 1]);
        let (y0, y1) = (self.y[i], self.y[i + 1]);
        let value = a * y0 + b * y1 + ((a * a * a - a) * m0 + (b * b * b - b) * m1) * h * h / 6.0;
        let slope =
            (y1 - y0) / h - (3.0 * a * a - 1.0) * h * m0 / 6.0 + (3.0 * b * b - 1.0) * h * m1 / 6.0;
        let curvature = a * m0 + b * m1;
        (value, slope, curvature)
    }

    /// The first time the spline reaches `level` within `[lo, hi]` over which it rises (the
    /// caller guarantees `s(lo) <= level <= s(hi)`), by bisection.
    pub fn first_reach(&self, level: f64, lo: f64, hi: f64) -> f64 {
        let (mut lo, mut hi) = (lo, hi);
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if self.eval(mid).0 < level {
                lo = mid;
            } else {
                hi = mid;
            }
            if hi - lo <= 1e-15 * hi.abs().max(1.0) {
                break;
            }
        }
        0.5 * (lo + hi)
    }
}

/// Solves a tridiagonal system (Thomas algorithm; `diag` and `rhs` are overwritten).
fn solve_tridiagonal(sub: &[f64], diag: &mut [f64], sup: &[f64], rhs: &mut [f64]) -> Vec<f64> {
    let n = diag.len();
    for i in 1..n {
        let w = sub[i] / diag[i - 1];
        diag[i] -= w * sup[i - 1];
        rhs[i] -= w * rhs[i - 1];
    }
    let mut x = vec![0.0; n];
    x[n - 1] = rhs[n - 1] / diag[n - 1];
    for i in (0..n - 1).rev() {
        x[i] = (rhs[i] - sup[i] * x[i + 1]) / diag[i];
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spline_reproduces_cubics_exactly_and_curves_closely() {
        // Not-a-knot splines are exact for any cubic, ends included (a natural spline is
        // not: it forces y'' = 0 there), on uneven knots too; 4 knots is the smallest case.
        let cubic = |x: f64| 2.0 - 3.0 * x + 0.5 * x * x - 4.0 * x * x * x;
        let slope = |x: f64| -3.0 + x - 12.0 * x * x;
        let curvature = |x: f64| 1.0 - 24.0 * x;
        for knots in [4usize, 5, 21] {
            let t: Vec<f64> = (0..knots)
                .map(|k| (k as f64 / (knots - 1) as f64).powf(1.3))
                .collect();
            let y: Vec<f64> = t.iter().map(|&x| cubic(x)).collect();
            let s = CubicSpline::not_a_knot(&t, &y).unwrap();
            for x in [0.0, 0.13, 0.5, 0.97, 1.0] {
                let (v, d, c) = s.eval(x);
                assert!((v - cubic(x)).abs() < 1e-11, "{knots} knots: value at {x}");
                assert!((d - slope(x)).abs() < 1e-9, "{knots} knots: slope at {x}");
                assert!(
                    (c - curvature(x)).abs() < 1e-8,
                    "{knots} knots: curvature at {x}"
                );
            }
        }
        let t: Vec<f64> = (0..=20).map(|k| k as f64 * 0.05).collect();
        let y: Vec<f64> = t.iter().map(|&x| x.sin()).collect();
        let s = CubicSpline::not_a_knot(&t, &y).unwrap();
        for x in [0.0, 0.5, 1.0] {
            let (v, d, c) = s.eval(x);
            assert!((v - x.sin()).abs() < 1e-6);
            assert!((d - x.cos()).abs() < 1e-4);
            assert!((c + x.sin()).abs() < 1e-2, "curvature at {x}");
        }
    }

    #[test]
    fn spline_refuses_bad_knots() {
        let s = |t: &[f64]| CubicSpline::not_a_knot(t, &vec![1.0; t.len()]);
        assert!(s(&[0.0, 1.0, 2.0]).is_none());
        assert!(s(&[0.0, 1.0, 1.0, 2.0]).is_none());
        assert!(s(&[0.0, 1.0, f64::NAN, 3.0]).is_none());
    }
}
