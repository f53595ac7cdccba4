//! The recording system: opens the stream on its first call, then logs a frame whenever a
//! recording is due (every N steps, or at the scene's output times, and always at t = 0 and
//! at the end).
//!
//! A stream that cannot be opened (unwritable file, no viewer to spawn) stops the run with a
//! message, like any output that cannot be written. The stream is flushed at the last step
//! and when the simulation is dropped, so a failed run keeps what was recorded before it.

use std::path::PathBuf;

use regolith::bevy_ecs::prelude::*;
use regolith::body::{Body, BodyState, PointStates, Points};
use regolith::glam::DVec2;
use regolith::grid::{GridField, GridGeometry};
use regolith::output::{OutputFaults, RunDir};
use regolith::resources::{Clock, OutputClock};
use rerun::{
    AnyValues, Arrows2D, LineStrips2D, Points2D, RecordingStream, RecordingStreamBuilder, Scalars,
};

use crate::Rerun;
use crate::{colour, document, legend};

/// What the last frame saw of a tracked body (for the acceleration).
#[derive(Clone, Copy, Debug)]
struct Last {
    time: f64,
    velocity: DVec2,
}

/// The recorder's state between steps (buffers are kept to avoid reallocating per frame).
#[derive(Resource)]
pub struct Recorder {
    params: Rerun,
    stream: Option<RecordingStream>,
    /// Centre of mass of each body at the first frame (for the depth).
    start: Vec<DVec2>,
    last: Vec<Option<Last>>,
    values: Vec<Vec<f64>>,
    positions: Vec<[f32; 2]>,
    radii: Vec<f32>,
    colours: Vec<[u8; 4]>,
    sorted: Vec<f64>,
    /// No frame logged yet (the static legends go with the first).
    first: bool,
}

impl Recorder {
    pub fn new(params: Rerun) -> Self {
        Recorder {
            params,
            stream: None,
            start: Vec::new(),
            last: Vec::new(),
            values: Vec::new(),
            positions: Vec::new(),
            radii: Vec::new(),
            colours: Vec::new(),
            sorted: Vec::new(),
            first: true,
        }
    }

    /// Opens the file and/or viewer sinks.
    fn open(
        &self,
        dir: Option<&PathBuf>,
        bodies: &[(&str, bool)],
    ) -> Result<RecordingStream, String> {
        let builder =
            RecordingStreamBuilder::new("regolith").with_blueprint(document::layout(bodies));
        let file = self.params.file.as_ref().map(|f| {
            let f = PathBuf::from(f);
            match dir {
                Some(d) if f.is_relative() => d.join(f),
                _ => f,
            }
        });
        let fail = |what: &str, e: &dyn std::fmt::Display| format!("{what}: {e}");
        match (&file, self.params.spawn) {
            (Some(path), false) => builder.save(path).map_err(|e| {
                fail(
                    &format!("cannot write the recording {}", path.display()),
                    &e,
                )
            }),
            (None, _) => builder.spawn().map_err(|e| fail(VIEWER, &e)),
            (Some(path), true) => {
                let stream = builder.buffered().map_err(|e| fail("rerun", &e))?;
                let viewer =
                    rerun::spawn(&rerun::SpawnOptions::default()).map_err(|e| fail(VIEWER, &e))?;
                let url = format!("rerun+http://127.0.0.1:{}/proxy", viewer.port);
                let uri = url.parse().map_err(|e| fail("viewer address", &e))?;
                let sink = rerun::sink::FileSink::new(path).map_err(|e| {
                    fail(
                        &format!("cannot write the recording {}", path.display()),
                        &e,
                    )
                })?;
                let sinks: Vec<Box<dyn rerun::sink::LogSink>> =
                    vec![Box::new(sink), Box::new(rerun::sink::GrpcSink::new(uri))];
                stream.set_sinks(sinks);
                Ok(stream)
            }
        }
    }
}

const VIEWER: &str = "cannot start the Rerun viewer (install the one matching this build with \
                      `pip install rerun-sdk==0.36.3`, which provides the `rerun` command)";

/// Logs a frame when one is due.
pub fn record(
    clock: Res<Clock>,
    outputs: Res<OutputClock>,
    dir: Res<RunDir>,
    grid: Res<GridGeometry>,
    mut recorder: ResMut<Recorder>,
    faults: Res<OutputFaults>,
    bodies: Query<(&Body, &Points, &PointStates, &BodyState, &GridField)>,
) {
    let due = match recorder.params.every {
        Some(n) => clock.observing || clock.last_step || clock.step.is_multiple_of(n),
        None => outputs.due,
    };
    if !due || faults.any() {
        return;
    }
    let mut sorted: Vec<_> = bodies.iter().collect();
    sorted.sort_by_key(|b| b.0.index);
    if recorder.stream.is_none() {
        let names: Vec<(&str, bool)> = sorted
            .iter()
            .map(|b| (b.0.name.as_str(), b.0.tracked))
            .collect();
        match recorder.open(dir.0.as_ref(), &names) {
            Ok(stream) => {
                document::log_setup(
                    &stream,
                    dir.0.as_deref(),
                    &grid,
                    &sorted,
                    recorder.params.grid,
                );
                recorder.start = sorted.iter().map(|b| b.3.centre_of_mass).collect();
                recorder.last = vec![None; sorted.len()];
                recorder.stream = Some(stream);
            }
            Err(message) => {
                faults.report(&clock, message);
                return;
            }
        }
    }
    let rec = &mut *recorder;
    let stream = rec.stream.as_ref().expect("opened above");
    stream.set_duration_secs("sim_time", clock.time);
    stream.set_time_sequence("step", clock.step as i64);
    let field = rec.params.color;
    rec.values.resize_with(sorted.len(), Vec::new);
    for ((body, p, st, _, _), values) in sorted.iter().zip(rec.values.iter_mut()) {
        field.values(body, p, st, values);
    }
    // Each body on its own scale: a stiff intruder's stress must not set the bed's.
    let tops: Vec<f64> = if field.scaled_by_frame() {
        let scratch = &mut rec.sorted;
        rec.values
            .iter()
            .map(|v| colour::upper_percentile(v.iter().copied(), scratch))
            .collect()
    } else {
        vec![0.0; sorted.len()]
    };
    let scales: Vec<(&str, f64)> = sorted
        .iter()
        .zip(&tops)
        .map(|(b, &t)| (b.0.name.as_str(), t))
        .collect();
    legend::log(stream, &grid, field, &scales, rec.first);
    rec.first = false;
    for (b, (body, p, _, state, f)) in sorted.iter().enumerate() {
        let path = format!("world/{}/points", body.name);
        rec.positions.clear();
        rec.positions
            .extend(p.position.iter().map(|x| [x.x as f32, x.y as f32]));
        rec.radii.clear();
        rec.radii.extend(
            p.volume
                .iter()
                .map(|&v| (v / std::f64::consts::PI).sqrt() as f32),
        );
        field.colours(&rec.values[b], tops[b], &mut rec.colours);
        let points = Points2D::new(rec.positions.iter().copied())
            .with_radii(rec.radii.iter().copied())
            .with_colors(rec.colours.iter().copied());
        let value = per_point(field.name(), &rec.values[b]);
        log(&path, stream, &points);
        log(&path, stream, &value);
        scalar(
            stream,
            &format!("plots/{}/kinetic_energy", body.name),
            state.kinetic_energy,
        );
        if body.tracked {
            let at = format!("plots/{}", body.name);
            scalar(
                stream,
                &format!("{at}/depth"),
                rec.start[b].y - state.centre_of_mass.y,
            );
            pair(stream, &format!("{at}/velocity"), state.velocity);
            pair(stream, &format!("{at}/contact_force"), f.contact_force);
            if let Some(last) = rec.last[b]
                && clock.time > last.time
            {
                let a = (state.velocity - last.velocity) / (clock.time - last.time);
                pair(stream, &format!("{at}/acceleration"), a);
            }
            rec.last[b] = Some(Last {
                time: clock.time,
                velocity: state.velocity,
            });
        }
        if rec.params.grid {
            log_grid(stream, &grid, body, f);
        }
    }
    if !clock.observing {
        scalar(stream, "plots/time_step", clock.dt);
    }
    if clock.last_step {
        let _ = stream.flush_blocking();
    }
}

/// One value per point (or node) as a plain float column named `name`. Not typed as a
/// `Scalar`: the viewer would otherwise plot every point as its own time series.
fn per_point(name: &'static str, values: &[f64]) -> AnyValues {
    let column = rerun::external::arrow::array::Float64Array::from(values.to_vec());
    AnyValues::default().with_component_from_data(name, std::sync::Arc::new(column))
}

/// Logs `what` at `path`; a sink error is rerun's to report (it logs and drops the data), a
/// recording must never stop the simulation it watches.
fn log(path: &str, stream: &RecordingStream, what: &dyn rerun::AsComponents) {
    let _ = stream.log(path, what);
}

fn scalar(stream: &RecordingStream, path: &str, v: f64) {
    log(path, stream, &Scalars::single(v));
}

fn pair(stream: &RecordingStream, path: &str, v: DVec2) {
    scalar(stream, &format!("{path}/x"), v.x);
    scalar(stream, &format!("{path}/y"), v.y);
}

/// Seconds of motion an arrow of `grid/<body>/velocity` shows.
const ARROW_TIME: f64 = 0.01;

fn log_grid(stream: &RecordingStream, grid: &GridGeometry, body: &Body, f: &GridField) {
    let (nx, ny) = (grid.nodes_along(0), grid.nodes_along(1));
    let mut origins = Vec::new();
    let mut vectors = Vec::new();
    let mut masses = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            let n = grid.index(i, j);
            if f.mass[n] > f.mass_tolerance {
                let x = grid.node_position(i, j);
                origins.push([x.x as f32, x.y as f32]);
                let d = f.velocity[n] * ARROW_TIME;
                vectors.push([d.x as f32, d.y as f32]);
                masses.push(f.mass[n]);
            }
        }
    }
    let largest = colour::upper_percentile(masses.iter().copied(), &mut Vec::new());
    let colours: Vec<[u8; 4]> = masses.iter().map(|&m| colour::linear(m, largest)).collect();
    let at = format!("grid/{}", body.name);
    log(
        &format!("{at}/velocity"),
        stream,
        &Arrows2D::from_vectors(vectors).with_origins(origins.iter().copied()),
    );
    log(
        &format!("{at}/mass"),
        stream,
        &Points2D::new(origins)
            .with_colors(colours)
            .with_radii([0.1 * grid.cell_size as f32]),
    );
    log(&format!("{at}/mass"), stream, &per_point("mass", &masses));
}

/// The domain's outline, logged once.
pub fn domain_outline(grid: &GridGeometry) -> LineStrips2D {
    let (lo, hi) = (grid.origin, grid.max());
    let corners = [
        [lo.x as f32, lo.y as f32],
        [hi.x as f32, lo.y as f32],
        [hi.x as f32, hi.y as f32],
        [lo.x as f32, hi.y as f32],
        [lo.x as f32, lo.y as f32],
    ];
    LineStrips2D::new([corners]).with_colors([[0u8, 0, 0, 255]])
}
