//! Checkpoints: the whole state a step depends on, written bit for bit, so that a resumed
//! run is bitwise identical to an uninterrupted one.
//!
//! What a step reads from the previous one: the clock, every body's points, point states and
//! material history, the energy bound, and (for outputs) the trajectory rows and each output
//! plugin's schedule, and the instant of an impact's first contact. Grid fields, cell sums and whole-body measures are recomputed from the
//! points, so they are not saved. The file is bincode (f64 as raw bits), written atomically;
//! the scene itself is the run directory's `scene.ron`.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::body::{Body, BodyState, PointStates, Points};
use crate::diagnostics::EnergyLimit;
use crate::output::impact::{ContactInstant, ImpactWatch};
use crate::output::write_atomic;
use crate::resources::{Clock, OutputClock, StepRule};
use crate::scene::Scene;
use crate::sim::Simulation;

/// Bumped whenever the layout changes; older files are refused with a message.
const FORMAT: u32 = 4;

#[derive(Serialize, Deserialize)]
pub struct Checkpoint {
    format: u32,
    /// The scene file and overrides the run started from (for its summary).
    pub scene_file: String,
    pub overrides: Vec<String>,
    clock: Clock,
    step_rule: StepRule,
    output_clock: OutputClock,
    energy_bound: Option<f64>,
    trajectory: Vec<Vec<f64>>,
    /// The `Impact` output's first contact, and its last state before contact.
    impact: Option<(Option<ContactInstant>, Option<ContactInstant>)>,
    bodies: Vec<BodyCheckpoint>,
}

#[derive(Serialize, Deserialize)]
struct BodyCheckpoint {
    name: String,
    points: Points,
    states: PointStates,
    history: Vec<u8>,
}

impl Checkpoint {
    /// Captures the state of `sim` (built from `scene`).
    pub fn capture(
        sim: &mut Simulation,
        scene: &Scene,
        scene_file: &str,
        overrides: &[String],
    ) -> Checkpoint {
        let mut q = sim
            .world
            .query::<(bevy_ecs::entity::Entity, &Body, &Points, &PointStates)>();
        let mut found: Vec<_> = q
            .iter(&sim.world)
            .map(|(e, b, p, s)| (b.index, e, b.name.clone(), p.clone(), s.clone()))
            .collect();
        found.sort_by_key(|f| f.0);
        let bodies = found
            .into_iter()
            .map(|(index, entity, name, points, states)| BodyCheckpoint {
                history: scene.bodies[index]
                    .material
                    .save_history(&sim.world, entity),
                name,
                points,
                states,
            })
            .collect();
        Checkpoint {
            format: FORMAT,
            scene_file: scene_file.to_string(),
            overrides: overrides.to_vec(),
            clock: sim.clock().clone(),
            step_rule: sim.world.resource::<StepRule>().clone(),
            output_clock: sim.world.resource::<OutputClock>().clone(),
            energy_bound: sim.world.resource::<EnergyLimit>().bound,
            trajectory: sim.trajectory().rows.clone(),
            impact: sim
                .world
                .get_resource::<ImpactWatch>()
                .map(|w| (w.contact, w.before)),
            bodies,
        }
    }

    /// Writes the checkpoint atomically.
    pub fn write(&self, path: &Path) -> std::io::Result<()> {
        let bytes = bincode::serialize(self).map_err(std::io::Error::other)?;
        write_atomic(path, &bytes)
    }

    /// Reads a checkpoint written by [`Checkpoint::write`].
    pub fn read(path: &Path) -> Result<Checkpoint, String> {
        let bytes =
            std::fs::read(path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
        let c: Checkpoint = bincode::deserialize(&bytes)
            .map_err(|e| format!("{} is not a regolith checkpoint: {e}", path.display()))?;
        if c.format != FORMAT {
            return Err(format!(
                "{} has checkpoint format {}, this regolith reads {FORMAT}",
                path.display(),
                c.format
            ));
        }
        Ok(c)
    }

    /// Puts the saved state into `sim`, a fresh simulation of the same scene.
    pub fn restore(self, sim: &mut Simulation, scene: &Scene) -> Result<(), String> {
        let mut q = sim.world.query::<(bevy_ecs::entity::Entity, &Body)>();
        let entities: Vec<_> = q
            .iter(&sim.world)
            .map(|(e, b)| (e, b.name.clone(), b.index))
            .collect();
        if entities.len() != self.bodies.len() {
            return Err("the checkpoint's bodies do not match the scene".into());
        }
        for saved in self.bodies {
            let Some(&(entity, _, index)) = entities.iter().find(|(_, n, _)| *n == saved.name)
            else {
                return Err(format!(
                    "the scene has no body \"{}\" from the checkpoint",
                    saved.name
                ));
            };
            let mut e = sim.world.entity_mut(entity);
            let state = BodyState::measure(&saved.points);
            if e.get::<Points>().map(|p| p.len()) != Some(saved.points.len()) {
                return Err(format!(
                    "body \"{}\" has a different number of points",
                    saved.name
                ));
            }
            e.insert((saved.points, saved.states, state));
            scene.bodies[index]
                .material
                .load_history(&mut sim.world, entity, &saved.history)?;
        }
        let time = self.clock.time;
        *sim.world.resource_mut::<Clock>() = self.clock;
        *sim.world.resource_mut::<StepRule>() = self.step_rule;
        *sim.world.resource_mut::<OutputClock>() = self.output_clock;
        sim.world.resource_mut::<EnergyLimit>().bound = self.energy_bound;
        sim.trajectory_mut().rows = self.trajectory;
        for output in &scene.outputs {
            output.resume(&mut sim.world, time);
        }
        for condition in &scene.conditions {
            condition.resume(&mut sim.world, time);
        }
        if let (Some(mut watch), Some((contact, before))) =
            (sim.world.get_resource_mut::<ImpactWatch>(), self.impact)
        {
            (watch.contact, watch.before) = (contact, before);
        }
        Ok(())
    }
}
