//! The recording system: opens the stream on its first call, then logs a frame whenever a
//! recording is due (every N steps, or at the scene's output times, and always at t = 0 and
//! at the end).
//!
//! A stream that cannot be opened (unwritable file, no viewer to spawn) stops the run with a
//! message, like any output that cannot be written.
//!
//! The recorder writes the file itself: rerun encodes each frame into an in-memory stream
//! (`BinaryStreamStorage`), and the recorder appends those bytes to the `.rrd` after the
//! frame, so the file always ends with a whole frame and a failed run keeps every frame it
//! logged. A checkpoint carries the file's length, the recording's id and what the plots
//! difference against; a resumed run cuts the file back to that length (dropping frames
//! logged after the checkpoint, which it logs again) and appends under the same recording
//! id. Rerun reads concatenated streams as one recording, so the resumed file opens as the
//! uninterrupted run's would.

use std::fs::File;
use std::io::{Seek, SeekFrom, Write};
use std::path::PathBuf;

use regolith::bevy_ecs::prelude::*;
use regolith::body::{Body, BodyState, PointStates, Points};
use regolith::glam::DVec2;
use regolith::grid::{GridField, GridGeometry};
use regolith::output::{OutputFaults, RunDir};
use regolith::resources::{Clock, OutputClock};
use rerun::sink::{BinaryStreamSink, BinaryStreamStorage};
use rerun::{AnyValues, Arrows2D, Points2D, RecordingStream, RecordingStreamBuilder, Scalars};
use serde::{Deserialize, Serialize};

use crate::Rerun;
use crate::{colour, document, legend};

/// What the last frame saw of a tracked body (for the acceleration).
#[derive(Clone, Copy, Debug, Serialize, Deserialize)]
struct Last {
    time: f64,
    velocity: DVec2,
}

/// The `.rrd` the recorder appends each frame's bytes to (module docs).
struct RecordingFile {
    path: PathBuf,
    file: File,
    /// The stream's encoded messages not yet appended.
    storage: BinaryStreamStorage,
    /// Bytes in the file.
    written: u64,
}

impl RecordingFile {
    /// Appends what the stream has encoded since the last call.
    fn append(&mut self) -> Result<(), String> {
        let Some(bytes) = self.storage.read() else {
            return Ok(());
        };
        self.file
            .write_all(&bytes)
            .and_then(|_| self.file.flush())
            .map_err(|e| format!("cannot write the recording {}: {e}", self.path.display()))?;
        self.written += bytes.len() as u64;
        Ok(())
    }
}

/// What a checkpoint carries of the recorder: enough for a resumed run to go on with the
/// same recording in the same file.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct Saved {
    /// The recording's id (empty before the first frame).
    recording: String,
    /// Bytes of the file holding every frame up to the checkpoint.
    written: u64,
    start: Vec<DVec2>,
    last: Vec<Option<Last>>,
    first: bool,
}

/// The recorder's state between steps (buffers are kept to avoid reallocating per frame).
#[derive(Resource)]
pub struct Recorder {
    params: Rerun,
    stream: Option<RecordingStream>,
    file: Option<RecordingFile>,
    /// The recording's id; a resumed run keeps the interrupted run's.
    recording: String,
    /// Set by a resume: the file's length at the checkpoint, to cut it back to when opened.
    resume_from: Option<u64>,
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
    /// The file the recording is written to, once the first frame has opened it.
    pub fn file_path(&self) -> Option<&std::path::Path> {
        self.file.as_ref().map(|f| f.path.as_path())
    }

    pub fn new(params: Rerun) -> Self {
        Recorder {
            params,
            stream: None,
            file: None,
            recording: String::new(),
            resume_from: None,
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

    /// What a checkpoint keeps (module docs): every logged frame is in the file already.
    pub fn saved(&self) -> Saved {
        Saved {
            recording: self.recording.clone(),
            written: self.file.as_ref().map_or(0, |f| f.written),
            start: self.start.clone(),
            last: self.last.clone(),
            first: self.first,
        }
    }

    /// Takes back what [`Recorder::carried`] gave, before the first resumed step.
    pub fn restore(&mut self, saved: Saved) {
        if saved.recording.is_empty() {
            return;
        }
        self.recording = saved.recording;
        self.resume_from = Some(saved.written);
        self.start = saved.start;
        self.last = saved.last;
        self.first = saved.first;
    }

    /// Opens the stream, with the file it appends to and/or the viewer it streams to.
    fn open(
        &mut self,
        dir: Option<&PathBuf>,
        bodies: &[(&str, bool)],
    ) -> Result<RecordingStream, String> {
        if self.recording.is_empty() {
            self.recording = rerun::external::re_log_types::RecordingId::random().to_string();
        }
        let stream = RecordingStreamBuilder::new("regolith")
            .recording_id(self.recording.clone())
            .with_blueprint(document::layout(bodies))
            .buffered()
            .map_err(|e| format!("rerun: {e}"))?;
        let path = self.params.file.as_ref().map(|f| {
            let f = PathBuf::from(f);
            match dir {
                Some(d) if f.is_relative() => d.join(f),
                _ => f,
            }
        });
        let mut sinks: Vec<Box<dyn rerun::sink::LogSink>> = Vec::new();
        if let Some(path) = path {
            let (sink, storage) = BinaryStreamSink::new(stream.clone());
            sinks.push(Box::new(sink));
            let (file, written) = open_file(&path, self.resume_from.take())?;
            self.file = Some(RecordingFile {
                path,
                file,
                storage,
                written,
            });
        }
        if self.params.spawn {
            let fail = |e: &dyn std::fmt::Display| format!("{VIEWER}: {e}");
            let viewer = rerun::spawn(&rerun::SpawnOptions::default()).map_err(|e| fail(&e))?;
            let url = format!("rerun+http://127.0.0.1:{}/proxy", viewer.port);
            let uri = url.parse().map_err(|e| format!("viewer address: {e}"))?;
            sinks.push(Box::new(rerun::sink::GrpcSink::new(uri)));
        }
        stream.set_sinks(sinks);
        Ok(stream)
    }
}

/// The recording file and its length: created afresh, or for a resumed run the existing
/// file cut back to the `resume_from` bytes that held every frame up to the checkpoint.
fn open_file(path: &PathBuf, resume_from: Option<u64>) -> Result<(File, u64), String> {
    let cannot = |e: std::io::Error| format!("cannot write the recording {}: {e}", path.display());
    let Some(length) = resume_from else {
        return File::create(path).map(|f| (f, 0)).map_err(cannot);
    };
    let mut file = std::fs::OpenOptions::new()
        .write(true)
        .open(path)
        .map_err(|e| {
            format!(
                "cannot continue the recording {} of the interrupted run: {e} (resume without the recording, or restore the file)",
                path.display()
            )
        })?;
    let found = file.metadata().map_err(cannot)?.len();
    if found < length {
        return Err(format!(
            "the recording {} holds {found} bytes, fewer than the {length} the checkpoint's frames took: frames before the resume are missing (resume without the recording, or restore the file)",
            path.display()
        ));
    }
    file.set_len(length).map_err(cannot)?;
    file.seek(SeekFrom::End(0)).map_err(cannot)?;
    Ok((file, length))
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
                // A resumed recording keeps the interrupted run's first frame and last frames.
                if recorder.start.is_empty() {
                    recorder.start = sorted.iter().map(|b| b.3.centre_of_mass).collect();
                    recorder.last = vec![None; sorted.len()];
                }
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
    // Every frame whole in the file before the step ends (module docs).
    let _ = stream.flush_blocking();
    if let Some(file) = rec.file.as_mut()
        && let Err(message) = file.append()
    {
        faults.report(&clock, message);
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
