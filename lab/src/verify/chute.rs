//! Steady inclined (chute) flow: the mu(I) answer and what a run is measured by.
//!
//! A layer of depth `H` on a rough incline at angle `th`, periodic along the slope, has a
//! steady solution when `mu_s < tan th < mu_2`: the stress ratio is `tan th` everywhere, so
//! the inertial number is the constant `I = I_0 (tan th - mu_s) / (mu_2 - tan th)`, the
//! pressure is lithostatic, `p = rho_c g cos th (H - y)`, and the shear rate
//! `I sqrt(p / rho_s) / d` integrates to the Bagnold profile
//! `u(y) = (2/3) (I / d) sqrt(phi g cos th) (H^1.5 - (H - y)^1.5)`, `phi = rho_c / rho_s`.
//! Below `atan mu_s` the layer stops; above `atan mu_2` no steady state exists and the
//! layer accelerates at least at `g (sin th - mu_2 cos th)`, since the base can resist at
//! most `mu_2 p`.
//!
//! The dense-flow failures this guards against (docs/numerics.md) take seconds of simulated
//! time, so the measures are cheap enough to take often: the layer's top, its disconnected
//! fraction below the surface cells, whether its summed point volume still equals the area
//! it occupies, and the velocity profile against the analytic one.

use std::path::Path;

use glam::DVec2;

use regolith::body::{Phase, PointStates, Points};
use regolith::material::granular::TransPhase;
use regolith::plugin::Regolith;
use regolith::scene::Scene;
use regolith::sim::Simulation;
use regolith::stress::Stress;

/// Depth of the layer in `scenes/chute_flow_mui.ron` (m); `run` checks it against the scene.
pub const DEPTH: f64 = 0.1;

/// The mu(I) steady state of a layer of depth `depth` at angle `angle` (radians).
#[derive(Clone, Debug)]
pub struct Bagnold {
    pub angle: f64,
    pub depth: f64,
    /// The constant inertial number of the steady layer.
    pub inertial_number: f64,
    /// `(I / d) sqrt(phi g cos th)`, so that `u = k (2/3) (H^1.5 - (H - y)^1.5)`.
    rate: f64,
}

impl Bagnold {
    /// The steady state, or `None` when `tan th` is outside `(mu_s, mu_2)`.
    pub fn new(material: &TransPhase, angle: f64, depth: f64, gravity: f64) -> Option<Bagnold> {
        let t = angle.tan();
        if !(t > material.mu_s && t < material.mu_2) {
            return None;
        }
        let i = material.i_0 * (t - material.mu_s) / (material.mu_2 - t);
        let phi = material.critical_density / material.grain_density;
        let rate = i / material.grain_diameter * (phi * gravity * angle.cos()).sqrt();
        Some(Bagnold {
            angle,
            depth,
            inertial_number: i,
            rate,
        })
    }

    /// Down-slope speed at height `y` above the base.
    pub fn speed(&self, y: f64) -> f64 {
        let h = self.depth;
        let below = (h - y.clamp(0.0, h)).powf(1.5);
        self.rate * (2.0 / 3.0) * (h.powf(1.5) - below)
    }

    pub fn surface_speed(&self) -> f64 {
        self.speed(self.depth)
    }

    /// Depth-averaged speed, `(3/5) u_s`.
    pub fn mean_speed(&self) -> f64 {
        0.6 * self.surface_speed()
    }
}

/// A steady down-slope velocity profile to start a layer on and measure it against.
pub trait Steady {
    /// The layer's depth (m).
    fn depth(&self) -> f64;
    /// Down-slope speed at height `y` above the base (m/s).
    fn speed(&self, y: f64) -> f64;
    fn surface_speed(&self) -> f64 {
        self.speed(self.depth())
    }
}

impl Steady for Bagnold {
    fn depth(&self) -> f64 {
        self.depth
    }
    fn speed(&self, y: f64) -> f64 {
        Bagnold::speed(self, y)
    }
}

/// `g (sin th - mu_2 cos th)`: the least acceleration of a layer steeper than `atan mu_2`.
pub fn least_acceleration(material: &TransPhase, angle: f64, gravity: f64) -> f64 {
    gravity * (angle.sin() - material.mu_2 * angle.cos())
}

/// The paper's PS-1 photoelastic discs (docs/model.md §7), as the chute scenes use them.
pub fn ps1() -> TransPhase {
    let (shear, bulk) = regolith::material::elastic::moduli(2.0e7, 0.45);
    TransPhase {
        shear,
        bulk,
        critical_density: 0.79 * 1280.0,
        grain_density: 1280.0,
        grain_diameter: 5e-3,
        mu_s: 0.320,
        mu_2: 0.598,
        i_0: 0.278,
    }
}

/// Puts a layer of depth `depth` under tilted `gravity` into its lithostatic state (normal
/// stress `-p` on every plane, shear `T_xy = rho_c g_x (H - y)`, `p = rho_c |g_y| (H - y)`,
/// volumes on the state line `V = m / rho_c exp(-p / K)`) and, given a profile, moving
/// with it: a steady flow starts steady instead of after a transient of seconds.
pub fn start_steady(
    points: &mut Points,
    material: &TransPhase,
    gravity: DVec2,
    depth: f64,
    profile: Option<&dyn Steady>,
) {
    let rho = material.critical_density;
    for k in 0..points.len() {
        let below = (depth - points.position[k].y).max(0.0);
        let p = rho * -gravity.y * below;
        points.stress[k] = Stress {
            xy: rho * gravity.x * below,
            ..Stress::isotropic(p)
        };
        points.volume[k] = points.mass[k] / rho * (-p / material.bulk).exp();
        if let Some(b) = profile {
            points.velocity[k] = DVec2::new(b.speed(points.position[k].y), 0.0);
        }
    }
}

/// What one moment of a chute run is measured by.
#[derive(Clone, Copy, Debug, Default)]
pub struct ChuteState {
    /// Height of the layer's top: the 99th percentile of the points' heights plus half
    /// their lattice spacing (m).
    pub top: f64,
    /// Summed point volume over the area the layer occupies, `width * top`: 1 for an honest
    /// body (the dense layer's density differs from `rho_c` by `p / K ~ 1e-5`).
    pub volume_ratio: f64,
    /// Fraction of the points below the top cell row that are disconnected.
    pub disconnected_bulk: f64,
    /// Fraction of all points that are disconnected.
    pub disconnected: f64,
    /// Mass-weighted mean down-slope speed (m/s).
    pub mean_speed: f64,
    /// 95th percentile of the point speeds (m/s).
    pub speed_95: f64,
    /// Mass-weighted rms of the points' speed normal to the bed (m/s): a steady layer has
    /// none, so this is the size of any disturbance (docs/numerics.md, "What breaks the
    /// chute").
    pub normal_rms: f64,
    /// RMS over cell rows of (row-mean speed - analytic), over the analytic surface
    /// speed; `None` without a profile.
    pub profile_error: Option<f64>,
    /// The most points in one grid cell (the layer starts with `points_per_cell^2`): how far
    /// the points have crowded together (docs/numerics.md, "Points that keep their spacing").
    pub most_in_a_cell: usize,
    /// The normal-velocity modes along the slope (the grid-modes issue).
    pub modes: Modes,
}

/// The disturbance of a steady layer split by wavelength along the slope: a steady layer
/// moves parallel to its bed and is uniform along it, so every one of these is zero in the
/// steady state and grows or decays with a disturbance (docs/numerics.md, "What breaks the
/// chute").
///
/// Points are grouped into rows one lattice spacing high; in each row the speed normal to
/// the bed is written as a Fourier series along the slope, `v_y = sum_n a_n cos(2 pi n x /
/// W) + b_n sin(..)`, over the wavelengths `W / n` the periodic box admits down to two point
/// spacings. A mode's amplitude is the rms over the rows of `sqrt(a_n^2 + b_n^2)`.
#[derive(Clone, Copy, Debug, Default)]
pub struct Modes {
    /// Amplitude of the longest mode, one box length (m/s).
    pub box_length: f64,
    /// The largest amplitude among the modes of at most 2.5 cells (m/s): the grid-scale
    /// modes, which a continuum has no reason to prefer.
    pub grid_scale: f64,
    /// That mode's wavelength, in cells.
    pub grid_scale_cells: f64,
    /// The largest spread of point volume along a row below the surface cells, `(max -
    /// min) / mean`: a layer in 1D flow keeps every row's points at one `det F` (1e-13).
    pub volume_spread: f64,
}

impl Modes {
    /// The modes of `points` in a periodic box of width `width` on cells of size `cell`,
    /// below `top`.
    pub fn measure(points: &Points, width: f64, cell: f64, top: f64) -> Modes {
        let spacing = 2.0 * points.half_width[0];
        let rows = (top / spacing).ceil().max(1.0) as usize;
        let mut by_row: Vec<Vec<usize>> = vec![Vec::new(); rows];
        for (k, x) in points.position.iter().enumerate() {
            let r = ((x.y / spacing).floor().max(0.0) as usize).min(rows - 1);
            by_row[r].push(k);
        }
        let by_row: Vec<&Vec<usize>> = by_row.iter().filter(|r| !r.is_empty()).collect();
        let highest = (width / (2.0 * spacing)).floor().max(1.0) as usize;
        let amplitude = |n: usize| -> f64 {
            let k = std::f64::consts::TAU * n as f64 / width;
            let ms = by_row
                .iter()
                .map(|row| {
                    let (mut a, mut b) = (0.0, 0.0);
                    for &p in row.iter() {
                        let (s, c) = (k * points.position[p].x).sin_cos();
                        a += points.velocity[p].y * c;
                        b += points.velocity[p].y * s;
                    }
                    (a * a + b * b) * (2.0 / row.len() as f64).powi(2)
                })
                .sum::<f64>()
                / by_row.len() as f64;
            ms.sqrt()
        };
        let amplitudes: Vec<f64> = (1..=highest).map(amplitude).collect();
        let (mut grid_scale, mut grid_scale_cells) = (0.0, 0.0);
        for (n, &a) in (1..=highest).zip(&amplitudes) {
            let cells = width / n as f64 / cell;
            if cells <= 2.5 + 1e-9 && a >= grid_scale {
                (grid_scale, grid_scale_cells) = (a, cells);
            }
        }
        let volume_spread = by_row
            .iter()
            .filter(|row| row.iter().all(|&p| points.position[p].y < top - cell))
            .map(|row| {
                let v = row.iter().map(|&p| points.volume[p]);
                let (lo, hi) = v
                    .clone()
                    .fold((f64::MAX, f64::MIN), |(l, h), x| (l.min(x), h.max(x)));
                (hi - lo) * row.len() as f64 / v.sum::<f64>()
            })
            .fold(0.0, f64::max);
        Modes {
            box_length: amplitudes[0],
            grid_scale,
            grid_scale_cells,
            volume_spread,
        }
    }
}

/// A seeded disturbance: the normal velocity `amplitude sin(2 pi x / (wavelength h)) sin(pi
/// y / 2 H)`, zero on the rough base, largest at the top, added to a layer at its start.
#[derive(Clone, Copy, Debug)]
pub struct Disturbance {
    /// Peak normal speed (m/s).
    pub amplitude: f64,
    /// Wavelength along the slope, in cells.
    pub cells: f64,
}

impl Disturbance {
    /// Adds the disturbance to the points of a layer of depth `depth` on cells of `cell`.
    pub fn seed(&self, points: &mut Points, cell: f64, depth: f64) {
        let k = std::f64::consts::TAU / (self.cells * cell);
        for (x, v) in points.position.iter().zip(points.velocity.iter_mut()) {
            let across = (0.5 * std::f64::consts::PI * x.y / depth).sin();
            v.y += self.amplitude * (k * x.x).sin() * across;
        }
    }
}

/// Measures a chute layer of width `width` on a grid of cell size `cell`; `profile` is the
/// analytic steady state to compare the velocity with, if there is one.
pub fn measure(
    points: &Points,
    states: &PointStates,
    width: f64,
    cell: f64,
    profile: Option<&dyn Steady>,
) -> ChuteState {
    let n = points.len();
    if n == 0 {
        return ChuteState::default();
    }
    let spacing = 2.0 * points.half_width[0];
    let top = super::quantile(points.position.iter().map(|x| x.y).collect(), 0.99) + 0.5 * spacing;
    let volume: f64 = points.volume.iter().sum();
    let gas = |k: usize| states.phase[k] == Phase::Disconnected;
    let bulk: Vec<usize> = (0..n)
        .filter(|&k| points.position[k].y < top - cell)
        .collect();
    let disconnected_bulk =
        bulk.iter().filter(|&&k| gas(k)).count() as f64 / bulk.len().max(1) as f64;
    let mass: f64 = points.mass.iter().sum();
    let mean_speed = (0..n)
        .map(|k| points.mass[k] * points.velocity[k].x)
        .sum::<f64>()
        / mass;
    let profile_error = profile.map(|b| {
        let rows = (b.depth() / cell).round() as usize;
        let mut sums = vec![(0.0, 0usize); rows];
        for (x, v) in points.position.iter().zip(&points.velocity) {
            let r = (x.y / cell) as usize;
            if r < rows {
                sums[r].0 += v.x;
                sums[r].1 += 1;
            }
        }
        let errors: Vec<f64> = sums
            .iter()
            .enumerate()
            .filter(|(_, s)| s.1 > 0)
            .map(|(r, s)| s.0 / s.1 as f64 - b.speed((r as f64 + 0.5) * cell))
            .collect();
        let ms = errors.iter().map(|e| e * e).sum::<f64>() / errors.len().max(1) as f64;
        ms.sqrt() / b.surface_speed()
    });
    let mut per_cell = std::collections::HashMap::new();
    for x in &points.position {
        *per_cell
            .entry(((x.x / cell).floor() as i64, (x.y / cell).floor() as i64))
            .or_insert(0usize) += 1;
    }
    ChuteState {
        modes: Modes::measure(points, width, cell, top),
        most_in_a_cell: per_cell.values().copied().max().unwrap_or(0),
        top,
        volume_ratio: volume / (width * top),
        disconnected_bulk,
        disconnected: (0..n).filter(|&k| gas(k)).count() as f64 / n as f64,
        mean_speed,
        speed_95: super::quantile(points.velocity.iter().map(|v| v.length()).collect(), 0.95),
        normal_rms: ((0..n)
            .map(|k| points.mass[k] * points.velocity[k].y.powi(2))
            .sum::<f64>()
            / mass)
            .sqrt(),
        profile_error,
    }
}

/// Runs the chute scene at `path` (`scenes/chute_flow_mui.ron`) at `angle_deg` degrees with
/// `cells_per_depth` cells across the layer (even: the domain is half as wide as the
/// layer is deep), to `end` seconds, with further `--set` overrides `sets`. The layer starts
/// in its lithostatic state moving with `profile` (`start_steady`), and is measured against
/// it at t = 0, every `every` seconds and at the end (`each(t, state)`, once each); a
/// `disturbance` is seeded on top of the start. Returns the steps taken; a scene error or a
/// fault of the run is the error.
#[allow(clippy::too_many_arguments)]
pub fn run(
    path: &Path,
    angle_deg: f64,
    cells_per_depth: usize,
    end: f64,
    sets: &[String],
    profile: Option<&dyn Steady>,
    disturbance: Option<Disturbance>,
    every: f64,
    mut each: impl FnMut(f64, &ChuteState),
) -> Result<u64, String> {
    if !cells_per_depth.is_multiple_of(2) {
        return Err(format!(
            "cells per depth must be even (the domain is half as wide), got {cells_per_depth}"
        ));
    }
    let th = angle_deg.to_radians();
    let gravity = DVec2::new(9.81 * th.sin(), -9.81 * th.cos());
    let across = cells_per_depth / 2;
    let mut all = vec![
        format!("gravity=({}, {})", gravity.x, gravity.y),
        format!("domain.cells=({across}, {})", 3 * across),
        format!("time.end={end}"),
    ];
    all.extend(sets.iter().cloned());
    let scene = Scene::load(path, &all, &Regolith::default().registries())
        .map_err(|e| e.to_string())?
        .0;
    let mut sim = Simulation::new(&scene);
    let (width, cell) = (scene.domain.size.x, sim.grid().cell_size);
    let body = scene
        .bodies
        .first()
        .map(|b| b.name.clone())
        .unwrap_or_default();
    let material = ps1();
    let mut points = sim
        .points_mut(&body)
        .ok_or_else(|| format!("{}: no body to run", path.display()))?;
    start_steady(&mut points, &material, gravity, DEPTH, profile);
    if let Some(d) = disturbance {
        d.seed(&mut points, cell, DEPTH);
    }
    let state = |sim: &mut Simulation| {
        let mut q = sim.world.query::<(&Points, &PointStates)>();
        let (p, s) = q.single(&sim.world).expect("the chute scene has one body");
        measure(p, s, width, cell, profile)
    };
    let first = state(&mut sim);
    if (first.top - DEPTH).abs() > 0.5 * cell {
        return Err(format!(
            "{}: the layer's top is at {:.4} m, not at the {DEPTH} m the chute measures assume",
            path.display(),
            first.top
        ));
    }
    each(0.0, &first);
    let mut next = every;
    let mut sampled = true;
    while !sim.finished() {
        sim.step()
            .map_err(|e| format!("{angle_deg} degrees, {cells_per_depth} cells per depth: {e}"))?;
        let t = sim.clock().time;
        sampled = t >= next - 1e-9;
        if sampled {
            next += every;
            each(t, &state(&mut sim));
        }
    }
    if !sampled {
        each(sim.clock().time, &state(&mut sim));
    }
    Ok(sim.clock().step)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The numbers of the dense-flow issue: at 25 degrees on a 0.1 m layer I = 0.309 and
    /// u_s = 3.45 m/s; and the profile's slope is the mu(I) shear rate at each depth.
    #[test]
    fn the_profile_is_the_mu_i_solution() {
        let m = ps1();
        let b = Bagnold::new(&m, 25f64.to_radians(), 0.1, 9.81).unwrap();
        assert!(
            (b.inertial_number - 0.3088).abs() < 1e-4,
            "{}",
            b.inertial_number
        );
        assert!(
            (b.surface_speed() - 3.451).abs() < 2e-3,
            "{}",
            b.surface_speed()
        );
        for y in [0.01, 0.05, 0.09] {
            let rate = (b.speed(y + 1e-6) - b.speed(y - 1e-6)) / 2e-6;
            let p = m.critical_density * 9.81 * b.angle.cos() * (0.1 - y);
            let i = rate * m.grain_diameter * (m.grain_density / p).sqrt();
            assert!((i - b.inertial_number).abs() < 1e-6, "I = {i} at y = {y}");
        }
        assert!(Bagnold::new(&m, 15f64.to_radians(), 0.1, 9.81).is_none());
        assert!(Bagnold::new(&m, 35f64.to_radians(), 0.1, 9.81).is_none());
    }

    /// A lattice of 2 x 2 points per 10 mm cell in a box 4 cells long, given the seeded
    /// disturbance plus a box-length mode of 3e-5 m/s: the measure finds each amplitude
    /// (the seeded one is `A sin(pi y / 2H)` in each row, whose rms over the rows it
    /// returns) and the two-cell wavelength, and a volume spread of 1% in one row.
    #[test]
    fn the_modes_are_found_by_wavelength() {
        let (cell, width, depth) = (0.01, 0.04, 0.1);
        let mut points = Points::default();
        for j in 0..20 {
            for i in 0..8 {
                points.position.push(DVec2::new(
                    (i as f64 + 0.5) * 0.005,
                    (j as f64 + 0.5) * 0.005,
                ));
                points.velocity.push(DVec2::ZERO);
                points.volume.push(2.5e-5);
                points.half_width.push(0.0025);
            }
        }
        let seed = Disturbance {
            amplitude: 1e-4,
            cells: 2.0,
        };
        seed.seed(&mut points, cell, depth);
        for (x, v) in points.position.iter().zip(points.velocity.iter_mut()) {
            v.y += 3e-5 * (std::f64::consts::TAU * x.x / width).cos();
        }
        points.volume[8 * 5 + 3] *= 1.01;
        let m = Modes::measure(&points, width, cell, depth);
        let rows: Vec<f64> = (0..20)
            .map(|j| (0.5 * std::f64::consts::PI * (j as f64 + 0.5) * 0.005 / depth).sin())
            .collect();
        let rms = (rows.iter().map(|s| s * s).sum::<f64>() / 20.0).sqrt();
        assert_eq!(m.grid_scale_cells, 2.0);
        assert!(
            (m.grid_scale - 1e-4 * rms).abs() < 1e-12,
            "{} against {}",
            m.grid_scale,
            1e-4 * rms
        );
        assert!((m.box_length - 3e-5).abs() < 1e-12, "{}", m.box_length);
        let spread = 0.01 * 8.0 / 8.01;
        assert!(
            (m.volume_spread - spread).abs() < 1e-12,
            "{}",
            m.volume_spread
        );
    }
}
