//! The Poncelet drag fit of the paper's section 4.2 (docs/model.md §7.2): `regolith fit`.
//!
//! The intruder's depth below the point of first contact, `z(t)` (positive downwards), is
//! assumed to obey `m z'' = m g - f(z) - h(z) z'^2` with a static term `f` and a collisional
//! term `h` that depend on depth and shape but not on speed. Runs of one shape at several
//! impact speeds pass every depth `z_k` at different speeds, so at each `z_k` the runs give
//! one linear equation each, `f + h z'^2 = m (g - z'')`, and `f(z_k), h(z_k)` follow by least
//! squares. As the paper: each run's `z(t)` is interpolated by a cubic spline (not-a-knot ends), the
//! spline is inverted to the time `t_k` at which the run reaches `z_k` (only while the run
//! still goes down, where `z(t)` is one-to-one), and the spline's derivatives give `z'` and
//! `z''` there.

use regolith::format::Num;
use regolith::linefit::line_fit;

mod runs;
mod spline;

pub use runs::{
    SceneGroup, default_table, expand_dirs, group_by_scene, load_run, refuse_duplicates,
};
pub use spline::CubicSpline;

/// One run's trajectory as the fit needs it.
#[derive(Clone, Debug)]
pub struct PonceletRun {
    /// Where it came from (for messages and the table).
    pub label: String,
    /// Mass per unit thickness (kg/m).
    pub mass: f64,
    /// Downward gravity (m/s^2).
    pub gravity: f64,
    /// Times since first contact (s).
    pub t: Vec<f64>,
    /// Depth below the position at first contact (m, positive down).
    pub z: Vec<f64>,
    /// The run's `state_hash` (summary.json), which tells the same run given twice.
    pub state_hash: Option<String>,
    /// The grid's cell size (m; summary.json), the period in depth of the pulses a grid
    /// adds as the intruder crosses its cells; `None` from an older regolith.
    pub cell_size: Option<f64>,
    /// What the run's scene is once the intruder's speed is taken out: runs with equal
    /// keys are one shape, bed and numerics at several speeds (see [`group_by_scene`]).
    pub scene_key: String,
}

impl PonceletRun {
    /// The part of the run before it first stops going down: the samples up to the deepest
    /// point reached before the depth first decreases.
    fn descent(&self) -> (&[f64], &[f64]) {
        let mut end = 1;
        while end < self.z.len() && self.z[end] > self.z[end - 1] {
            end += 1;
        }
        (&self.t[..end], &self.z[..end])
    }
}

/// 20 depths from 5% to 90% of the shallowest depth the runs reach while descending (the
/// first few samples after contact, where the spline is least accurate, are left out as the
/// paper did).
pub fn default_depths(runs: &[PonceletRun]) -> Vec<f64> {
    let shallowest = runs
        .iter()
        .map(|r| *r.descent().1.last().unwrap_or(&0.0))
        .fold(f64::INFINITY, f64::min);
    (0..20)
        .map(|k| shallowest * (0.05 + 0.85 * k as f64 / 19.0))
        .collect()
}

/// `f(z_k)` and `h(z_k)` at one depth.
#[derive(Clone, Debug, PartialEq)]
pub struct PonceletPoint {
    pub depth: f64,
    /// Static force (N per metre of thickness).
    pub f: f64,
    /// Collisional coefficient (kg/m per metre of thickness).
    pub h: f64,
    /// Runs that reached this depth while still descending.
    pub runs: usize,
    /// Root mean square of `f + h z'^2 - m (g - z'')` over those runs (N/m).
    pub residual: f64,
    /// Standard errors of `f` and `h` from the residual (`n - 2` degrees of freedom).
    pub f_error: f64,
    pub h_error: f64,
    /// Condition number of the least-squares problem (its columns `1` and `z'^2` scaled to
    /// unit length): large when the speeds at this depth hardly differ.
    pub condition: f64,
    /// Mean over the runs of the measured force `m (g - z'')` (N/m) and of `z'^2` (m^2/s^2):
    /// the scales `f` and `h` are judged against.
    pub mean_force: f64,
    pub mean_v2: f64,
}

impl PonceletPoint {
    /// Whether `f` and `h` at this depth are a drag law: neither is negative by more than
    /// two standard errors (a resisting medium pushes back and its collisional term grows
    /// with speed), and each is known to better than its own size (a standard error larger
    /// than the value says the derivatives were noise, not a law).
    /// (A standard error below 1e-9 of the term's share of the mean force is round-off:
    /// exact data with `h = 0` is a law, and then only a negative value beyond round-off
    /// is refused.)
    pub fn is_physical(&self) -> bool {
        let known = |value: f64, error: f64, scale: f64| {
            let round_off = 1e-9 * scale.abs();
            if error <= round_off {
                value > -round_off
            } else {
                value > -2.0 * error && error < value.abs()
            }
        };
        known(self.f, self.f_error, self.mean_force)
            && known(self.h, self.h_error, self.mean_force / self.mean_v2)
    }
}

/// What [`PonceletPoint::is_physical`] refuses, in the words of messages.
pub const NOT_PHYSICAL: &str =
    "f or h negative beyond two standard errors, or with a standard error larger than itself";

/// Distinct speeds a depth needs before it is fitted. Two unknowns per depth: with two
/// speeds the line passes exactly through both points, the residual is zero whatever the
/// data, and nothing checks that they follow the law (f and h may come out negative); a
/// third speed leaves one degree of freedom to measure the misfit.
pub const MIN_SPEEDS: usize = 3;

/// How the velocity and acceleration at `t_k` are taken from a run's depth samples.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Derivatives {
    /// From the interpolating spline, as the paper does.
    Spline,
    /// From a least-squares parabola through the samples within half this window (s) of
    /// `t_k`: it averages out oscillations shorter than the window (on a coarse grid the
    /// deceleration pulses each time the intruder crosses a cell), at the price of bias where
    /// the acceleration changes within the window.
    Window(f64),
    /// From a least-squares parabola through the descending samples within half this many
    /// cells of depth of `z_k`: the grid's pulses are periodic in depth, one per cell
    /// crossed, so a window in cells spans the same number of pulse periods at every speed
    /// (a window in seconds spans fewer at lower speed). The default, at
    /// [`DEFAULT_CELLS`].
    Cells(f64),
}

/// The default window of [`Derivatives::Cells`]: three cells of depth, three pulse periods,
/// the length that averaged out the pulses best on synthetic runs (`lab/tests/poncelet.rs`,
/// docs/VALIDATION.md "Poncelet").
pub const DEFAULT_CELLS: f64 = 3.0;

impl Derivatives {
    /// The `regolith fit` flag that selects it.
    pub fn flag(&self) -> String {
        match self {
            Derivatives::Spline => "--spline".to_string(),
            Derivatives::Window(w) => format!("--window {w}"),
            Derivatives::Cells(n) => format!("--cells {n}"),
        }
    }
}

/// The first of wider cell windows (5, 8, 12 cells), then the spline, that gives physical
/// values ([`PonceletPoint::is_physical`]) at every fitted depth: what `regolith fit`
/// proposes when its default does not.
pub fn physical_method(runs: &[PonceletRun], depths: &[f64]) -> Option<Derivatives> {
    [
        Derivatives::Cells(5.0),
        Derivatives::Cells(8.0),
        Derivatives::Cells(12.0),
        Derivatives::Spline,
    ]
    .into_iter()
    .find(|&how| {
        let points = fit(runs, depths, how);
        !points.is_empty() && points.iter().all(PonceletPoint::is_physical)
    })
}

/// What to tell a user whose fit with `how` gave `points` of which some are not physical:
/// the depths from which on they all are (when the bad ones are the shallowest, as where a
/// flat face's contact transient is no Poncelet law), and a wider window that makes every
/// depth physical, with its length in depth (it averages over that much and biases
/// accordingly).
pub fn physical_hint(runs: &[PonceletRun], depths: &[f64], points: &[PonceletPoint]) -> String {
    let mut hints = Vec::new();
    if let Some(first) = points.iter().rposition(|p| !p.is_physical()).map(|i| i + 1)
        && first < points.len()
        && points[first..].iter().all(PonceletPoint::is_physical)
    {
        let (lo, hi) = (points[first].depth, points[points.len() - 1].depth);
        hints.push(format!(
            "f and h are physical from {:.1} cm down (--depths {lo:.4}:{hi:.4}:{})",
            100.0 * lo,
            points.len() - first
        ));
    }
    if let Some(how) = physical_method(runs, depths) {
        let cell = runs.iter().filter_map(|r| r.cell_size).fold(0.0, f64::max);
        let span = match how {
            Derivatives::Cells(n) => {
                format!(", which averages over {:.1} cm of depth", 100.0 * n * cell)
            }
            _ => String::new(),
        };
        hints.push(format!("at every depth with {how} ({}){span}", how.flag()));
    }
    match hints.len() {
        0 => "no window of 5 to 12 cells, nor the spline, makes every depth physical: the runs are too noisy for a drag law (a finer grid, or more speeds)".to_string(),
        _ => hints.join(", or "),
    }
}

impl std::fmt::Display for Derivatives {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        match self {
            Derivatives::Spline => write!(f, "the interpolating spline"),
            Derivatives::Window(w) => write!(f, "a window of {w} s"),
            Derivatives::Cells(n) => write!(f, "a window of {n} cells"),
        }
    }
}

/// Slope and curvature (`z'`, `z''`) at `tk` of the least-squares parabola through the
/// samples `(t, z)` that `keep` accepts; `None` with fewer than four samples.
fn local_parabola(
    t: &[f64],
    z: &[f64],
    tk: f64,
    keep: impl Fn(f64, f64) -> bool,
) -> Option<(f64, f64)> {
    let mut m = [[0.0f64; 3]; 3];
    let mut r = [0.0f64; 3];
    let mut count = 0;
    for (&ti, &zi) in t.iter().zip(z) {
        if !keep(ti, zi) {
            continue;
        }
        let tau = ti - tk;
        count += 1;
        let p = [1.0, tau, tau * tau];
        for a in 0..3 {
            r[a] += p[a] * zi;
            for b in 0..3 {
                m[a][b] += p[a] * p[b];
            }
        }
    }
    if count < 4 {
        return None;
    }
    // Gaussian elimination on the 3 x 3 normal equations.
    for c in 0..3 {
        let pivot = m[c][c];
        if pivot.abs() < 1e-300 {
            return None;
        }
        let upper = m[c];
        for row in c + 1..3 {
            let w = m[row][c] / pivot;
            for (entry, above) in m[row].iter_mut().zip(upper).skip(c) {
                *entry -= w * above;
            }
            r[row] -= w * r[c];
        }
    }
    let mut x = [0.0f64; 3];
    for c in (0..3).rev() {
        let tail: f64 = (c + 1..3).map(|k| m[c][k] * x[k]).sum();
        x[c] = (r[c] - tail) / m[c][c];
    }
    Some((x[1], 2.0 * x[2]))
}

/// Fits `f` and `h` at each of `depths` from `runs`; a depth reached (while descending) by
/// runs at fewer than [`MIN_SPEEDS`] distinct speeds is left out.
pub fn fit(runs: &[PonceletRun], depths: &[f64], how: Derivatives) -> Vec<PonceletPoint> {
    let splines: Vec<_> = runs
        .iter()
        .filter_map(|r| {
            let (t, z) = r.descent();
            CubicSpline::not_a_knot(t, z)
                .map(|s| (r, s, t[0], *t.last().unwrap(), *z.last().unwrap()))
        })
        .collect();
    let mut out = Vec::new();
    for &zk in depths {
        // Rows (1, v^2) -> m (g - a).
        let rows: Vec<(f64, f64)> = splines
            .iter()
            .filter(|(_, s, lo, _, deepest)| zk <= *deepest && zk >= s.eval(*lo).0)
            .filter_map(|(r, s, lo, hi, _)| {
                let tk = s.first_reach(zk, *lo, *hi);
                let (v, a) = match how {
                    Derivatives::Spline => {
                        let (_, v, a) = s.eval(tk);
                        (v, a)
                    }
                    Derivatives::Window(w) => {
                        local_parabola(&r.t, &r.z, tk, |t, _| (t - tk).abs() <= 0.5 * w)?
                    }
                    Derivatives::Cells(n) => {
                        let (t, z) = r.descent();
                        let half = 0.5 * n * r.cell_size?;
                        local_parabola(t, z, tk, |_, z| (z - zk).abs() <= half)?
                    }
                };
                Some((v * v, r.mass * (r.gravity - a)))
            })
            .collect();
        if distinct_speeds(&rows) < MIN_SPEEDS {
            continue;
        }
        if let Some(point) = fit_depth(zk, &rows) {
            out.push(point);
        }
    }
    out
}

/// Number of distinct `v^2` among the rows (equal to 1e-9 of the largest counts once).
fn distinct_speeds(rows: &[(f64, f64)]) -> usize {
    let mut v2: Vec<f64> = rows.iter().map(|r| r.0).collect();
    v2.sort_by(f64::total_cmp);
    let scale = v2.last().copied().unwrap_or(0.0).abs();
    v2.windows(2).filter(|w| w[1] - w[0] > 1e-9 * scale).count() + usize::from(!v2.is_empty())
}

/// The least-squares line `m (g - z'') = f + h v^2` through one depth's rows, with its
/// uncertainty.
fn fit_depth(depth: f64, rows: &[(f64, f64)]) -> Option<PonceletPoint> {
    let (f, h) = line_fit(rows)?;
    let n = rows.len() as f64;
    let squares: f64 = rows.iter().map(|(v2, b)| (f + h * v2 - b).powi(2)).sum();
    let mean = rows.iter().map(|r| r.0).sum::<f64>() / n;
    let sxx: f64 = rows.iter().map(|r| (r.0 - mean).powi(2)).sum();
    let variance = squares / (n - 2.0);
    // Columns 1 and v^2 scaled to unit length have Gram matrix [[1, c], [c, 1]].
    let c = rows.iter().map(|r| r.0).sum::<f64>()
        / (n.sqrt() * rows.iter().map(|r| r.0 * r.0).sum::<f64>().sqrt());
    Some(PonceletPoint {
        depth,
        f,
        h,
        runs: rows.len(),
        residual: (squares / n).sqrt(),
        f_error: (variance * (1.0 / n + mean * mean / sxx)).sqrt(),
        h_error: (variance / sxx).sqrt(),
        condition: ((1.0 + c) / (1.0 - c).max(f64::MIN_POSITIVE)).sqrt(),
        mean_force: rows.iter().map(|r| r.1).sum::<f64>() / n,
        mean_v2: mean,
    })
}

/// The fit as CSV: `depth,f,h,runs,residual,f_error,h_error,condition`.
pub fn to_csv(points: &[PonceletPoint]) -> String {
    let mut s = String::from("depth,f,h,runs,residual,f_error,h_error,condition\n");
    for p in points {
        s.push_str(&format!(
            "{},{},{},{},{},{},{},{}\n",
            Num(p.depth),
            Num(p.f),
            Num(p.h),
            p.runs,
            Num(p.residual),
            Num(p.f_error),
            Num(p.h_error),
            Num(p.condition)
        ));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_local_parabola_is_exact_for_parabolas() {
        let t: Vec<f64> = (0..50).map(|k| k as f64 * 1e-3).collect();
        let z: Vec<f64> = t.iter().map(|&x| 0.1 + 3.0 * x - 40.0 * x * x).collect();
        let within = |half: f64| move |t: f64, _| (t - 0.02f64).abs() <= half;
        let (v, a) = local_parabola(&t, &z, 0.02, within(0.006)).unwrap();
        assert!((v - (3.0 - 80.0 * 0.02)).abs() < 1e-9 && (a + 80.0).abs() < 1e-6);
        assert_eq!(
            local_parabola(&t, &z, 0.02, within(0.001)),
            None,
            "three samples are too few"
        );
    }
}
