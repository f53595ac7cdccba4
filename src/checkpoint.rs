//! Checkpoints: the whole state a step depends on, written bit for bit, so that a resumed
//! run is bitwise identical to an uninterrupted one.
//!
//! What a step reads from the previous one: the clock, every body's points, point states,
//! material history and field columns (`grid_field::FieldColumns`, by name), the energy bound; and for the outputs the trajectory rows, the output
//! clock, and whatever each output and condition carries (`crate::carry`: its records, its
//! schedule, the instant of an impact's first contact, the frames a collection lists). Grid
//! fields, cell sums and whole-body measures are recomputed from the points, so they are not
//! saved. The file is bincode (f64 as raw bits), written atomically; the scene itself is the
//! run directory's `scene.ron`.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::body::{Body, BodyState, PointStates, Points};
use crate::carry::{Carried, Partial};
use crate::diagnostics::EnergyLimit;
use crate::format::Seconds;
use crate::grid_field::{Column, FieldColumns};
use crate::output::write_atomic;
use crate::resources::{Clock, OutputClock, StepRule};
use crate::scene::Scene;
use crate::sim::Simulation;

/// Bumped whenever the layout changes; older files are refused with a message.
const FORMAT: u32 = 7;

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
    /// What each output and condition carries, in scene order.
    items: Vec<ItemCheckpoint>,
    /// Why the run so far is partial (from earlier resumes).
    partial: Partial,
    bodies: Vec<BodyCheckpoint>,
}

/// One output's or condition's carried state, keyed by its place and name in the scene.
#[derive(Serialize, Deserialize)]
struct ItemCheckpoint {
    /// `output` or `condition`.
    kind: String,
    index: usize,
    name: String,
    carried: Carried,
}

impl ItemCheckpoint {
    fn of(kind: &str, index: usize, name: &str, carried: Carried) -> ItemCheckpoint {
        ItemCheckpoint {
            kind: kind.to_string(),
            index,
            name: name.to_string(),
            carried,
        }
    }
}

#[derive(Serialize, Deserialize)]
struct BodyCheckpoint {
    name: String,
    points: Points,
    states: PointStates,
    history: Vec<u8>,
    /// The columns of the body's fields (none for a body without fields).
    columns: Vec<Column>,
}

impl Checkpoint {
    /// Captures the state of `sim` (built from `scene`).
    pub fn capture(
        sim: &mut Simulation,
        scene: &Scene,
        scene_file: &str,
        overrides: &[String],
    ) -> Checkpoint {
        let mut q = sim.world.query::<(
            bevy_ecs::entity::Entity,
            &Body,
            &Points,
            &PointStates,
            Option<&FieldColumns>,
        )>();
        let mut found: Vec<_> = q
            .iter(&sim.world)
            .map(|(e, b, p, s, c)| {
                let columns = c.map_or(Vec::new(), |c| c.columns().to_vec());
                (b.index, e, b.name.clone(), p.clone(), s.clone(), columns)
            })
            .collect();
        found.sort_by_key(|f| f.0);
        let bodies = found
            .into_iter()
            .map(
                |(index, entity, name, points, states, columns)| BodyCheckpoint {
                    history: scene.bodies[index]
                        .material
                        .save_history(&sim.world, entity),
                    name,
                    points,
                    states,
                    columns,
                },
            )
            .collect();
        let world = &sim.world;
        let outputs = scene.outputs.iter().enumerate();
        let outputs =
            outputs.map(|(k, o)| ItemCheckpoint::of("output", k, o.name(), o.save(world)));
        let conditions = scene.conditions.iter().enumerate();
        let conditions =
            conditions.map(|(k, c)| ItemCheckpoint::of("condition", k, c.name(), c.save(world)));
        let items = outputs.chain(conditions).collect();
        Checkpoint {
            format: FORMAT,
            scene_file: scene_file.to_string(),
            overrides: overrides.to_vec(),
            clock: sim.clock().clone(),
            step_rule: sim.world.resource::<StepRule>().clone(),
            output_clock: sim.world.resource::<OutputClock>().clone(),
            energy_bound: sim.world.resource::<EnergyLimit>().bound,
            trajectory: sim.trajectory().rows.clone(),
            items,
            partial: world.get_resource::<Partial>().cloned().unwrap_or_default(),
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

    /// Puts the saved state into `sim`, a fresh simulation of the same scene made by
    /// [`Simulation::unobserved`] (so that no output has recorded or opened a file for the
    /// initial state the checkpoint replaces).
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
            match e.get_mut::<FieldColumns>() {
                Some(mut columns) => columns.restore(saved.columns),
                None if saved.columns.is_empty() => Ok(()),
                None => {
                    Err("the checkpoint carries field columns the scene's fields do not".into())
                }
            }
            .map_err(|m| format!("body \"{}\": {m}", saved.name))?;
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
        let mut partial = self.partial.0;
        for (k, output) in scene.outputs.iter().enumerate() {
            let restore = |state: &[u8]| output.restore(&mut sim.world, state);
            let key = ("output", k, output.name());
            carry_over(&self.items, key, time, restore, &mut partial)?;
        }
        for (k, condition) in scene.conditions.iter().enumerate() {
            let restore = |state: &[u8]| condition.restore(&mut sim.world, state);
            let key = ("condition", k, condition.name());
            carry_over(&self.items, key, time, restore, &mut partial)?;
        }
        // An item of the interrupted run that the resumed scene lacks (a recording not asked
        // for again) stops at the checkpoint.
        for item in &self.items {
            let listed = match item.kind.as_str() {
                "output" => scene.outputs.get(item.index).map(|o| o.name()),
                _ => scene.conditions.get(item.index).map(|c| c.name()),
            };
            if listed != Some(item.name.as_str()) {
                partial.push(format!(
                    "the {} {} of the interrupted run was not asked for again: its record ends at t = {} s",
                    item.name,
                    item.kind,
                    Seconds(time)
                ));
            }
        }
        if !partial.is_empty() {
            sim.world.insert_resource(Partial(partial));
        }
        Ok(())
    }
}

/// Restores the `index`-th item of `kind`, called `name`, from what the checkpoint holds of
/// it, or records why its results are partial: it could not carry its state, or it was not
/// in the run that was interrupted (an output added at the resume, such as a recording).
fn carry_over(
    items: &[ItemCheckpoint],
    (kind, index, name): (&str, usize, &str),
    time: f64,
    restore: impl FnOnce(&[u8]) -> Result<(), String>,
    partial: &mut Vec<String>,
) -> Result<(), String> {
    let saved = items
        .iter()
        .find(|i| i.kind == kind && i.index == index && i.name == name);
    match saved.map(|i| &i.carried) {
        None => partial.push(format!(
            "the {name} {kind} was added when the run resumed at t = {} s: it holds only what came after",
            Seconds(time)
        )),
        Some(Carried::Nothing) => {}
        Some(Carried::State(state)) => {
            restore(state).map_err(|e| format!("the checkpoint's {name} {kind}: {e}"))?
        }
        Some(Carried::Lost(why)) => partial.push(format!("{why} (at t = {} s)", Seconds(time))),
    }
    Ok(())
}
