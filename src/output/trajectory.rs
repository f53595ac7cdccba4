//! `trajectory.csv`: time and centre-of-mass position and velocity of each tracked body.
//!
//! Columns: `t`, then `<body>_x, <body>_y, <body>_vx, <body>_vy` per tracked body in scene
//! order, then `<body>_depth, <body>_fx, <body>_fy` per tracked body: the downward
//! displacement of its centre of mass since the first row (m) and the force the other
//! bodies exert on it through contact in the last step (N per metre of thickness; zero for
//! a lone body). The later columns come after all the first ones, so a table's first
//! columns are where they always were. Rows are kept in memory (tests read them) and, when
//! the run writes files, appended and flushed to `trajectory.csv.part` as they are made, so
//! a failed run keeps them.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use bevy_ecs::prelude::*;

use super::OutputFaults;
use crate::body::{Body, BodyState};
use crate::grid::GridField;
use crate::resources::Clock;

#[derive(Resource, Debug, Default)]
pub struct Trajectory {
    pub columns: Vec<String>,
    pub rows: Vec<Vec<f64>>,
    sink: Option<(PathBuf, BufWriter<File>)>,
}

impl Trajectory {
    /// An empty table for the tracked bodies, by name in scene order.
    pub fn new(tracked: &[String]) -> Self {
        let mut columns = vec!["t".to_string()];
        for quantities in [["x", "y", "vx", "vy"].as_slice(), &["depth", "fx", "fy"]] {
            for name in tracked {
                for q in quantities {
                    columns.push(format!("{name}_{q}"));
                }
            }
        }
        Trajectory {
            columns,
            ..Default::default()
        }
    }

    /// Starts streaming rows to `<dir>/trajectory.csv.part`.
    pub fn open(&mut self, dir: &Path) -> std::io::Result<()> {
        let part = dir.join("trajectory.csv.part");
        let mut w = BufWriter::new(File::create(&part)?);
        writeln!(w, "{}", self.columns.join(","))?;
        for row in &self.rows {
            write_row(&mut w, row)?;
        }
        w.flush()?;
        self.sink = Some((part, w));
        Ok(())
    }

    /// Flushes and renames the streamed file to `trajectory.csv`.
    pub fn close(&mut self) -> std::io::Result<()> {
        if let Some((part, mut w)) = self.sink.take() {
            w.flush()?;
            w.get_ref().sync_all()?;
            drop(w);
            std::fs::rename(&part, part.with_extension(""))?;
        }
        Ok(())
    }

    /// The column index of `<body>_<quantity>`.
    pub fn column(&self, body: &str, quantity: &str) -> Option<usize> {
        let name = format!("{body}_{quantity}");
        self.columns.iter().position(|c| *c == name)
    }

    /// One column as a vector.
    pub fn series(&self, col: usize) -> Vec<f64> {
        self.rows.iter().map(|r| r[col]).collect()
    }
}

fn write_row(w: &mut impl Write, row: &[f64]) -> std::io::Result<()> {
    let text: Vec<String> = row
        .iter()
        .map(|&v| crate::format::Num(v).to_string())
        .collect();
    writeln!(w, "{}", text.join(","))
}

/// Appends a row for the current time.
pub fn record_trajectory(
    clock: Res<Clock>,
    faults: Res<OutputFaults>,
    mut table: ResMut<Trajectory>,
    bodies: Query<(&Body, &BodyState, &GridField)>,
) {
    let mut tracked: Vec<_> = bodies.iter().filter(|(b, _, _)| b.tracked).collect();
    tracked.sort_by_key(|(b, _, _)| b.index);
    let mut row = vec![clock.time];
    for (_, s, _) in &tracked {
        row.extend([
            s.centre_of_mass.x,
            s.centre_of_mass.y,
            s.velocity.x,
            s.velocity.y,
        ]);
    }
    let table = &mut *table;
    for (k, (_, s, field)) in tracked.iter().enumerate() {
        // Column of this body's y: after `t`, four per body.
        let y0 = table
            .rows
            .first()
            .map_or(s.centre_of_mass.y, |r| r[2 + 4 * k]);
        row.extend([
            y0 - s.centre_of_mass.y,
            field.contact_force.x,
            field.contact_force.y,
        ]);
    }
    if let Some((_, w)) = table.sink.as_mut()
        && let Err(e) = write_row(w, &row).and_then(|_| w.flush())
    {
        faults.report(&clock, format!("cannot write trajectory.csv: {e}"));
    }
    table.rows.push(row);
}
