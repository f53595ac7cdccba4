//! `Runout(..)`: how far a granular body spreads and how high it stands, at a fixed
//! interval: a column collapse's runout and final height, the measures experiments report
//! (`(Lf - L0)/L0` and `Hf/H0` against the aspect ratio `a = H0/L0`, Lube et al. 2005), or
//! a chute layer's extent and thickness.
//!
//! The body is measured where it is dense, as `FreeSurface` draws its surface: over the
//! cells holding at least half the body's initial number of points per cell, so the thin
//! front of single points that runs ahead of a collapsing pile, and grains thrown above
//! it, do not count (the largest x of any point, which the lab's column study used before,
//! counted them: docs/GRANULAR.md). Within those cells the extent is the points' own, each
//! point reaching half its spacing beyond its centre, so a body at rest measures its
//! shape's width and height exactly. `runout.csv` has `t, left, right, length, height`
//! (m); the summary's `runout` gives the initial and final length and height, their
//! ratios and the aspect ratio, from the first and the last record.

use bevy_ecs::prelude::*;
use serde::{Deserialize, Serialize};

use crate::body::Points;
use crate::carry::{Carried, carried, restored};
use crate::grid::GridGeometry;
use crate::output::free_surface::DenseCells;
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
pub struct Runout {
    /// The granular body.
    pub body: String,
    /// Interval between records (s).
    pub every: f64,
}

/// The body's dense extent at one time (m).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Extent {
    pub left: f64,
    pub right: f64,
    /// The top of the highest dense point above the domain's origin.
    pub height: f64,
}

impl Extent {
    /// `right - left`.
    pub fn length(&self) -> f64 {
        self.right - self.left
    }

    /// The extent of the points in dense cells (`None` if no cell is dense).
    pub(crate) fn measure(
        points: &Points,
        grid: &GridGeometry,
        cells: &DenseCells,
    ) -> Option<Extent> {
        let nx = grid.cells[0];
        let mut extent: Option<Extent> = None;
        for (k, x) in points.position.iter().enumerate() {
            let c = (*x - grid.origin) / grid.cell_size;
            if points.mass[k] <= 0.0 || c.x < 0.0 || c.y < 0.0 {
                continue;
            }
            let (i, j) = (c.x as usize, c.y as usize);
            if i >= nx || j >= grid.cells[1] || !cells.dense(i, j) {
                continue;
            }
            let h = points.half_width[k];
            let top = x.y + h - grid.origin.y;
            let e = extent.get_or_insert(Extent {
                left: x.x - h,
                right: x.x + h,
                height: top,
            });
            e.left = e.left.min(x.x - h);
            e.right = e.right.max(x.x + h);
            e.height = e.height.max(top);
        }
        extent
    }
}

/// The records so far.
#[derive(Resource, Clone, Debug)]
pub struct RunoutRecord {
    /// The body, found at install.
    body: Option<Entity>,
    interval: Interval,
    /// Which cells the body fills (its points per cell at the first record carried over).
    cells: DenseCells,
    pub times: Vec<f64>,
    pub extents: Vec<Extent>,
}

/// The summary's `runout`: from the first record to the last.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RunoutSummary {
    pub initial_length: f64,
    pub initial_height: f64,
    pub final_length: f64,
    pub final_height: f64,
    /// `(Lf - L0)/L0`.
    pub runout_ratio: f64,
    /// `Hf/H0`.
    pub height_ratio: f64,
    /// `H0/L0`.
    pub aspect_ratio: f64,
    /// When the last record was taken (s).
    pub time: f64,
}

impl RunoutRecord {
    pub fn summary(&self) -> Option<RunoutSummary> {
        let (first, last) = (self.extents.first()?, self.extents.last()?);
        let (l0, h0) = (first.length(), first.height);
        Some(RunoutSummary {
            initial_length: l0,
            initial_height: h0,
            final_length: last.length(),
            final_height: last.height,
            runout_ratio: (last.length() - l0) / l0,
            height_ratio: last.height / h0,
            aspect_ratio: h0 / l0,
            time: *self.times.last()?,
        })
    }
}

impl Item for Runout {
    const NAME: &'static str = "Runout";
    fn validate(&self) -> Result<(), String> {
        check_every(self.every)
    }
}

impl Output for Runout {
    fn bodies(&self) -> Vec<&str> {
        vec![&self.body]
    }

    fn install(&self, sim: &mut Install) {
        let body = sim.body(&self.body);
        sim.insert_resource(RunoutRecord {
            body,
            interval: Interval::new(self.every),
            cells: DenseCells::default(),
            times: Vec::new(),
            extents: Vec::new(),
        });
        sim.add_systems(StepSet::Output, record_runout);
    }

    /// `runout`: the initial and final length and height (m), their ratios and the aspect
    /// ratio.
    fn summary(&self, world: &World) -> Section {
        let summary = world
            .get_resource::<RunoutRecord>()
            .and_then(|r| r.summary());
        let mut section = Section::entry("runout", serde_json::json!(summary));
        section.units = [
            "initial_length",
            "initial_height",
            "final_length",
            "final_height",
        ]
        .iter()
        .map(|k| (format!("runout.{k}"), "m".to_string()))
        .chain([("runout.time".to_string(), "s".to_string())])
        .collect();
        section.headline = Some(match &summary {
            Some(s) => format!(
                "runout: (Lf - L0)/L0 = {:.3}, Hf/H0 = {:.3} at t = {:.3} s (a = H0/L0 = {:.3}; L0 = {:.4} m, Lf = {:.4} m, H0 = {:.4} m, Hf = {:.4} m)",
                s.runout_ratio,
                s.height_ratio,
                s.time,
                s.aspect_ratio,
                s.initial_length,
                s.final_length,
                s.initial_height,
                s.final_height
            ),
            None => format!(
                "runout: not measured (no dense cell of body \"{}\")",
                self.body
            ),
        });
        section
    }

    /// The record so far: its schedule, the initial points per cell, the extents.
    fn save(&self, world: &World) -> Carried {
        let r = world.resource::<RunoutRecord>();
        carried(&(&r.interval, r.cells.full, &r.times, &r.extents))
    }

    fn restore(&self, world: &mut World, state: &[u8]) -> Result<(), String> {
        let mut r = world.resource_mut::<RunoutRecord>();
        (r.interval, r.cells.full, r.times, r.extents) = restored(state)?;
        Ok(())
    }
}

fn record_runout(
    clock: Res<Clock>,
    dir: Res<RunDir>,
    grid: Res<GridGeometry>,
    mut record: ResMut<RunoutRecord>,
    faults: Res<OutputFaults>,
    bodies: Query<&Points>,
) {
    let rec = &mut *record;
    let Some(points) = due_points(&mut rec.interval, &clock, &bodies, rec.body) else {
        return;
    };
    rec.cells.count(points, &grid);
    let Some(extent) = Extent::measure(points, &grid, &rec.cells) else {
        return;
    };
    rec.times.push(clock.time);
    rec.extents.push(extent);
    if let Some(dir) = &dir.0 {
        let labels: Vec<String> = ["left", "right", "length", "height"]
            .map(String::from)
            .to_vec();
        let rows: Vec<Vec<f64>> = rec
            .extents
            .iter()
            .map(|e| vec![e.left, e.right, e.length(), e.height])
            .collect();
        let csv = series_csv(&labels, &rec.times, &rows);
        write_or_fault(&dir.join("runout.csv"), csv.as_bytes(), &clock, &faults);
    }
}
