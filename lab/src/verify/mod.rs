//! Measurements on the verification problems of dense flow: the steady chute (`chute`) and
//! the nonlocal layer (`nonlocal`). The elastic step's own measures (a bar's period, a
//! front's speed, spurious stress) are the engine's tests' (tests/common/measure.rs).

pub mod chute;
pub mod nonlocal;

/// The `q` quantile of `values` (0 <= q <= 1): the sorted value at index `floor(q (n - 1))`,
/// no interpolation; NaN for no values.
pub fn quantile(mut values: Vec<f64>, q: f64) -> f64 {
    if values.is_empty() {
        return f64::NAN;
    }
    values.sort_by(f64::total_cmp);
    values[(q * (values.len() - 1) as f64) as usize]
}
