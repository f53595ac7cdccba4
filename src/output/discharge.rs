//! `Discharge(..)`: how fast a body leaves the domain through its `Open` sides and segments
//! (a silo's orifice), or crosses a horizontal line (`height`), at a fixed interval, and its
//! steady rate.
//!
//! The mass out at a record is the body's mass at the first record minus its mass now
//! (retired points carry none), so it counts exactly what the walls retired. With
//! `height: y` it is instead the net mass that has crossed the line at height `y` downwards
//! since the start: every step, each point that changed side carries its mass across (up
//! counts negative), so the flux through a section of a hopper or a bin can be measured
//! without retiring anything. `discharge.csv`
//! has `t`, `mass_out` (kg per metre of thickness) and `rate` (kg/(m s), over the interval
//! since the previous record; empty at the first). The steady rate in `summary.json` is the
//! least-squares slope of the mass out against time over the records from `steady_from` on,
//! with the slope's standard error from the fit's residuals: a discharge that is not steady
//! over the window shows a large error. The record lives in memory (carried over checkpoints)
//! and the file is rewritten at each interval.

use bevy_ecs::prelude::*;
use serde::{Deserialize, Serialize};

use crate::body::Points;
use crate::carry::{Carried, carried, restored};
use crate::linefit::{line_fit, slope_error};
use crate::output::summary::Section;
use crate::output::{
    Output, OutputFaults, RunDir, check_every, due_points, points_of, series_csv, write_or_fault,
};
use crate::plugin::Install;
use crate::registry::Item;
use crate::resources::Clock;
use crate::resources::Interval;
use crate::scene_view::SceneView;
use crate::step::StepSet;

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Discharge {
    /// The body whose outflow is measured.
    pub body: String,
    /// Interval between records (s).
    pub every: f64,
    /// Start of the window over which the steady rate is fitted (s; default 0).
    #[serde(default)]
    pub steady_from: f64,
    /// Measure the mass crossing the horizontal line at this height (m) instead of the mass
    /// retired; none by default.
    #[serde(default)]
    pub height: Option<f64>,
}

/// The outflow so far.
#[derive(Resource, Clone, Debug)]
pub struct DischargeRecord {
    spec: Discharge,
    /// The body, found at install.
    body: Option<Entity>,
    interval: Interval,
    /// The body's mass at the first record (kg/m).
    start_mass: Option<f64>,
    pub times: Vec<f64>,
    pub mass_out: Vec<f64>,
    /// With a `height`: the net mass crossed downwards so far (kg/m), and which points are
    /// above the line (empty until the first step it is looked at).
    crossed: f64,
    above: Vec<bool>,
}

/// The `discharge` entry of `summary.json`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct DischargeSummary {
    /// Least-squares slope of the mass out over the window (kg/(m s)).
    pub steady_rate: f64,
    /// Its standard error (kg/(m s)).
    pub steady_rate_error: f64,
    /// The window fitted (s) and the records in it.
    pub window: [f64; 2],
    pub records: usize,
    /// Mass out at the last record (kg/m).
    pub mass_out: f64,
}

impl DischargeRecord {
    /// Carries every point that changed side of the line at height `y` across it.
    fn track(&mut self, points: &Points, y: f64) {
        if self.above.len() != points.len() {
            self.above = points.position.iter().map(|x| x.y > y).collect();
            return;
        }
        for ((above, x), &m) in self
            .above
            .iter_mut()
            .zip(&points.position)
            .zip(&points.mass)
        {
            let now = x.y > y;
            if now != *above {
                self.crossed += if now { -m } else { m };
                *above = now;
            }
        }
    }

    /// The steady rate over the records from `steady_from` on; `None` with fewer than three.
    pub fn summary(&self) -> Option<DischargeSummary> {
        let window: Vec<(f64, f64)> = self
            .times
            .iter()
            .zip(&self.mass_out)
            .filter(|(t, _)| **t >= self.spec.steady_from)
            .map(|(&t, &m)| (t, m))
            .collect();
        if window.len() < 3 {
            return None;
        }
        let (a, b) = line_fit(&window)?;
        Some(DischargeSummary {
            steady_rate: b,
            steady_rate_error: slope_error(&window, a, b)?,
            window: [window[0].0, window[window.len() - 1].0],
            records: window.len(),
            mass_out: *self.mass_out.last()?,
        })
    }
}

impl Item for Discharge {
    const NAME: &'static str = "Discharge";
    fn validate(&self) -> Result<(), String> {
        check_every(self.every)?;
        if let Some(y) = self.height
            && !y.is_finite()
        {
            return Err(format!("height must be a finite height (m), got {y}"));
        }
        if self.steady_from.is_finite() && self.steady_from >= 0.0 {
            Ok(())
        } else {
            Err(format!(
                "steady_from must be a time of at least 0 s, got {}",
                self.steady_from
            ))
        }
    }
}

impl Output for Discharge {
    fn bodies(&self) -> Vec<&str> {
        vec![&self.body]
    }

    fn check_scene(&self, scene: &SceneView) -> Result<(), String> {
        scene.body(&self.body)?;
        let grid = scene.grid();
        match self.height {
            Some(y) if !(grid.origin.y < y && y < grid.max().y) => Err(format!(
                "height {y} m is not inside the domain ({} to {} m)",
                grid.origin.y,
                grid.max().y
            )),
            _ => Ok(()),
        }
    }

    fn install(&self, sim: &mut Install) {
        let body = sim.body(&self.body);
        sim.insert_resource(DischargeRecord {
            spec: self.clone(),
            body,
            interval: Interval::new(self.every),
            start_mass: None,
            times: Vec::new(),
            mass_out: Vec::new(),
            crossed: 0.0,
            above: Vec::new(),
        });
        sim.add_systems(StepSet::Output, record_discharge);
    }

    /// `discharge`: the steady rate and its standard error, the window, the mass out.
    fn summary(&self, world: &World) -> Section {
        let summary = world
            .get_resource::<DischargeRecord>()
            .and_then(|r| r.summary());
        let mut section = Section::entry("discharge", serde_json::json!(summary));
        section.units = vec![
            ("discharge.steady_rate".into(), "kg/(m s)".into()),
            ("discharge.steady_rate_error".into(), "kg/(m s)".into()),
            ("discharge.window".into(), "s".into()),
            ("discharge.mass_out".into(), "kg/m".into()),
        ];
        let through = self
            .height
            .map_or(String::new(), |y| format!(" through y = {y} m"));
        section.headline = Some(match &summary {
            Some(s) => format!(
                "discharge{through}: steady rate {:.4} +- {:.4} kg/(m s) over t = {:.3}-{:.3} s ({} records); {:.4} kg/m out in all",
                s.steady_rate, s.steady_rate_error, s.window[0], s.window[1], s.records, s.mass_out
            ),
            None => format!(
                "discharge: not measured (fewer than three records from t = {} s)",
                self.steady_from
            ),
        });
        section
    }

    /// The record so far: its schedule, the starting mass, the mass out, and with a
    /// `height` the mass crossed and the points' sides of the line.
    fn save(&self, world: &World) -> Carried {
        let r = world.resource::<DischargeRecord>();
        if self.height.is_some() {
            carried(&(
                &r.interval,
                r.start_mass,
                &r.times,
                &r.mass_out,
                r.crossed,
                &r.above,
            ))
        } else {
            carried(&(&r.interval, r.start_mass, &r.times, &r.mass_out))
        }
    }

    fn restore(&self, world: &mut World, state: &[u8]) -> Result<(), String> {
        let mut r = world.resource_mut::<DischargeRecord>();
        if self.height.is_some() {
            (
                r.interval,
                r.start_mass,
                r.times,
                r.mass_out,
                r.crossed,
                r.above,
            ) = restored(state)?;
        } else {
            (r.interval, r.start_mass, r.times, r.mass_out) = restored(state)?;
        }
        Ok(())
    }
}

fn record_discharge(
    clock: Res<Clock>,
    dir: Res<RunDir>,
    mut record: ResMut<DischargeRecord>,
    faults: Res<OutputFaults>,
    bodies: Query<&Points>,
) {
    let rec = &mut *record;
    if let (Some(y), Some(points)) = (rec.spec.height, points_of(&bodies, rec.body)) {
        rec.track(points, y);
    }
    let Some(points) = due_points(&mut rec.interval, &clock, &bodies, rec.body) else {
        return;
    };
    let mass: f64 = points.mass.iter().sum();
    let start = *rec.start_mass.get_or_insert(mass);
    rec.times.push(clock.time);
    rec.mass_out.push(match rec.spec.height {
        Some(_) => rec.crossed,
        None => start - mass,
    });
    if let Some(dir) = &dir.0 {
        let labels = vec!["mass_out".to_string(), "rate".to_string()];
        let rows: Vec<Vec<f64>> = (0..rec.times.len())
            .map(|k| {
                let rate = if k == 0 {
                    f64::NAN
                } else {
                    (rec.mass_out[k] - rec.mass_out[k - 1]) / (rec.times[k] - rec.times[k - 1])
                };
                vec![rec.mass_out[k], rate]
            })
            .collect();
        let csv = series_csv(&labels, &rec.times, &rows);
        write_or_fault(&dir.join("discharge.csv"), csv.as_bytes(), &clock, &faults);
    }
}
