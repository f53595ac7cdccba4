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
}
