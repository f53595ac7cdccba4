//! Impact diagnostics as the paper defines them (section 4.2), from an intruder's
//! centre-of-mass trajectory.
//!
//! * final depth: the vertical displacement of the centre of mass from first contact to the
//!   end of the run;
//! * stopping time: the last time the position differs from its final value by more than
//!   0.2% of the final depth (measured from first contact);
//! * impact energy: the intruder's kinetic energy at first contact (J per metre of
//!   thickness);
//! * peak deceleration: the largest upward acceleration after contact, from the
//!   centre-of-mass velocity differenced between output rows (so it is the mean over one
//!   output interval; a finer `output_every` resolves sharper peaks).
//!
//! A scene asks for them with the output `Impact(body: "intruder", surface: 0.6825)` (the
//! body must be tracked): first contact is the first output row at which the body's centre
//! of mass is within its initial height above its lowest point of `surface`. They appear in
//! `summary.json` under `impact`.

use bevy_ecs::prelude::*;
use serde::{Deserialize, Serialize};

use crate::body::{Body, Points};
use crate::output::Output;

/// The paper's impact measures.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ImpactMetrics {
    pub contact_time: f64,
    pub final_depth: f64,
    pub stopping_time: f64,
    pub impact_energy: f64,
    pub peak_deceleration: f64,
}

/// Computes the measures from output rows `(t, y, vy)` of the centre of mass, the index of
/// the first row in contact, and the intruder's mass per unit thickness. `None` without
/// contact or with fewer than two rows after it.
pub fn analyse(
    t: &[f64],
    y: &[f64],
    vy: &[f64],
    contact: usize,
    mass: f64,
) -> Option<ImpactMetrics> {
    let n = t.len();
    if contact + 1 >= n {
        return None;
    }
    let final_y = y[n - 1];
    let depth = y[contact] - final_y;
    let tolerance = 0.002 * depth.abs();
    let last_away = (contact..n)
        .rev()
        .find(|&k| (y[k] - final_y).abs() > tolerance);
    let stopping = last_away.map_or(0.0, |k| t[k] - t[contact]);
    let peak = (contact + 1..n)
        .map(|k| (vy[k] - vy[k - 1]) / (t[k] - t[k - 1]))
        .fold(0.0, f64::max);
    Some(ImpactMetrics {
        contact_time: t[contact],
        final_depth: depth,
        stopping_time: stopping,
        impact_energy: 0.5 * mass * vy[contact] * vy[contact],
        peak_deceleration: peak,
    })
}

/// `Impact(body: "intruder", surface: 0.6825)`: records the measures for `summary.json`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Impact {
    /// The impacting body (it must be `tracked`).
    pub body: String,
    /// Height of the free surface the body hits (m).
    pub surface: f64,
}

/// What the `Impact` output watches: the body, the surface, and how far the body's centre
/// of mass sits above its lowest point's domain at the start. First contact is the first trajectory
/// row where the centre of mass is within that offset of the surface, which needs nothing
/// but the trajectory (so it survives a checkpoint and resume).
#[derive(Resource, Clone, Debug)]
pub struct ImpactWatch {
    pub body: String,
    pub surface: f64,
    pub offset: f64,
}

impl ImpactWatch {
    /// The first row (times `t`, centre-of-mass heights `y`) in contact with the surface.
    pub fn contact_row(&self, y: &[f64]) -> Option<usize> {
        y.iter()
            .position(|&y| y - self.offset <= self.surface + 1e-12)
    }
}

impl Output for Impact {
    const NAME: &'static str = "Impact";

    fn validate(&self) -> Result<(), String> {
        if self.body.is_empty() {
            return Err("body must name the impacting body".into());
        }
        if !self.surface.is_finite() {
            return Err(format!(
                "surface must be a finite height (m), got {}",
                self.surface
            ));
        }
        Ok(())
    }

    fn install(&self, world: &mut World, _schedule: &mut Schedule) {
        let mut q = world.query::<(&Body, &Points)>();
        let offset = q
            .iter(world)
            .find(|(b, _)| b.name == self.body)
            .map(|(_, p)| {
                let state = crate::body::BodyState::measure(p);
                // The bottom of the lowest point's domain: a body placed with its outline
                // on the surface is in contact at once.
                let lowest = (0..p.len())
                    .map(|k| p.position[k].y - p.half_width[k])
                    .fold(f64::INFINITY, f64::min);
                state.centre_of_mass.y - lowest
            })
            .unwrap_or(f64::NAN);
        world.insert_resource(ImpactWatch {
            body: self.body.clone(),
            surface: self.surface,
            offset,
        });
    }
}
#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_constant_deceleration_is_measured_exactly() {
        // y = y0 - v0 t + a t^2 / 2 until it stops at t = v0 / a, then rest.
        let (y0, v0, a) = (1.0, 3.0, 20.0);
        let stop = v0 / a;
        let t: Vec<f64> = (0..=400).map(|k| k as f64 * 1e-3).collect();
        let y: Vec<f64> = t
            .iter()
            .map(|&t| {
                let s = t.min(stop);
                y0 - v0 * s + 0.5 * a * s * s
            })
            .collect();
        let vy: Vec<f64> = t
            .iter()
            .map(|&t| if t < stop { -v0 + a * t } else { 0.0 })
            .collect();
        let m = analyse(&t, &y, &vy, 0, 2.0).unwrap();
        assert!((m.final_depth - v0 * v0 / (2.0 * a)).abs() < 1e-12);
        assert!((m.impact_energy - 9.0).abs() < 1e-12);
        assert!((m.peak_deceleration - a).abs() < 1e-9);
        // the last row further than 0.2% of the depth from rest: (v0 - a t)^2 / 2a > 0.002 d
        let expected = stop - (2.0 * a * 0.002 * m.final_depth).sqrt() / a;
        assert!(
            (m.stopping_time - expected).abs() < 2e-3,
            "{} vs {expected}",
            m.stopping_time
        );
    }
}
