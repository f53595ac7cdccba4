//! Running a scene to its end with files written: what `regolith run` does.
//!
//! Outputs land in the run directory as the run goes: `scene.ron` (the text that ran, with
//! overrides applied), `trajectory.csv` (streamed as `trajectory.csv.part`, renamed at the
//! end), `checkpoint.bin` when asked (atomically, every N steps) and `summary.json` (written
//! atomically last). A run that stops on a fault still writes all of them, with
//! `"status": "failed"` and the reason in the summary; one stopped by a signal
//! ([`request_stop`]) finishes its step, writes `checkpoint.bin` and a summary with
//! `"status": "interrupted"`. `resume_run` continues a run from its checkpoint.

use std::collections::BTreeMap;
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use crate::carry::Partial;
use crate::checkpoint::Checkpoint;
use crate::error::{Error, Fault, SceneError};
use crate::grid::GridField;
use crate::output::health;
use crate::output::summary::{BodySummary, Summary};
use crate::output::write_atomic;
use crate::resources::{Clock, StepRule};
use crate::scene::{Scene, TimeStep};
use crate::sim::{Simulation, on_worker};
use crate::step::StepSet;

/// Where the scene came from, for the record.
pub struct Provenance<'a> {
    pub file: &'a str,
    pub text: &'a str,
    pub overrides: &'a [String],
}

/// Something told about each step (the command line draws a progress bar with it).
pub trait Progress: Send {
    fn step(&mut self, clock: &Clock);
    /// Whether the run should stop after this step as a signal would stop it (checkpoint,
    /// `interrupted` summary): a driver's own way to interrupt a run, as the resume tests
    /// do. By default never; [`request_stop`] stops every run in the process.
    fn stop(&mut self, _clock: &Clock) -> bool {
        false
    }
}

/// Stops a run after the given step, as a signal would (checkpoint, `interrupted` summary):
/// a driver's own interruption, as the resume tests make.
pub struct StopAfter(pub u64);

impl Progress for StopAfter {
    fn step(&mut self, _clock: &Clock) {}
    fn stop(&mut self, clock: &Clock) -> bool {
        clock.step == self.0
    }
}

impl<F: FnMut(&Clock) + Send> Progress for F {
    fn step(&mut self, clock: &Clock) {
        self(clock)
    }
}

/// How often a run writes `checkpoint.bin` (every this many steps), if at all.
#[derive(Clone, Copy, Debug, Default)]
pub struct CheckpointEvery(pub Option<u64>);

fn io_error(out: &Path, what: &str) -> impl FnOnce(std::io::Error) -> Error {
    let what = format!("{what} in {}", out.display());
    move |e| Error::io(what, e)
}

/// Runs `scene` to its end time writing into `out`; returns the summary, or the fault after
/// the summary of the failed run has been written.
pub fn run_scene(
    scene: &Scene,
    from: &Provenance,
    out: &Path,
    checkpoints: CheckpointEvery,
    progress: &mut dyn Progress,
) -> Result<Summary, Error> {
    std::fs::create_dir_all(out).map_err(io_error(out, "cannot create the output directory"))?;
    write_atomic(&out.join("scene.ron"), from.text.as_bytes())
        .map_err(io_error(out, "cannot write scene.ron"))?;
    let sim = Simulation::with_output(scene, out)
        .map_err(io_error(out, "cannot start trajectory.csv"))?;
    run_to_end(sim, scene, from, out, checkpoints, progress)
}

/// Continues the run in `out` from its `checkpoint.bin`, with the scene text it started
/// from (`scene.ron`); the result is bitwise identical to a run never interrupted.
/// `extend` may add outputs that do not change the state (the command line's recording).
pub fn resume_run(
    registries: &std::sync::Arc<crate::registry::Registries>,
    out: &Path,
    checkpoints: CheckpointEvery,
    extend: impl FnOnce(&mut Scene) -> Result<(), Error>,
    progress: &mut dyn Progress,
) -> Result<Summary, Error> {
    let scene_path = out.join("scene.ron");
    let text =
        std::fs::read_to_string(&scene_path).map_err(io_error(out, "cannot read scene.ron"))?;
    let mut scene = Scene::parse(&text, &scene_path.display().to_string(), registries)?;
    extend(&mut scene)?;
    let checkpoint = Checkpoint::read(&out.join("checkpoint.bin"))
        .map_err(|e| Error::Scene(SceneError::file(&out.display().to_string(), e)))?;
    let (file, overrides) = (checkpoint.scene_file.clone(), checkpoint.overrides.clone());
    let mut sim = Simulation::unobserved(&scene);
    checkpoint
        .restore(&mut sim, &scene)
        .map_err(|e| Error::Scene(SceneError::file(&out.display().to_string(), e)))?;
    sim.write_to(out)
        .map_err(io_error(out, "cannot reopen trajectory.csv"))?;
    let from = Provenance {
        file: &file,
        text: &text,
        overrides: &overrides,
    };
    run_to_end(sim, &scene, &from, out, checkpoints, progress)
}

/// Set by [`request_stop`] (the command line's SIGINT / SIGTERM handler); every run in
/// the process stops after its current step.
static STOP: AtomicBool = AtomicBool::new(false);

/// Asks every run in the process to stop after its current step, save a checkpoint and
/// write its summary as `interrupted`. Returns whether a stop had been asked already.
pub fn request_stop() -> bool {
    STOP.swap(true, Ordering::SeqCst)
}

/// This machine's host name, as `summary.json` and claims on run directories record it.
pub fn host() -> String {
    gethostname::gethostname().to_string_lossy().into_owned()
}

/// How a run's loop ended.
enum Ending {
    Finished,
    Fault(Fault),
    Interrupted,
}

fn run_to_end(
    mut sim: Simulation,
    scene: &Scene,
    from: &Provenance,
    out: &Path,
    checkpoints: CheckpointEvery,
    progress: &mut dyn Progress,
) -> Result<Summary, Error> {
    let started = Instant::now();
    let ending = on_worker(|| -> Result<Ending, Error> {
        while !sim.finished() {
            if let Err(f) = sim.step() {
                return Ok(Ending::Fault(f));
            }
            progress.step(sim.clock());
            if sim.finished() {
                break;
            }
            let stop = STOP.load(Ordering::SeqCst) || progress.stop(sim.clock());
            let due = checkpoints
                .0
                .is_some_and(|every| sim.clock().step.is_multiple_of(every));
            if stop || due {
                Checkpoint::capture(&mut sim, scene, from.file, from.overrides)
                    .write(&out.join("checkpoint.bin"))
                    .map_err(io_error(out, "cannot write checkpoint.bin"))?;
            }
            if stop {
                return Ok(Ending::Interrupted);
            }
        }
        Ok(Ending::Finished)
    })?;
    let wall = started.elapsed().as_secs_f64();
    sim.trajectory_mut()
        .close()
        .map_err(io_error(out, "cannot finish trajectory.csv"))?;
    let (status, failure) = match &ending {
        Ending::Finished => ("completed", None),
        Ending::Fault(f) => ("failed", Some(f.to_string())),
        Ending::Interrupted => (
            "interrupted",
            Some(format!(
                "interrupted by a signal at t = {} s (trajectory.csv ends there); `regolith resume {}` continues the run",
                crate::format::Seconds(sim.clock().time),
                out.display()
            )),
        ),
    };
    let summary = summarize(&mut sim, scene, from, wall, status, failure);
    let json = serde_json::to_string_pretty(&summary).expect("a summary always serialises");
    write_atomic(&out.join("summary.json"), json.as_bytes())
        .map_err(io_error(out, "cannot write summary.json"))?;
    match ending {
        Ending::Finished => Ok(summary),
        Ending::Fault(f) => Err(Error::from(f)),
        Ending::Interrupted => Err(Error::Interrupted {
            time: summary.time,
            dir: out.to_path_buf(),
        }),
    }
}

/// The summary of a simulation in its current state.
pub fn summarize(
    sim: &mut Simulation,
    scene: &Scene,
    from: &Provenance,
    wall_s: f64,
    status: &str,
    failure: Option<String>,
) -> Summary {
    let clock = sim.clock().clone();
    let grid = sim.grid().clone();
    let bodies: Vec<BodySummary> = sim
        .bodies()
        .into_iter()
        .map(|(b, s, n)| BodySummary {
            // every body listed by `bodies` has points
            state_hash: sim.state_hash(&b.name).unwrap_or_default(),
            health: b.inertial_scale.and_then(|_| {
                let layer = scene
                    .body(&b.name)
                    .ok()
                    .and_then(|spec| health::layer_bounds(spec.shape.bounds(), &grid));
                sim.health(&b.name, layer)
            }),
            name: b.name,
            material: b.material.to_string(),
            points: n,
            mass: s.mass,
            centre_of_mass: s.centre_of_mass.to_array(),
            velocity: s.velocity.to_array(),
            kinetic_energy: s.kinetic_energy,
            retired_points: s.retired,
        })
        .collect();
    let particles: usize = bodies.iter().map(|b| b.points).sum();
    let timings_s: BTreeMap<String, f64> = StepSet::ALL
        .iter()
        .zip(sim.timings().per_set)
        .map(|(set, d)| (set.label().to_string(), d.as_secs_f64()))
        .collect();
    let rule = sim.world.resource::<StepRule>().clone();
    let (dt_rule, dt) = match rule.rule {
        TimeStep::Fixed(dt) => ("fixed", dt),
        TimeStep::Cfl(_) => ("cfl", rule.dt_max),
    };
    let mut units = crate::output::summary::units();
    let mut sections = serde_json::Map::new();
    let mut headlines = Vec::new();
    let items = scene.outputs.iter().map(|o| o.summary(&sim.world));
    let items = items.chain(scene.conditions.iter().map(|c| c.summary(&sim.world)));
    for section in items {
        sections.extend(section.entries);
        units.extend(section.units);
        headlines.extend(section.headline);
    }
    let partial_because = sim
        .world
        .get_resource::<Partial>()
        .map_or(Vec::new(), |p| p.0.clone());
    headlines.extend(partial_because.iter().map(|why| format!("PARTIAL: {why}")));
    let warnings: Vec<String> = bodies
        .iter()
        .filter_map(|b| b.health.as_ref().map(|h| h.warnings(&b.name)))
        .flatten()
        .collect();
    headlines.extend(warnings.iter().map(|w| format!("WARNING: {w}")));
    Summary {
        sections,
        headlines,
        warnings,
        units,
        scene: scene.name.clone(),
        scene_file: from.file.to_string(),
        overrides: from.overrides.to_vec(),
        status: status.to_string(),
        failure,
        partial: !partial_because.is_empty(),
        partial_because,
        integration: format!("{:?}", scene.integration),
        steps: clock.step,
        time: clock.time,
        dt,
        dt_min: if clock.step > 0 { rule.dt_min } else { 0.0 },
        dt_max: rule.dt_max,
        dt_rule: dt_rule.to_string(),
        cfl: rule.cfl_max,
        particles,
        cells: grid.cells,
        cell_size: grid.cell_size,
        gravity: scene.gravity.to_array(),
        threads: rayon::current_num_threads(),
        kernels: sim
            .world
            .get_resource::<crate::kernels::Kernels>()
            .map_or("scalar", |k| k.name())
            .to_string(),
        host: host(),
        regolith_version: env!("CARGO_PKG_VERSION").to_string(),
        wall_s,
        particle_steps_per_s: if wall_s > 0.0 {
            particles as f64 * clock.step as f64 / wall_s
        } else {
            0.0
        },
        timings_s,
        bodies,
    }
}

/// The memory a scene's state takes: what every point carries (its columns, material
/// history, phase and rates, footprint, cell and band, and its fields' columns with the
/// bands kept for them) and what the grid holds (one nodal field per body, the cell sums,
/// the fields' nodal scalars once a step has made them). Point columns that are empty for a body (the affine
/// field of a FLIP scene, history of a history-free material) are not counted.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MemoryEstimate {
    pub points: usize,
    /// Bytes of per-point state, all bodies together.
    pub point_bytes: usize,
    /// Bytes of nodal fields and cell sums.
    pub grid_bytes: usize,
}

impl MemoryEstimate {
    pub fn total(&self) -> usize {
        self.point_bytes + self.grid_bytes
    }

    /// Bytes of state per point, the grid's share left out.
    pub fn per_point(&self) -> f64 {
        self.point_bytes as f64 / self.points.max(1) as f64
    }
}

/// Bytes one point of a body made of `material` carries through a step, whatever its
/// material: the columns of [`crate::body::Points`] (with the affine field if `affine`),
/// [`crate::body::PointStates`], the footprint, cell and band of `step::Location` and its
/// slot in the bands.
pub fn bytes_per_point(material: &dyn crate::material::MaterialSpec, affine: bool) -> usize {
    let affine = if affine {
        crate::body::Points::AFFINE_BYTES
    } else {
        0
    };
    crate::body::Points::BYTES_PER_POINT
        + affine
        + crate::body::PointStates::BYTES_PER_POINT
        + crate::shape_functions::Footprint::BYTES
        + crate::step::Location::BYTES_PER_POINT
        + material.history_bytes()
}

/// Memory use of a scene's state (see [`MemoryEstimate`]).
pub fn memory_estimate(sim: &mut Simulation, scene: &Scene) -> MemoryEstimate {
    let nodes = sim.grid().node_count();
    let cells = sim.grid().cells[0] * sim.grid().cells[1];
    let averaging = if scene.dilatation == crate::resources::Dilatation::CellAveraged {
        crate::step::CellDilatation::BYTES_PER_CELL * cells
    } else {
        0
    };
    let counts: Vec<usize> = sim.bodies().iter().map(|b| b.2).collect();
    let mut estimate = MemoryEstimate {
        points: 0,
        point_bytes: 0,
        grid_bytes: 0,
    };
    // The delta-correction's arrays: a place and a gradient per point, a fill and a slope
    // per node of its grid (`refinement` times finer).
    let (spacing_point, spacing_grid) = match scene.spacing {
        crate::step::spacing::Spacing::Off => (0, 0),
        crate::step::spacing::Spacing::DeltaCorrection(c) => {
            let g = sim.grid();
            let along = |a: usize| g.cells[a] * c.refinement + usize::from(!g.periodic[a]);
            (
                crate::step::spacing::BYTES_PER_POINT,
                crate::step::spacing::BYTES_PER_NODE * along(0) * along(1),
            )
        }
    };
    estimate.grid_bytes += spacing_grid;
    // The packed copy of each body's velocities and accelerations the vector gathers read.
    let packed = match sim.world.get_resource::<crate::kernels::Kernels>() {
        Some(k) if k.packs() => crate::grid::NodeMotion::BYTES,
        _ => 0,
    };
    for (spec, n) in scene.bodies.iter().zip(counts) {
        let normals = scene
            .contact
            .needs_normal_of(&spec.name, scene.bodies.len());
        estimate.points += n;
        estimate.point_bytes +=
            n * (bytes_per_point(&*spec.material, scene.transfer.affine()) + spacing_point);
        estimate.grid_bytes += nodes * (GridField::bytes_per_node(normals) + packed) + averaging;
    }
    // The fields: their columns, a slot per point in the bands kept for their scatters, and
    // their nodal scalars.
    let mut fields = sim.world.query::<(
        &crate::grid_field::FieldColumns,
        &crate::grid_field::GridFields,
        &crate::body::Points,
    )>();
    for (columns, nodal, points) in fields.iter(&sim.world) {
        estimate.point_bytes += columns.bytes() + points.len() * std::mem::size_of::<u32>();
        estimate.grid_bytes += nodal.bytes();
    }
    estimate
}
