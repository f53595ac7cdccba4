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

use std::path::{Path, PathBuf};

use regolith::linefit::line_fit;

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
}

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
}

/// Slope and curvature (`z'`, `z''`) at `tk` of the least-squares parabola through the
/// samples within `half` of it; `None` with fewer than four samples.
fn local_parabola(t: &[f64], z: &[f64], tk: f64, half: f64) -> Option<(f64, f64)> {
    let mut m = [[0.0f64; 3]; 3];
    let mut r = [0.0f64; 3];
    let mut count = 0;
    for (&ti, &zi) in t.iter().zip(z) {
        let tau = ti - tk;
        if tau.abs() > half {
            continue;
        }
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
                    Derivatives::Window(w) => local_parabola(&r.t, &r.z, tk, 0.5 * w)?,
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
    })
}

/// Reads a run directory (`summary.json` and `trajectory.csv`) for the fit of `body`.
pub fn load_run(dir: &Path, body: &str) -> Result<PonceletRun, String> {
    let label = dir.display().to_string();
    let read = |name: &str| {
        std::fs::read_to_string(dir.join(name)).map_err(|e| format!("{label}/{name}: {e}"))
    };
    let summary: serde_json::Value = serde_json::from_str(&read("summary.json")?)
        .map_err(|e| format!("{label}/summary.json: {e}"))?;
    if summary["status"] != "completed" {
        return Err(format!("{label}: the run did not complete"));
    }
    let mass = summary["bodies"]
        .as_array()
        .and_then(|b| b.iter().find(|b| b["name"] == body))
        .and_then(|b| b["mass"].as_f64())
        .ok_or_else(|| format!("{label}/summary.json: no body named `{body}`"))?;
    let gravity = -summary["gravity"][1].as_f64().ok_or_else(|| {
        format!("{label}/summary.json: no gravity (written by an older regolith)")
    })?;
    let impact = &summary["impact"];
    if impact["at_rest"] == false {
        return Err(format!(
            "{label}: the intruder is not at rest ({}); a Poncelet fit needs runs that end at rest (rerun with a later time.end)",
            impact["not_at_rest"].as_str().unwrap_or_default()
        ));
    }
    let contact = impact["contact_time"].as_f64().unwrap_or(0.0);
    let csv = read("trajectory.csv")?;
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap_or("").split(',').collect();
    let column = |name: &str| {
        header
            .iter()
            .position(|h| *h == name)
            .ok_or_else(|| format!("{label}/trajectory.csv: no column {name}"))
    };
    let (ct, cy) = (column("t")?, column(&format!("{body}_y"))?);
    let (mut t, mut y) = (Vec::new(), Vec::new());
    for (n, line) in lines.enumerate() {
        let cells: Vec<&str> = line.split(',').collect();
        let num = |c: usize| {
            cells
                .get(c)
                .and_then(|s| s.parse::<f64>().ok())
                .ok_or_else(|| format!("{label}/trajectory.csv line {}: expected numbers", n + 2))
        };
        let (tn, yn) = (num(ct)?, num(cy)?);
        if tn >= contact {
            t.push(tn - contact);
            y.push(yn);
        }
    }
    let Some(&y0) = y.first() else {
        return Err(format!("{label}: no trajectory after first contact"));
    };
    Ok(PonceletRun {
        label,
        mass,
        gravity,
        t,
        z: y.iter().map(|y| y0 - y).collect(),
        state_hash: summary["state_hash"].as_str().map(str::to_string),
    })
}

/// Refuses a run given twice: the same directory twice, or two directories holding the same
/// run (equal `state_hash`). A duplicate would count as a second speed where there is one.
pub fn refuse_duplicates(dirs: &[PathBuf], runs: &[PonceletRun]) -> Result<(), String> {
    let canonical: Vec<PathBuf> = dirs
        .iter()
        .map(|d| d.canonicalize().unwrap_or_else(|_| d.clone()))
        .collect();
    for (b, run) in runs.iter().enumerate() {
        for a in 0..b {
            if canonical[a] == canonical[b] {
                return Err(format!("{} is given twice", run.label));
            }
            if let (Some(x), Some(y)) = (&runs[a].state_hash, &run.state_hash)
                && x == y
            {
                return Err(format!(
                    "{} and {} are the same run (state_hash {x}); give each run once",
                    runs[a].label, run.label
                ));
            }
        }
    }
    Ok(())
}

/// Where `regolith fit` writes by default: in the sweep directory when the first argument
/// is one, else beside the first run directory (never inside a run's own record).
pub fn default_table(first: &Path) -> PathBuf {
    if first.join("sweep.csv").is_file() {
        return first.join("poncelet.csv");
    }
    match first.parent() {
        Some(parent) if !parent.as_os_str().is_empty() => parent.join("poncelet.csv"),
        _ => PathBuf::from("poncelet.csv"),
    }
}

/// Run directories named on the command line: a plan (`plan.json`: a sweep's output
/// directory, or a plan run elsewhere and collected) stands for its runs that have a
/// summary, as does a sweep directory written before plans (it has a `sweep.csv`).
pub fn expand_dirs(dirs: &[PathBuf]) -> Result<Vec<PathBuf>, String> {
    let mut out = Vec::new();
    for d in dirs {
        if d.join("plan.json").is_file() {
            // A sweep's output directory or a plan: the runs it lists that have a summary.
            let plan = crate::plan::read_plan(d).map_err(|e| e.to_string())?;
            out.extend(
                plan.runs
                    .iter()
                    .map(|r| d.join(&r.dir))
                    .filter(|p| p.join("summary.json").is_file()),
            );
        } else if d.join("sweep.csv").is_file() {
            // A sweep written before plans: its runs sit in its directory.
            let mut runs = Vec::new();
            for base in [d.clone(), d.join("runs")] {
                if !base.is_dir() {
                    continue;
                }
                runs.extend(
                    std::fs::read_dir(&base)
                        .map_err(|e| format!("{}: {e}", base.display()))?
                        .filter_map(|e| e.ok().map(|e| e.path()))
                        .filter(|p| p.join("summary.json").is_file()),
                );
            }
            runs.sort();
            out.extend(runs);
        } else {
            out.push(d.clone());
        }
    }
    Ok(out)
}

/// The fit as CSV: `depth,f,h,runs,residual,f_error,h_error,condition`.
pub fn to_csv(points: &[PonceletPoint]) -> String {
    let mut s = String::from("depth,f,h,runs,residual,f_error,h_error,condition\n");
    for p in points {
        s.push_str(&format!(
            "{:e},{:e},{:e},{},{:e},{:e},{:e},{:e}\n",
            p.depth, p.f, p.h, p.runs, p.residual, p.f_error, p.h_error, p.condition
        ));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_sweep_directory_and_a_collected_plan_list_their_runs() {
        let dir = tempfile::tempdir().unwrap();
        let sweep = dir.path().join("sweep");
        let plan = dir.path().join("plan");
        for run in [sweep.join("run_0001"), plan.join("runs/run_0002")] {
            std::fs::create_dir_all(&run).unwrap();
            std::fs::write(run.join("summary.json"), "{}").unwrap();
        }
        std::fs::create_dir_all(sweep.join("run_0002")).unwrap(); // never ran
        // Not in the plan: left out even with a summary.
        std::fs::create_dir_all(plan.join("runs/stray")).unwrap();
        std::fs::write(plan.join("runs/stray/summary.json"), "{}").unwrap();
        std::fs::write(sweep.join("sweep.csv"), "run\n").unwrap();
        let run = |d: &str| {
            format!(r#"{{"dir": "{d}", "values": [], "scene_digest": "", "estimated_s": 1.0}}"#)
        };
        std::fs::write(
            plan.join("plan.json"),
            format!(
                r#"{{"kind": "sweep", "name": "p", "keys": [], "runs": [{}, {}]}}"#,
                run("runs/run_0001"),
                run("runs/run_0002")
            ),
        )
        .unwrap();
        let found = expand_dirs(&[sweep.clone(), plan.clone()]).unwrap();
        assert_eq!(found, [sweep.join("run_0001"), plan.join("runs/run_0002")]);
    }

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
    fn the_local_parabola_is_exact_for_parabolas() {
        let t: Vec<f64> = (0..50).map(|k| k as f64 * 1e-3).collect();
        let z: Vec<f64> = t.iter().map(|&x| 0.1 + 3.0 * x - 40.0 * x * x).collect();
        let (v, a) = local_parabola(&t, &z, 0.02, 0.006).unwrap();
        assert!((v - (3.0 - 80.0 * 0.02)).abs() < 1e-9 && (a + 80.0).abs() < 1e-6);
        assert_eq!(
            local_parabola(&t, &z, 0.02, 0.001),
            None,
            "three samples are too few"
        );
    }

    #[test]
    fn spline_refuses_bad_knots() {
        let s = |t: &[f64]| CubicSpline::not_a_knot(t, &vec![1.0; t.len()]);
        assert!(s(&[0.0, 1.0, 2.0]).is_none());
        assert!(s(&[0.0, 1.0, 1.0, 2.0]).is_none());
        assert!(s(&[0.0, 1.0, f64::NAN, 3.0]).is_none());
    }
}
