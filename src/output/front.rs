//! `PressureFront(..)`: the pressure space-time diagram of the paper's section 4.3.1 and the
//! speed of the front it shows.
//!
//! As the paper (after Clark et al. 2015): the points of one body inside a sector below an
//! impact point (90 degrees, symmetric about the downward vertical, by default) are binned by
//! their distance from that point, and each bin's mean pressure is recorded at a fixed
//! interval. The mean is of the pressure *change* since t = 0, so the lithostatic pressure
//! the bed starts with does not hide a weak front. The front reaches a bin when that bin's
//! mean rises through half of its largest value (interpolated between records, which is
//! insensitive to how much the numerical front is smeared); the front speed is the
//! least-squares slope of bin radius against arrival time. The diagram goes to
//! `pressure_front.csv` (`t` and one column per bin centre) and the speed to `summary.json`
//! (`pressure_front`). The record lives in memory and is carried over checkpoints, so a
//! resumed run continues it.

use bevy_ecs::prelude::*;
use glam::DVec2;
use serde::{Deserialize, Serialize};

use crate::body::Points;
use crate::carry::{Carried, carried, restored};
use crate::linefit::line_fit;
use crate::output::summary::Section;
use crate::output::{
    Output, OutputFaults, RunDir, check_every, due_points, series_csv, write_or_fault,
};
use crate::plugin::Install;
use crate::registry::Item;
use crate::resources::Clock;
use crate::resources::Interval;
use crate::step::StepSet;

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PressureFront {
    /// The body whose pressure is binned (the bed).
    pub body: String,
    /// The impact point (m).
    pub centre: DVec2,
    /// Outer radius of the last bin (m).
    pub radius: f64,
    /// Number of radial bins.
    pub bins: usize,
    /// Interval between records (s); the paper's camera ran at 40 kHz (2.5e-5 s).
    pub every: f64,
    /// Opening of the sector below the impact point (degrees).
    #[serde(default = "ninety")]
    pub sector: f64,
}

fn ninety() -> f64 {
    90.0
}

/// The fitted front, as `summary.json` reports it.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct FrontMetrics {
    /// Least-squares slope of bin radius against arrival time (m/s).
    pub speed: f64,
    /// Bins the front reached (of `bins`).
    pub bins_reached: usize,
    /// `(radius, arrival time)` of each bin reached.
    pub arrivals: Vec<(f64, f64)>,
}

/// The space-time record.
#[derive(Resource, Clone, Debug)]
pub struct PressureRecord {
    pub spec: PressureFront,
    /// The body, found at install.
    body: Option<Entity>,
    interval: Interval,
    /// Each point's pressure at t = 0 (taken at the first record).
    initial: Vec<f64>,
    pub times: Vec<f64>,
    /// Mean pressure change per bin, one row per record.
    pub rows: Vec<Vec<f64>>,
}

impl PressureRecord {
    /// Bin centres (m).
    pub fn radii(&self) -> Vec<f64> {
        let w = self.spec.radius / self.spec.bins as f64;
        (0..self.spec.bins).map(|k| (k as f64 + 0.5) * w).collect()
    }

    /// The front's arrivals and speed; `None` if fewer than two bins saw it.
    pub fn front(&self) -> Option<FrontMetrics> {
        let radii = self.radii();
        let mut arrivals = Vec::new();
        for (b, &r) in radii.iter().enumerate() {
            let series: Vec<f64> = self.rows.iter().map(|row| row[b]).collect();
            if let Some(t) = half_rise(&self.times, &series) {
                arrivals.push((r, t));
            }
        }
        let points: Vec<(f64, f64)> = arrivals.iter().map(|&(r, t)| (t, r)).collect();
        let (_, speed) = line_fit(&points)?;
        Some(FrontMetrics {
            speed,
            bins_reached: arrivals.len(),
            arrivals,
        })
    }

    fn csv(&self) -> String {
        let labels: Vec<String> = self.radii().iter().map(|r| format!("r{r:.5}")).collect();
        series_csv(&labels, &self.times, &self.rows)
    }
}

/// The time at which `values` first rises through half of its largest value, interpolated
/// linearly between records; `None` if it never rises above zero.
pub fn half_rise(times: &[f64], values: &[f64]) -> Option<f64> {
    let peak = values.iter().copied().fold(0.0f64, f64::max);
    if peak.is_nan() || peak <= 0.0 {
        return None;
    }
    let level = 0.5 * peak;
    let k = values.iter().position(|&v| v >= level)?;
    if k == 0 {
        return Some(times[0]);
    }
    let (v0, v1) = (values[k - 1], values[k]);
    Some(times[k - 1] + (times[k] - times[k - 1]) * (level - v0) / (v1 - v0))
}

impl Item for PressureFront {
    const NAME: &'static str = "PressureFront";
    fn validate(&self) -> Result<(), String> {
        if !(self.centre.is_finite()) {
            return Err("centre must be finite".into());
        }
        if !(self.radius.is_finite() && self.radius > 0.0) {
            return Err(format!("radius must be positive, got {}", self.radius));
        }
        if !(1..=10_000).contains(&self.bins) {
            return Err(format!("bins must be 1 to 10000, got {}", self.bins));
        }
        check_every(self.every)?;
        if !(self.sector > 0.0 && self.sector <= 360.0) {
            return Err(format!(
                "sector must be in (0, 360] degrees, got {}",
                self.sector
            ));
        }
        Ok(())
    }
}

impl Output for PressureFront {
    fn bodies(&self) -> Vec<&str> {
        vec![&self.body]
    }

    /// `pressure_front`: the front's speed and arrivals (`null` if fewer than two bins saw
    /// it).
    fn summary(&self, world: &World) -> Section {
        let front = world
            .get_resource::<PressureRecord>()
            .and_then(|r| r.front());
        let mut section = Section::entry("pressure_front", serde_json::json!(front));
        section.units = vec![("pressure_front.speed".to_string(), "m/s".to_string())];
        section.headline = Some(match &front {
            Some(f) => format!(
                "pressure front: {:.1} m/s over {} bins",
                f.speed, f.bins_reached
            ),
            None => "pressure front: not measured (fewer than two bins saw it)".to_string(),
        });
        section
    }

    fn install(&self, sim: &mut Install) {
        let body = sim.body(&self.body);
        sim.insert_resource(PressureRecord {
            spec: self.clone(),
            body,
            interval: Interval::new(self.every),
            initial: Vec::new(),
            times: Vec::new(),
            rows: Vec::new(),
        });
        sim.add_systems(StepSet::Output, record_pressure);
    }

    /// The record so far: its schedule, the pressures at t = 0, the rows.
    fn save(&self, world: &World) -> Carried {
        let r = world.resource::<PressureRecord>();
        carried(&(&r.interval, &r.initial, &r.times, &r.rows))
    }

    fn restore(&self, world: &mut World, state: &[u8]) -> Result<(), String> {
        let mut r = world.resource_mut::<PressureRecord>();
        (r.interval, r.initial, r.times, r.rows) = restored(state)?;
        Ok(())
    }
}

fn record_pressure(
    clock: Res<Clock>,
    dir: Res<RunDir>,
    mut record: ResMut<PressureRecord>,
    faults: Res<OutputFaults>,
    bodies: Query<&Points>,
) {
    let rec = &mut *record;
    let Some(points) = due_points(&mut rec.interval, &clock, &bodies, rec.body) else {
        return;
    };
    if record.initial.is_empty() {
        record.initial = points.stress.iter().map(|s| s.pressure()).collect();
    }
    let spec = &record.spec;
    let (centre, width) = (spec.centre, spec.radius / spec.bins as f64);
    let half_angle = 0.5 * spec.sector.to_radians();
    let (mut sum, mut count) = (vec![0.0; spec.bins], vec![0usize; spec.bins]);
    for (k, x) in points.position.iter().enumerate() {
        let d = *x - centre;
        let r = d.length();
        if points.mass[k] == 0.0 || r >= spec.radius {
            continue;
        }
        // Angle from the downward vertical.
        if d.x.abs().atan2(-d.y) > half_angle {
            continue;
        }
        let b = ((r / width) as usize).min(spec.bins - 1);
        sum[b] += points.stress[k].pressure() - record.initial[k];
        count[b] += 1;
    }
    let row: Vec<f64> = sum
        .iter()
        .zip(&count)
        .map(|(s, &c)| if c > 0 { s / c as f64 } else { 0.0 })
        .collect();
    record.times.push(clock.time);
    record.rows.push(row);
    if let Some(dir) = &dir.0 {
        let csv = record.csv();
        write_or_fault(
            &dir.join("pressure_front.csv"),
            csv.as_bytes(),
            &clock,
            &faults,
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn half_rise_interpolates_between_records() {
        let t = [0.0, 1.0, 2.0, 3.0];
        // Peak 6, level 3: crossed between 2 (t = 1) and 6 (t = 2), a quarter of the way.
        assert_eq!(half_rise(&t, &[0.0, 2.0, 6.0, 4.0]), Some(1.25));
        assert_eq!(half_rise(&t, &[0.0, 0.0, 0.0, 0.0]), None);
        assert_eq!(half_rise(&t, &[0.0, -1.0, -3.0, 0.0]), None);
    }
}
