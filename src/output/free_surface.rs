//! `FreeSurface(..)`: the height of a granular body's free surface across the domain, at a
//! fixed interval (the paper's section 4.3.2 compares the surface and splash shapes).
//!
//! The paper draws the surface as a contour of the points' number density. Here, per column
//! of cells, the surface is the top of the highest cell whose number of points is at least
//! half the body's initial number per cell (so thrown, dilute grains above it do not count,
//! and a cell half-filled at rest sits at the surface). `free_surface.csv` has `t` and one
//! column per cell column (`x` of its centre); a column without such a cell has an empty
//! value. The record lives in memory (carried over checkpoints) and the file is rewritten at
//! each interval.

use bevy_ecs::prelude::*;
use serde::Deserialize;

use crate::body::Points;
use crate::carry::{Carried, carried, restored};
use crate::grid::GridGeometry;
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
pub struct FreeSurface {
    /// The granular body.
    pub body: String,
    /// Interval between records (s).
    pub every: f64,
}

/// The surface profiles so far.
#[derive(Resource, Clone, Debug)]
pub struct SurfaceRecord {
    /// The body, found at install.
    body: Option<Entity>,
    interval: Interval,
    /// Which cells the body fills (its points per cell at t = 0 carried over checkpoints).
    cells: DenseCells,
    pub times: Vec<f64>,
    /// One height per cell column (NaN where the column has no dense cell).
    pub heights: Vec<Vec<f64>>,
}

impl Item for FreeSurface {
    const NAME: &'static str = "FreeSurface";
    fn validate(&self) -> Result<(), String> {
        check_every(self.every)
    }
}

impl Output for FreeSurface {
    fn bodies(&self) -> Vec<&str> {
        vec![&self.body]
    }

    fn install(&self, sim: &mut Install) {
        let body = sim.body(&self.body);
        sim.insert_resource(SurfaceRecord {
            body,
            interval: Interval::new(self.every),
            cells: DenseCells::default(),
            times: Vec::new(),
            heights: Vec::new(),
        });
        sim.add_systems(StepSet::Output, record_surface);
    }

    /// The record so far: its schedule, the initial points per cell, the profiles.
    fn save(&self, world: &World) -> Carried {
        let r = world.resource::<SurfaceRecord>();
        carried(&(&r.interval, r.cells.full, &r.times, &r.heights))
    }

    fn restore(&self, world: &mut World, state: &[u8]) -> Result<(), String> {
        let mut r = world.resource_mut::<SurfaceRecord>();
        (r.interval, r.cells.full, r.times, r.heights) = restored(state)?;
        Ok(())
    }
}

fn record_surface(
    clock: Res<Clock>,
    dir: Res<RunDir>,
    grid: Res<GridGeometry>,
    mut record: ResMut<SurfaceRecord>,
    faults: Res<OutputFaults>,
    bodies: Query<&Points>,
) {
    let rec = &mut *record;
    let Some(points) = due_points(&mut rec.interval, &clock, &bodies, rec.body) else {
        return;
    };
    let [nx, ny] = grid.cells;
    rec.cells.count(points, &grid);
    let heights: Vec<f64> = (0..nx)
        .map(|i| {
            (0..ny)
                .rev()
                .find(|&j| rec.cells.dense(i, j))
                .map_or(f64::NAN, |j| {
                    grid.origin.y + (j + 1) as f64 * grid.cell_size
                })
        })
        .collect();
    rec.times.push(clock.time);
    rec.heights.push(heights);
    if let Some(dir) = &dir.0 {
        let labels: Vec<String> = (0..nx)
            .map(|i| format!("x{:.5}", grid.origin.x + (i as f64 + 0.5) * grid.cell_size))
            .collect();
        let csv = series_csv(&labels, &rec.times, &rec.heights);
        write_or_fault(
            &dir.join("free_surface.csv"),
            csv.as_bytes(),
            &clock,
            &faults,
        );
    }
}

/// Which cells a granular body fills densely: those holding at least half the points per
/// cell its densest cell held at the first count (`full`), so that thrown, dilute grains do
/// not count and a cell half-filled at rest does. `full` is what a checkpoint carries.
#[derive(Clone, Debug, Default)]
pub(crate) struct DenseCells {
    pub full: usize,
    counts: Vec<usize>,
    columns: usize,
}

impl DenseCells {
    /// Counts the body's points (of positive mass) per cell, row by row.
    pub fn count(&mut self, points: &Points, grid: &GridGeometry) {
        let [nx, ny] = grid.cells;
        self.columns = nx;
        self.counts.clear();
        self.counts.resize(nx * ny, 0);
        for (x, &m) in points.position.iter().zip(&points.mass) {
            let c = (*x - grid.origin) / grid.cell_size;
            if m > 0.0 && c.x >= 0.0 && c.y >= 0.0 && (c.x as usize) < nx && (c.y as usize) < ny {
                self.counts[c.y as usize * nx + c.x as usize] += 1;
            }
        }
        if self.full == 0 {
            self.full = self.counts.iter().copied().max().unwrap_or(0);
        }
    }

    /// Whether cell `(i, j)` was dense at the last count.
    pub fn dense(&self, i: usize, j: usize) -> bool {
        self.counts[j * self.columns + i] >= self.full.div_ceil(2).max(1)
    }
}
