//! Least-squares straight lines, shared by the measurements that need one (the Poncelet fit,
//! front speeds).

/// The least-squares line `y = a + b x` through `(x, y)` points, as `(a, b)`; `None` with
/// fewer than two points or when the `x` do not differ.
pub fn line_fit(points: &[(f64, f64)]) -> Option<(f64, f64)> {
    if points.len() < 2 {
        return None;
    }
    let n = points.len() as f64;
    let mx = points.iter().map(|p| p.0).sum::<f64>() / n;
    let my = points.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = points.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = points.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let spread = points.iter().map(|p| (p.0 - mx).abs()).fold(0.0, f64::max);
    if sxx.is_nan() || sxx <= 0.0 || spread <= 1e-12 * mx.abs() {
        return None;
    }
    let b = sxy / sxx;
    Some((my - b * mx, b))
}

/// The standard error of the slope `b` of the line `y = a + b x` fitted to `points`, from
/// its residuals: `sqrt(sum r^2 / (n - 2) / sum (x - mean x)^2)`; `None` with fewer than three
/// points or when the `x` do not differ.
pub fn slope_error(points: &[(f64, f64)], a: f64, b: f64) -> Option<f64> {
    if points.len() < 3 {
        return None;
    }
    let n = points.len() as f64;
    let mx = points.iter().map(|p| p.0).sum::<f64>() / n;
    let sxx: f64 = points.iter().map(|p| (p.0 - mx).powi(2)).sum();
    if sxx.is_nan() || sxx <= 0.0 {
        return None;
    }
    let residuals: f64 = points.iter().map(|p| (p.1 - a - b * p.0).powi(2)).sum();
    Some((residuals / (n - 2.0) / sxx).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fits_a_line_and_refuses_degenerate_data() {
        let (a, b) = line_fit(&[(1.0, 5.0), (3.0, 11.0), (2.0, 8.0)]).unwrap();
        assert!((a - 2.0).abs() < 1e-12 && (b - 3.0).abs() < 1e-12);
        assert_eq!(line_fit(&[(1.0, 3.0)]), None);
        assert_eq!(line_fit(&[(2.0, 3.0), (2.0, 5.0)]), None);
        assert_eq!(line_fit(&[]), None);
    }

    /// Points on a line have no slope error; y = x + (1, -1, 1, -1) over x = 0..3 has
    /// residuals r with sum r^2 = 3.2 about its fit (slope 0.6) and sum (x - 1.5)^2 = 5, so
    /// sqrt(3.2 / 2 / 5).
    #[test]
    fn the_slope_error_comes_from_the_residuals() {
        let exact = [(0.0, 1.0), (1.0, 3.0), (2.0, 5.0)];
        let (a, b) = line_fit(&exact).unwrap();
        assert!(slope_error(&exact, a, b).unwrap() < 1e-12);
        let noisy = [(0.0, 1.0), (1.0, 0.0), (2.0, 3.0), (3.0, 2.0)];
        let (a, b) = line_fit(&noisy).unwrap();
        assert!((b - 0.6).abs() < 1e-12, "slope {b}");
        let e = slope_error(&noisy, a, b).unwrap();
        assert!((e - (3.2f64 / 2.0 / 5.0).sqrt()).abs() < 1e-12, "error {e}");
        assert_eq!(slope_error(&exact[..2], a, b), None);
    }
}
