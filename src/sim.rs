//! A simulation: the ECS world built from a scene, and the schedule that steps it.

use crate::step::spacing::{Spacing, SpacingScratch};

use bevy_ecs::prelude::*;
use glam::{DMat2, DVec2};

use crate::body::{Body, BodyState, PointStates, Points};
use crate::diagnostics::{EnergyLimit, Health, Surveys};
use crate::error::Fault;
use crate::fill::fill;
use crate::grid::{GridField, GridGeometry};
use crate::grid_field::{FieldColumns, GridFields, StartBands};
use crate::obstacle::Obstacles;
use crate::output::trajectory::Trajectory;
use crate::output::{OutputFaults, RunDir};
use crate::plugin::Install;
use crate::resources::{Dilatation, Interval};
use crate::scene::{BodySpec, InitialStress, Scene};
use crate::schedule::{StepOptions, build_schedule};
use crate::step::Timings;
use crate::step::{Bands, CellDilatation, Location};
use crate::stress::Stress;

// The global state's old paths, kept so that code written against them still builds; the one
// documented path is `resources`.
#[doc(hidden)]
pub use crate::resources::{Boundaries, Clock, Gravity, OutputClock, StepRule, VelocityRule};

/// A ready-to-step simulation.
pub struct Simulation {
    pub world: World,
    schedule: Schedule,
}

/// Runs `f` on a thread of the current rayon pool. The step's parallel loops then push
/// their jobs onto that worker's own deque, which keeps its capacity, and a step allocates
/// nothing; launched from outside the pool every parallel loop goes through rayon's global
/// injector, which allocates a block every 63 jobs (measured in tests/invariants/determinism.rs).
pub fn on_worker<R: Send>(f: impl FnOnce() -> R + Send) -> R {
    if rayon::current_thread_index().is_some() {
        f()
    } else {
        rayon::join(f, || ()).0
    }
}

/// Mass tolerance of a body's nodes: `1e-8 rho h^2` per unit thickness (docs/model.md §2, step 3).
fn mass_tolerance(density: f64, h: f64) -> f64 {
    1e-8 * density * h * h
}

/// Initial stress of each lattice point.
fn initial_stresses(
    spec: &BodySpec,
    positions: &[DVec2],
    spacing: f64,
    gravity: DVec2,
) -> Vec<Stress> {
    match spec.initial_stress {
        InitialStress::None => vec![Stress::ZERO; positions.len()],
        InitialStress::Lithostatic => {
            // The body's top surface above each lattice column.
            let column = |x: f64| (x / spacing).floor() as i64;
            let mut top = std::collections::HashMap::new();
            for p in positions {
                let t = top.entry(column(p.x)).or_insert(f64::NEG_INFINITY);
                *t = f64::max(*t, p.y + 0.5 * spacing);
            }
            let rho = spec.material.density();
            let k0 = spec
                .lateral_stress_ratio
                .unwrap_or_else(|| spec.material.lithostatic_ratio());
            positions
                .iter()
                .map(|p| {
                    let syy = rho * gravity.y * (top[&column(p.x)] - p.y);
                    Stress {
                        xx: k0 * syy,
                        yy: syy,
                        xy: 0.0,
                        zz: k0 * syy,
                    }
                })
                .collect()
        }
    }
}

impl Simulation {
    /// Builds the world and schedule of a checked scene and observes the t = 0 state,
    /// keeping every output in memory only.
    pub fn new(scene: &Scene) -> Simulation {
        let mut sim =
            Simulation::build(scene, None).expect("no files are written without a directory");
        sim.observe();
        sim
    }

    /// As [`Simulation::new`], also writing outputs into `dir` (which must exist).
    pub fn with_output(scene: &Scene, dir: &std::path::Path) -> std::io::Result<Simulation> {
        let mut sim = Simulation::build(scene, Some(dir))?;
        sim.observe();
        Ok(sim)
    }

    /// The simulation of `scene` before its t = 0 outputs: what a checkpoint restores into
    /// (`Checkpoint::restore`). Observing t = 0 would have the outputs
    /// record, and open their files for, a state that the checkpoint then replaces (the
    /// Rerun recorder would start its file afresh).
    pub fn unobserved(scene: &Scene) -> Simulation {
        let mut sim =
            Simulation::build(scene, None).expect("no files are written without a directory");
        sim.world.resource_mut::<Clock>().observing = false;
        sim
    }

    /// Diagnostics and Output on the t = 0 state, without a step.
    fn observe(&mut self) {
        self.schedule.run(&mut self.world);
        self.world.resource_mut::<Clock>().observing = false;
    }

    fn build(scene: &Scene, dir: Option<&std::path::Path>) -> std::io::Result<Simulation> {
        let grid = scene.grid();
        let mut world = World::new();
        let options = StepOptions::of(scene);
        let mut schedule = build_schedule(&options);
        // The contact law's resources, where the step runs its system (two bodies or more).
        if let Some(contact) = options.contact {
            contact.insert_resources(&mut world);
        }
        let mut tracked = Vec::new();
        for (index, spec) in scene.bodies.iter().enumerate() {
            let lattice = fill(&*spec.shape, &grid, spec.points_per_cell);
            let n = lattice.positions.len();
            let density = spec.material.density();
            // With a known area (and the whole shape inside the domain, as checked) the
            // points share the exact mass; otherwise each carries its lattice cell's.
            let cell_area = lattice.spacing * lattice.spacing;
            let area = spec.shape.area().unwrap_or(cell_area * n as f64);
            let mass = density * area / n as f64;
            let stress = initial_stresses(spec, &lattice.positions, lattice.spacing, scene.gravity);
            let volume: Vec<f64> = stress
                .iter()
                .map(|s| spec.material.initial_volume(mass, s))
                .collect();
            let point_density = volume.iter().map(|v| mass / v).collect();
            let points = Points {
                position: lattice.positions,
                velocity: vec![spec.velocity; n],
                mass: vec![mass; n],
                volume,
                half_width: vec![0.5 * lattice.spacing; n],
                stress,
                velocity_gradient: vec![DMat2::ZERO; n],
                advection: vec![spec.velocity; n],
                affine: if scene.transfer.affine() {
                    vec![DMat2::ZERO; n]
                } else {
                    Vec::new()
                },
                density: point_density,
            };
            let body = Body {
                name: spec.name.clone(),
                index,
                tracked: spec.tracked,
                material: spec.material.name(),
                wave_speed: spec.material.wave_speed(),
                inertial_scale: spec.material.inertial_scale(),
                granular: spec.material.granular(),
            };
            if spec.tracked {
                tracked.push(spec.name.clone());
            }
            let field = GridField::new(
                grid.node_count(),
                mass_tolerance(density, grid.cell_size),
                scene
                    .contact
                    .needs_normal_of(&spec.name, scene.bodies.len()),
            );
            let mut entity = world.spawn((
                body,
                points,
                PointStates::new(n),
                field,
                BodyState::default(),
                Bands::default(),
                Location::default(),
                Surveys::default(),
            ));
            spec.material.attach(&mut entity, n);
            let fields = scene.fields_of(spec);
            if !fields.is_empty() {
                entity.insert((
                    FieldColumns::default(),
                    GridFields::default(),
                    StartBands::default(),
                ));
                for field in fields {
                    field.attach(&mut entity);
                }
            }
            if scene.dilatation == Dilatation::CellAveraged {
                entity.insert(CellDilatation::new(grid.cells[0] * grid.cells[1]));
            }
        }
        for output in &scene.outputs {
            output.install(&mut Install::new(&mut world, &mut schedule));
        }
        for condition in &scene.conditions {
            condition.install(&mut Install::new(&mut world, &mut schedule));
        }
        scene.registries.install(&mut world, &mut schedule);
        world.insert_resource(Obstacles::new(&scene.obstacles, &grid));
        world.insert_resource(grid);
        world.insert_resource(Clock::start(scene.time.end));
        world.insert_resource(StepRule::new(scene.time.step, scene.time.allow_unstable));
        world.insert_resource(OutputClock {
            interval: Interval::new(scene.time.output_every),
            due: false,
        });
        world.insert_resource(EnergyLimit {
            bound: scene.limits.max_kinetic_energy,
        });
        world.insert_resource(Gravity(scene.gravity));
        world.insert_resource(Boundaries(scene.walls.clone()));
        if let Spacing::DeltaCorrection(constants) = scene.spacing {
            world.insert_resource(constants);
            world.insert_resource(SpacingScratch::default());
        }
        world.insert_resource(VelocityRule {
            transfer: scene.transfer.0.clone(),
            flip: scene.flip,
        });
        world.insert_resource(crate::kernels::Kernels::detect());
        world.insert_resource(Health::default());
        world.insert_resource(OutputFaults::default());
        world.insert_resource(Timings::default());
        let mut trajectory = Trajectory::new(&tracked);
        if let Some(dir) = dir {
            trajectory.open(dir)?;
        }
        world.insert_resource(trajectory);
        world.insert_resource(RunDir(dir.map(|d| d.to_path_buf())));
        Ok(Simulation { world, schedule })
    }

    /// Sends outputs to `dir` from now on (for a resumed run): the trajectory so far is
    /// written to `trajectory.csv.part` and streamed from there.
    pub fn write_to(&mut self, dir: &std::path::Path) -> std::io::Result<()> {
        self.world.resource_mut::<RunDir>().0 = Some(dir.to_path_buf());
        self.world.resource_mut::<Trajectory>().open(dir)
    }

    /// Takes one step; a fault (non-finite state, escaped point, write error) stops it.
    pub fn step(&mut self) -> Result<(), Fault> {
        self.world.resource_mut::<Timings>().restart();
        self.schedule.run(&mut self.world);
        if let Some(fault) = self.world.resource::<OutputFaults>().take() {
            self.world
                .resource_mut::<Health>()
                .fault
                .get_or_insert(fault);
        }
        match &self.world.resource::<Health>().fault {
            Some(f) => Err(f.clone()),
            None => Ok(()),
        }
    }

    /// Whether the end time has been reached.
    pub fn finished(&self) -> bool {
        let c = self.clock();
        c.time >= c.end
    }

    /// Steps to the end time, calling `each` after every step.
    /// The loop runs on a rayon worker thread (see [`on_worker`]).
    pub fn run(&mut self, mut each: impl FnMut(&Clock) + Send) -> Result<(), Fault> {
        on_worker(|| {
            while !self.finished() {
                self.step()?;
                each(self.clock());
            }
            Ok(())
        })
    }

    pub fn clock(&self) -> &Clock {
        self.world.resource::<Clock>()
    }

    pub fn grid(&self) -> &GridGeometry {
        self.world.resource::<GridGeometry>()
    }

    pub fn trajectory(&self) -> &Trajectory {
        self.world.resource::<Trajectory>()
    }

    pub fn trajectory_mut(&mut self) -> Mut<'_, Trajectory> {
        self.world.resource_mut::<Trajectory>()
    }

    pub fn timings(&self) -> &Timings {
        self.world.resource::<Timings>()
    }

    /// Bodies in scene order with their points and state.
    pub fn bodies(&mut self) -> Vec<(Body, BodyState, usize)> {
        let mut q = self.world.query::<(&Body, &BodyState, &Points)>();
        let mut v: Vec<_> = q
            .iter(&self.world)
            .map(|(b, s, p)| (b.clone(), *s, p.len()))
            .collect();
        v.sort_by_key(|(b, _, _)| b.index);
        v
    }

    /// Component `C` of the body called `name`.
    fn of_body<C: Component>(&mut self, name: &str) -> Option<&C> {
        let mut q = self.world.query::<(&Body, &C)>();
        q.iter(&self.world)
            .find(|(b, _)| b.name == name)
            .map(|(_, c)| c)
    }

    /// The points of the body called `name`.
    pub fn points(&mut self, name: &str) -> Option<&Points> {
        self.of_body(name)
    }

    /// The health of the body called `name` (`output::health`); `layer` is its bottom and
    /// top at the start when it is a layer.
    pub fn health(
        &mut self,
        name: &str,
        layer: Option<(f64, f64)>,
    ) -> Option<crate::output::health::BodyHealth> {
        let grid = self.grid().clone();
        let mut q = self.world.query::<(&Body, &Points, &PointStates)>();
        q.iter(&self.world)
            .find(|(b, _, _)| b.name == name)
            .map(|(_, p, s)| crate::output::health::BodyHealth::measure(p, s, &grid, layer))
    }

    /// The `state_hash` of the body called `name`, as summary.json gives it: its points'
    /// fingerprint in 16 hex digits, equal exactly when two states are bitwise equal.
    pub fn state_hash(&mut self, name: &str) -> Option<String> {
        self.points(name)
            .map(|p| format!("{:016x}", p.fingerprint()))
    }

    /// The material state of each point (plastic strain, phase) of the body called `name`.
    pub fn point_states(&mut self, name: &str) -> Option<&PointStates> {
        self.of_body(name)
    }

    /// Mutable points of the body called `name` (for tests that prescribe a state).
    pub fn points_mut(&mut self, name: &str) -> Option<Mut<'_, Points>> {
        let mut q = self.world.query::<(&Body, &mut Points, &mut Location)>();
        q.iter_mut(&mut self.world)
            .find(|(b, _, _)| b.name == name)
            .map(|(_, p, mut location)| {
                location.invalidate();
                p
            })
    }

    /// The nodal field of the body called `name`.
    pub fn grid_field(&mut self, name: &str) -> Option<&GridField> {
        self.of_body(name)
    }

    pub fn particle_count(&mut self) -> usize {
        self.bodies().iter().map(|b| b.2).sum()
    }

    /// The time step the scene's rule gives for the current state, and its CFL number.
    pub fn next_time_step(&mut self) -> (f64, f64) {
        let h = self.grid().cell_size;
        let mut q = self.world.query::<(&Body, &BodyState)>();
        let signal = crate::step::signal_speed(q.iter(&self.world));
        let rule = self.world.resource::<StepRule>().rule;
        let dt = rule.dt(h, signal, self.clock().end);
        (dt, dt * signal / h)
    }
}
