//! `regolith beverloo`: Beverloo's law fitted to silo runs, `W = C rho_b sqrt(g) (D - k d)^beta`
//! (the 2D form has `beta = 3/2`), one fit per grid.
//!
//! Each run gives one point: its opening `D` (the total width of the `Open` segments of its
//! scene's floor), its steady discharge rate `W` with the standard error (`discharge` in its
//! `summary.json`, from the `Discharge` output), its bulk density (the granular body's
//! material density) and its cell size, by which runs are grouped: a grid is a series, so
//! that the fit on two grids tells how much of the answer is the grid.
//!
//! The fit is least squares on `W`: for given `k` and `beta`, `C` is linear and solved
//! exactly; `k` (and `beta` when free) minimise the residual by a scan and golden-section
//! refinement, `k` between 0 and the smallest opening over `d`. Uncertainties are jackknife
//! estimates over the openings (one left out at a time), which take in the scatter of the
//! points about the law as well as their own errors.
//!
//! With three grids, each finer by the same ratio, the rate at each opening all three ran is
//! also extrapolated to zero cell size (Richardson, with the order the three rates show) and
//! the law fitted to those: the nearest the runs come to the model's own `C`, `k` and `beta`
//! when the grids are not yet converged.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use regolith::registry::Registries;
use regolith::scene::{Scene, Side, Wall};

use crate::batch::read_summary;
use crate::figures::plot::{self, Series};

/// Gravity's magnitude in the law (m/s^2): the shipped silos' `gravity` (the default).
const G: f64 = 9.81;

/// One run: an opening and its steady rate.
#[derive(Clone, Debug, PartialEq)]
pub struct Opening {
    pub run: PathBuf,
    /// The opening `D` (m).
    pub width: f64,
    /// The grid's cell size (m).
    pub cell: f64,
    /// Bulk density of the draining body (kg/m^3).
    pub bulk_density: f64,
    /// Steady rate and its standard error (kg/(m s)).
    pub rate: f64,
    pub rate_error: f64,
}

/// A fitted law: `C`, `k`, `beta` with their jackknife errors (zero for a fixed `beta`),
/// and the rms residual (kg/(m s)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fit {
    pub c: f64,
    pub k: f64,
    pub beta: f64,
    pub c_error: f64,
    pub k_error: f64,
    pub beta_error: f64,
    pub rms: f64,
}

/// Reads one run directory: its scene (`scene.ron`, as the run resolved it) and summary.
pub fn read_run(dir: &Path, registries: &Arc<Registries>) -> Result<Opening, String> {
    let at = |what: &str| format!("{}: {what}", dir.display());
    let (scene, _) = Scene::load(&dir.join("scene.ron"), &[], registries)
        .map_err(|e| at(&format!("its scene.ron: {e}")))?;
    let summary = read_summary(dir).ok_or_else(|| at("no summary.json that parses"))?;
    let discharge = &summary["discharge"];
    let (Some(rate), Some(rate_error)) = (
        discharge["steady_rate"].as_f64(),
        discharge["steady_rate_error"].as_f64(),
    ) else {
        return Err(at(
            "its summary.json has no discharge.steady_rate (the scene needs a Discharge output)",
        ));
    };
    let width: f64 = scene
        .walls
        .segments
        .iter()
        .filter(|s| s.side == Side::Bottom && s.wall == Wall::Open)
        .map(|s| s.to - s.from)
        .sum();
    if width <= 0.0 {
        return Err(at("its scene has no Open segment on the floor"));
    }
    let body = scene
        .bodies
        .iter()
        .find(|b| b.material.granular())
        .ok_or_else(|| at("its scene has no granular body"))?;
    Ok(Opening {
        run: dir.to_path_buf(),
        width,
        cell: scene.grid().cell_size,
        bulk_density: body.material.density(),
        rate,
        rate_error,
    })
}

/// The residual sum of squares and `C` of the law with `k`, `beta` on `points`.
fn solve_c(points: &[Opening], d: f64, k: f64, beta: f64) -> (f64, f64) {
    let f = |p: &Opening| p.bulk_density * G.sqrt() * (p.width - k * d).max(0.0).powf(beta);
    let (fw, ff) = points.iter().fold((0.0, 0.0), |(fw, ff), p| {
        (fw + f(p) * p.rate, ff + f(p) * f(p))
    });
    let c = if ff > 0.0 { fw / ff } else { 0.0 };
    let rss = points.iter().map(|p| (p.rate - c * f(p)).powi(2)).sum();
    (rss, c)
}

/// The minimum of `cost` on `[lo, hi]`: a scan of 64 intervals, then golden sections in the
/// best one's neighbours.
fn minimise(cost: impl Fn(f64) -> f64, lo: f64, hi: f64) -> f64 {
    const SCAN: usize = 64;
    let at = |i: usize| lo + (hi - lo) * i as f64 / SCAN as f64;
    let best = (0..=SCAN)
        .min_by(|&a, &b| cost(at(a)).total_cmp(&cost(at(b))))
        .unwrap_or(0);
    let (mut a, mut b) = (at(best.saturating_sub(1)), at((best + 1).min(SCAN)));
    let ratio = (5f64.sqrt() - 1.0) / 2.0;
    for _ in 0..80 {
        let (x1, x2) = (b - ratio * (b - a), a + ratio * (b - a));
        if cost(x1) < cost(x2) {
            b = x2;
        } else {
            a = x1;
        }
    }
    0.5 * (a + b)
}

/// `(C, k, beta, rss)` of the best law on `points`, with `beta` fixed or free (1 to 3).
fn best(points: &[Opening], d: f64, beta: Option<f64>) -> (f64, f64, f64, f64) {
    let widest_k = points.iter().map(|p| p.width).fold(f64::INFINITY, f64::min) / d;
    let k_for = |beta: f64| minimise(|k| solve_c(points, d, k, beta).0, 0.0, widest_k * 0.999);
    let beta =
        beta.unwrap_or_else(|| minimise(|beta| solve_c(points, d, k_for(beta), beta).0, 1.0, 3.0));
    let k = k_for(beta);
    let (rss, c) = solve_c(points, d, k, beta);
    (c, k, beta, rss)
}

/// Fits the law on `points` (grain diameter `d`, m) with `beta` fixed, or free when `None`.
/// Needs one point more than the free parameters and at least three; `None` otherwise.
pub fn fit(points: &[Opening], d: f64, beta: Option<f64>) -> Option<Fit> {
    let free = if beta.is_some() { 2 } else { 3 };
    let n = points.len();
    if n < free + 1 || n < 3 {
        return None;
    }
    let (c, k, b, rss) = best(points, d, beta);
    // Jackknife: each point left out in turn.
    let leave_out: Vec<(f64, f64, f64)> = (0..n)
        .map(|i| {
            let rest: Vec<Opening> = points
                .iter()
                .enumerate()
                .filter(|(j, _)| *j != i)
                .map(|(_, p)| p.clone())
                .collect();
            let (c, k, b, _) = best(&rest, d, beta);
            (c, k, b)
        })
        .collect();
    let spread = |pick: fn(&(f64, f64, f64)) -> f64| {
        let mean = leave_out.iter().map(pick).sum::<f64>() / n as f64;
        let sum: f64 = leave_out.iter().map(|x| (pick(x) - mean).powi(2)).sum();
        ((n - 1) as f64 / n as f64 * sum).sqrt()
    };
    Some(Fit {
        c,
        k,
        beta: b,
        c_error: spread(|x| x.0),
        k_error: spread(|x| x.1),
        beta_error: if beta.is_some() { 0.0 } else { spread(|x| x.2) },
        rms: (rss / n as f64).sqrt(),
    })
}

/// The law's rate at opening `width` (kg/(m s)).
pub fn rate(fit: &Fit, width: f64, bulk_density: f64, d: f64) -> f64 {
    fit.c * bulk_density * G.sqrt() * (width - fit.k * d).max(0.0).powf(fit.beta)
}

/// The runs grouped by cell size (finest last), each sorted by opening.
pub fn by_grid(mut runs: Vec<Opening>) -> Vec<Vec<Opening>> {
    runs.sort_by(|a, b| b.cell.total_cmp(&a.cell).then(a.width.total_cmp(&b.width)));
    let mut grids: Vec<Vec<Opening>> = Vec::new();
    for r in runs {
        match grids.last_mut() {
            Some(g) if (g[0].cell - r.cell).abs() <= 1e-9 * r.cell => g.push(r),
            _ => grids.push(vec![r]),
        }
    }
    grids
}

/// One opening's rate extrapolated to zero cell size from the three finest grids.
#[derive(Clone, Debug, PartialEq)]
pub struct Extrapolated {
    /// The opening as the runs saw it, `rate` the extrapolated one and `rate_error` its
    /// distance from the finest grid's (how far the extrapolation reaches), `cell` zero.
    pub opening: Opening,
    /// The three grids' rates, coarsest first.
    pub rates: [f64; 3],
    /// The order of convergence the three show: `ln((W2 - W1) / (W3 - W2)) / ln r`.
    pub order: f64,
}

/// Richardson extrapolation of each opening the three finest grids share, when their cells
/// shrink by one ratio `r` (within 1%) and the rates change monotonically with shrinking
/// steps (an order above zero); openings that do not are left out. `(r, extrapolated)`, or
/// `None` with fewer than three grids or grids of unequal ratios.
pub fn extrapolate(grids: &[Vec<Opening>]) -> Option<(f64, Vec<Extrapolated>)> {
    let [g1, g2, g3] = grids.get(grids.len().checked_sub(3)?..)? else {
        return None;
    };
    let r = g1[0].cell / g2[0].cell;
    if (g2[0].cell / g3[0].cell / r - 1.0).abs() > 0.01 || r <= 1.0 {
        return None;
    }
    let at = |g: &[Opening], w: f64| {
        g.iter()
            .find(|p| (p.width - w).abs() <= 1e-9 * w)
            .map(|p| p.rate)
    };
    let out = g3
        .iter()
        .filter_map(|fine| {
            let rates = [at(g1, fine.width)?, at(g2, fine.width)?, fine.rate];
            let (e12, e23) = (rates[1] - rates[0], rates[2] - rates[1]);
            let order = (e12 / e23).ln() / r.ln();
            // Same sign and a smaller second step: otherwise not converging (NaN included).
            if order.is_nan() || order <= 0.0 {
                return None;
            }
            let rate = rates[2] + e23 / (r.powf(order) - 1.0);
            Some(Extrapolated {
                opening: Opening {
                    rate,
                    rate_error: (rate - rates[2]).abs(),
                    cell: 0.0,
                    ..fine.clone()
                },
                rates,
                order,
            })
        })
        .collect();
    Some((r, out))
}

/// Both fits of `points` as Markdown lines.
fn fits(md: &mut String, points: &[Opening], d: f64) {
    for (label, beta) in [
        ("beta = 3/2 (Beverloo, 2D)", Some(1.5)),
        ("beta free", None),
    ] {
        match fit(points, d, beta) {
            Some(f) => {
                let _ = writeln!(
                    md,
                    "- {label}: C = {:.3} +- {:.3}, k = {:.2} +- {:.2}, beta = {:.3} +- {:.3}, rms residual {:.2} kg/(m s)",
                    f.c, f.c_error, f.k, f.k_error, f.beta, f.beta_error, f.rms
                );
            }
            None => {
                let _ = writeln!(md, "- {label}: too few openings to fit");
            }
        }
    }
    md.push('\n');
}

/// The report: per grid, the table of openings and both fits (`beta = 3/2` and free), and
/// with three grids the rates extrapolated to zero cell size and their fits, as Markdown.
pub fn report(grids: &[Vec<Opening>], d: f64) -> String {
    let mut md = String::new();
    for g in grids {
        let h = g[0].cell;
        let _ = writeln!(
            md,
            "**Cells of {:.4} m** ({} openings; d = {d} m, rho_b = {:.1} kg/m^3)\n",
            h,
            g.len(),
            g[0].bulk_density
        );
        md.push_str("| D (m) | D / d | D / h | W (kg/(m s)) | run |\n|---|---|---|---|---|\n");
        for p in g {
            let _ = writeln!(
                md,
                "| {:.4} | {:.1} | {:.1} | {:.2} +- {:.2} | {} |",
                p.width,
                p.width / d,
                p.width / h,
                p.rate,
                p.rate_error,
                p.run.display()
            );
        }
        md.push('\n');
        fits(&mut md, g, d);
    }
    if let Some((r, ex)) = extrapolate(grids) {
        let _ = writeln!(
            md,
            "**Extrapolated to zero cell size** (Richardson from the three finest grids, cells \
             shrinking by {r:.2}; {} of {} openings converging; the error column is the \
             extrapolation's distance from the finest grid)\n",
            ex.len(),
            grids[grids.len() - 1].len()
        );
        md.push_str("| D (m) | D / d | W, coarsest to finest (kg/(m s)) | order | W extrapolated (kg/(m s)) |\n|---|---|---|---|---|\n");
        for e in &ex {
            let _ = writeln!(
                md,
                "| {:.4} | {:.1} | {:.2} / {:.2} / {:.2} | {:.2} | {:.2} +- {:.2} |",
                e.opening.width,
                e.opening.width / d,
                e.rates[0],
                e.rates[1],
                e.rates[2],
                e.order,
                e.opening.rate,
                e.opening.rate_error
            );
        }
        md.push('\n');
        let points: Vec<Opening> = ex.into_iter().map(|e| e.opening).collect();
        fits(&mut md, &points, d);
    }
    md
}

/// Draws `W` against `D` for every grid, with the `beta = 3/2` fit of each (hollow markers,
/// evaluated at 16 openings across the measured range).
pub fn figure(grids: &[Vec<Opening>], d: f64, path: &Path) -> Result<(), String> {
    plot::register_font()?;
    let mut series = Vec::new();
    let extrapolated = extrapolate(grids)
        .map(|(_, ex)| ex.into_iter().map(|e| e.opening).collect::<Vec<_>>())
        .filter(|points| !points.is_empty());
    for g in grids.iter().chain(&extrapolated) {
        let h = g[0].cell;
        let name = if h > 0.0 {
            format!("h = {:.1} mm", h * 1e3)
        } else {
            "h -> 0 (extrapolated)".to_string()
        };
        series.push(Series {
            label: name.clone(),
            points: g.iter().map(|p| (p.width / d, p.rate)).collect(),
            hollow: false,
            band: None,
        });
        if let Some(f) = fit(g, d, Some(1.5)) {
            let (lo, hi) = (g[0].width, g[g.len() - 1].width);
            series.push(Series {
                label: format!("fit, {name}: C {:.2}, k {:.1}", f.c, f.k),
                points: (0..16)
                    .map(|i| {
                        let w = lo + (hi - lo) * i as f64 / 15.0;
                        (w / d, rate(&f, w, g[0].bulk_density, d))
                    })
                    .collect(),
                hollow: true,
                band: None,
            });
        }
    }
    plot::curves(
        path,
        "Silo discharge against the opening, with Beverloo's 2D law",
        "D / d",
        "W (kg/(m s))",
        &series,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn openings(c: f64, k: f64, beta: f64, d: f64) -> Vec<Opening> {
        [0.04, 0.06, 0.08, 0.10, 0.12]
            .iter()
            .map(|&w| Opening {
                run: PathBuf::new(),
                width: w,
                cell: 0.01,
                bulk_density: 1011.2,
                rate: c * 1011.2 * G.sqrt() * (w - k * d).powf(beta),
                rate_error: 0.0,
            })
            .collect()
    }

    #[test]
    fn the_fit_recovers_a_law_it_was_given() {
        let d = 0.005;
        let exact = fit(&openings(1.2, 2.5, 1.5, d), d, Some(1.5)).unwrap();
        assert!(
            (exact.c - 1.2).abs() < 1e-6 && (exact.k - 2.5).abs() < 1e-5,
            "{exact:?}"
        );
        assert!(exact.rms < 1e-6 && exact.c_error < 1e-5);
        let free = fit(&openings(0.8, 4.0, 1.25, d), d, None).unwrap();
        assert!(
            (free.beta - 1.25).abs() < 1e-4 && (free.k - 4.0).abs() < 1e-3,
            "{free:?}"
        );
        // Too few openings for three parameters.
        assert!(fit(&openings(0.8, 4.0, 1.25, d)[..3], d, None).is_none());
    }

    /// Rates that converge as `W(h) = W0 - A h^p` on three grids halving the cell give back
    /// `W0` and `p`; a grid whose rate overshoots leaves its opening out.
    #[test]
    fn three_grids_extrapolate_to_the_rate_they_converge_to() {
        let grid = |h: f64| {
            let mut g = openings(1.0, 1.0, 1.5, 0.005);
            for p in &mut g {
                p.cell = h;
                p.rate -= 40.0 * (h / 0.01).powf(1.3) * p.width / 0.12;
            }
            g
        };
        let mut grids = vec![grid(0.02), grid(0.01), grid(0.005), grid(0.0025)];
        grids[3][4].rate = grids[2][4].rate - 1.0;
        let exact = openings(1.0, 1.0, 1.5, 0.005);
        let (r, ex) = extrapolate(&grids).unwrap();
        assert!((r - 2.0).abs() < 1e-12);
        assert_eq!(ex.len(), 4, "the overshooting opening is left out");
        for (e, w) in ex.iter().zip(&exact) {
            assert!((e.order - 1.3).abs() < 1e-9, "{e:?}");
            assert!((e.opening.rate - w.rate).abs() < 1e-9 * w.rate, "{e:?}");
            assert!(e.opening.cell == 0.0 && e.opening.rate_error > 0.0);
        }
        assert!(report(&grids, 0.005).contains("Extrapolated to zero cell size"));
        // Unequal ratios, or two grids: nothing extrapolated.
        assert!(extrapolate(&[grid(0.02), grid(0.01), grid(0.004)]).is_none());
        assert!(extrapolate(&grids[..2]).is_none());
    }

    #[test]
    fn runs_group_by_grid_finest_last() {
        let mut runs = openings(1.0, 1.0, 1.5, 0.005);
        runs[1].cell = 0.005;
        runs[3].cell = 0.005;
        let grids = by_grid(runs);
        assert_eq!(grids.len(), 2);
        assert_eq!(grids[0].len(), 3);
        assert_eq!(
            grids[1].iter().map(|p| p.width).collect::<Vec<_>>(),
            [0.06, 0.10]
        );
    }
}
