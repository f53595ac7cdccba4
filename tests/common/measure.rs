//! Measurements on the step's verification problems with analytic answers, shared by the
//! engine's tests and the accuracy study (`cargo run --release -p regolith-lab --example
//! accuracy`, which includes this file by path).
//!
//! Each function runs a prepared scene and returns the measured quantity; comparing it with
//! the analytic value (and choosing a tolerance) is the caller's business.
#![allow(dead_code)]

use std::f64::consts::FRAC_PI_2;

use regolith::error::Fault;
use regolith::linefit::line_fit;
use regolith::scene::Scene;
use regolith::sim::Simulation;

/// Times where `v` changes sign, linearly interpolated between samples.
pub fn zero_crossings(t: &[f64], v: &[f64]) -> Vec<f64> {
    let mut out = Vec::new();
    for k in 1..t.len() {
        let (a, b) = (v[k - 1], v[k]);
        if a != 0.0 && a.signum() != b.signum() {
            out.push(t[k - 1] + (t[k] - t[k - 1]) * a / (a - b));
        }
    }
    out
}

/// First axial mode of a bar fixed at x = 0 and free at `length`: sets the mode shape
/// `v0 sin(pi x / 2L)` on body `body`, runs the scene and returns the period measured from
/// the zero crossings of the centre-of-mass velocity (`None` if fewer than four crossings).
pub fn bar_mode_period(
    scene: &Scene,
    body: &str,
    length: f64,
    v0: f64,
) -> Result<Option<f64>, Fault> {
    let mut sim = Simulation::new(scene);
    if let Some(mut p) = sim.points_mut(body) {
        for k in 0..p.len() {
            let x = p.position[k].x - scene.domain.origin.x;
            p.velocity[k].x = v0 * (FRAC_PI_2 * x / length).sin();
        }
    }
    sim.run(|_| {})?;
    let tr = sim.trajectory();
    let Some(col) = tr.column(body, "vx") else {
        return Ok(None);
    };
    let (t, vx) = (tr.series(0), tr.series(col));
    // The t = 0 row was recorded before the mode shape was set.
    let z = zero_crossings(&t[1..], &vx[1..]);
    if z.len() < 4 {
        return Ok(None);
    }
    Ok(Some(2.0 * (z[z.len() - 1] - z[0]) / (z.len() - 1) as f64))
}

/// A compression front entering a bar that moves at `-v0` towards its fixed end at x = 0:
/// the arrival time at each station is when the mean x velocity of the points within
/// `half_width` of it rises through `-v0/2`. Returns the least-squares speed through the
/// (station, arrival) pairs, or `None` if the front missed a station.
pub fn front_speed(
    scene: &Scene,
    body: &str,
    stations: &[f64],
    half_width: f64,
    v0: f64,
) -> Result<Option<f64>, Fault> {
    let mut sim = Simulation::new(scene);
    let mut arrival = vec![f64::NAN; stations.len()];
    let mut previous = vec![-v0; stations.len()];
    let mut t_prev = 0.0;
    while !sim.finished() {
        sim.step()?;
        let t = sim.clock().time;
        let Some(pts) = sim.points(body) else {
            return Ok(None);
        };
        for (k, &xs) in stations.iter().enumerate() {
            let (mut sum, mut count) = (0.0, 0.0);
            for (x, v) in pts.position.iter().zip(&pts.velocity) {
                if (x.x - xs).abs() < half_width {
                    sum += v.x;
                    count += 1.0;
                }
            }
            let mean = sum / count;
            let level = -0.5 * v0;
            if arrival[k].is_nan() && mean > level {
                arrival[k] = t_prev + (t - t_prev) * (level - previous[k]) / (mean - previous[k]);
            }
            previous[k] = mean;
        }
        t_prev = t;
    }
    if arrival.iter().any(|a| !a.is_finite()) {
        return Ok(None);
    }
    let points: Vec<(f64, f64)> = arrival
        .iter()
        .copied()
        .zip(stations.iter().copied())
        .collect();
    Ok(line_fit(&points).map(|(_, speed)| speed))
}

/// Largest stress component magnitude seen on any point of `body` over the run.
pub fn largest_stress(scene: &Scene, body: &str) -> Result<f64, Fault> {
    let mut sim = Simulation::new(scene);
    let mut worst: f64 = 0.0;
    while !sim.finished() {
        sim.step()?;
        if let Some(p) = sim.points(body) {
            for s in &p.stress {
                worst = worst
                    .max(s.xx.abs())
                    .max(s.yy.abs())
                    .max(s.xy.abs())
                    .max(s.zz.abs());
            }
        }
    }
    Ok(worst)
}
