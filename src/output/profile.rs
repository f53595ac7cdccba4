//! `VelocityProfile(..)`: a flowing layer's down-slope velocity against height, at a fixed
//! interval: the profile a chute flow is judged by (the Bagnold profile of mu(I),
//! docs/VALIDATION.md "Steady chute flow").
//!
//! Per cell row, the mass-weighted mean `vx` of the body's points whose centres lie in it,
//! across the whole width (a periodic chute is uniform along x). `velocity_profile.csv` has
//! `t` and one column per row (`y` of its centre); a row without points has an empty value.
//! The summary's `velocity_profile` gives, at the last record, the layer's mean `vx`
//! (mass-weighted over all its points), its surface speed (the highest row holding at least
//! half the points of the fullest row, so a few thrown grains are not the surface) and that
//! row's height.

use bevy_ecs::prelude::*;
use serde::Serialize;

use crate::body::Points;
use crate::carry::{Carried, carried, restored};
use crate::grid::GridGeometry;
use crate::output::summary::Section;
use crate::output::{
    Output, OutputFaults, RunDir, check_every, due_points, series_csv, write_or_fault,
};
use crate::plugin::Install;
use crate::registry::Item;
use crate::resources::Clock;
use crate::resources::Interval;
use crate::step::StepSet;

#[derive(Clone, Debug, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VelocityProfile {
    /// The flowing body.
    pub body: String,
    /// Interval between records (s).
    pub every: f64,
}

/// One record: per cell row the mean `vx` (NaN where empty) and the number of points, and
/// the body's mean `vx`.
#[derive(Clone, Debug, PartialEq, Serialize, serde::Deserialize)]
pub struct Profile {
    pub speeds: Vec<f64>,
    pub counts: Vec<usize>,
    pub mean_speed: f64,
}

impl Profile {
    /// Measures `points` over the rows of `grid`.
    pub fn measure(points: &Points, grid: &GridGeometry) -> Profile {
        let rows = grid.cells[1];
        let (mut momentum, mut mass, mut counts) =
            (vec![0.0; rows], vec![0.0; rows], vec![0; rows]);
        let (mut total_p, mut total_m) = (0.0, 0.0);
        for k in 0..points.len() {
            let (m, vx) = (points.mass[k], points.velocity[k].x);
            total_p += m * vx;
            total_m += m;
            let j = ((points.position[k].y - grid.origin.y) / grid.cell_size).floor();
            if j >= 0.0 && (j as usize) < rows {
                momentum[j as usize] += m * vx;
                mass[j as usize] += m;
                counts[j as usize] += 1;
            }
        }
        Profile {
            speeds: momentum
                .iter()
                .zip(&mass)
                .map(|(p, m)| if *m > 0.0 { p / m } else { f64::NAN })
                .collect(),
            counts,
            mean_speed: if total_m > 0.0 {
                total_p / total_m
            } else {
                0.0
            },
        }
    }

    /// The surface row: the highest holding at least half the points of the fullest row.
    pub fn surface(&self) -> Option<usize> {
        let full = self.counts.iter().copied().max()?;
        (0..self.counts.len())
            .rev()
            .find(|&j| full > 0 && 2 * self.counts[j] >= full)
    }
}

/// The records so far.
#[derive(Resource, Clone, Debug)]
pub struct ProfileRecord {
    /// The body, found at install.
    body: Option<Entity>,
    interval: Interval,
    pub times: Vec<f64>,
    pub profiles: Vec<Profile>,
}

/// The summary's `velocity_profile`: the last record's speeds and surface.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ProfileSummary {
    /// When the last record was taken (s).
    pub time: f64,
    pub mean_speed: f64,
    pub surface_speed: f64,
    /// The centre of the surface row (m).
    pub surface_height: f64,
}

impl ProfileRecord {
    /// The last record's summary, on `grid` (`None` before a record with points).
    pub fn summary(&self, grid: &GridGeometry) -> Option<ProfileSummary> {
        let (time, p) = (*self.times.last()?, self.profiles.last()?);
        let j = p.surface()?;
        Some(ProfileSummary {
            time,
            mean_speed: p.mean_speed,
            surface_speed: p.speeds[j],
            surface_height: grid.origin.y + (j as f64 + 0.5) * grid.cell_size,
        })
    }
}

impl Item for VelocityProfile {
    const NAME: &'static str = "VelocityProfile";
    fn validate(&self) -> Result<(), String> {
        check_every(self.every)
    }
}

impl Output for VelocityProfile {
    fn bodies(&self) -> Vec<&str> {
        vec![&self.body]
    }

    fn install(&self, sim: &mut Install) {
        let body = sim.body(&self.body);
        sim.insert_resource(ProfileRecord {
            body,
            interval: Interval::new(self.every),
            times: Vec::new(),
            profiles: Vec::new(),
        });
        sim.add_systems(StepSet::Output, record_profile);
    }

    /// `velocity_profile`: the mean and surface speeds (m/s) and the surface row's height
    /// (m) at the last record.
    fn summary(&self, world: &World) -> Section {
        let grid = world.resource::<GridGeometry>();
        let entry = world
            .get_resource::<ProfileRecord>()
            .and_then(|r| r.summary(grid));
        let mut section = Section::entry("velocity_profile", serde_json::json!(entry));
        section.units = [
            ("time", "s"),
            ("mean_speed", "m/s"),
            ("surface_speed", "m/s"),
            ("surface_height", "m"),
        ]
        .iter()
        .map(|(k, u)| (format!("velocity_profile.{k}"), u.to_string()))
        .collect();
        section.headline = Some(match &entry {
            Some(e) => format!(
                "velocity profile at t = {:.3} s: mean {:.4} m/s, surface {:.4} m/s at y = {:.4} m",
                e.time, e.mean_speed, e.surface_speed, e.surface_height
            ),
            None => format!(
                "velocity profile: not measured (no points of body \"{}\")",
                self.body
            ),
        });
        section
    }

    /// The record so far: its schedule and the profiles.
    fn save(&self, world: &World) -> Carried {
        let r = world.resource::<ProfileRecord>();
        carried(&(&r.interval, &r.times, &r.profiles))
    }

    fn restore(&self, world: &mut World, state: &[u8]) -> Result<(), String> {
        let mut r = world.resource_mut::<ProfileRecord>();
        (r.interval, r.times, r.profiles) = restored(state)?;
        Ok(())
    }
}

fn record_profile(
    clock: Res<Clock>,
    dir: Res<RunDir>,
    grid: Res<GridGeometry>,
    mut record: ResMut<ProfileRecord>,
    faults: Res<OutputFaults>,
    bodies: Query<&Points>,
) {
    let rec = &mut *record;
    let Some(points) = due_points(&mut rec.interval, &clock, &bodies, rec.body) else {
        return;
    };
    record.times.push(clock.time);
    record.profiles.push(Profile::measure(points, &grid));
    if let Some(dir) = &dir.0 {
        let labels: Vec<String> = (0..grid.cells[1])
            .map(|j| format!("y{:.5}", grid.origin.y + (j as f64 + 0.5) * grid.cell_size))
            .collect();
        let rows: Vec<Vec<f64>> = record.profiles.iter().map(|p| p.speeds.clone()).collect();
        let csv = series_csv(&labels, &record.times, &rows);
        write_or_fault(
            &dir.join("velocity_profile.csv"),
            csv.as_bytes(),
            &clock,
            &faults,
        );
    }
}
