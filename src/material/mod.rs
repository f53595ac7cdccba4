//! Materials: the constitutive update of a body's points, as plugins.
//!
//! A material is a parameter type implementing [`Material`], registered under its scene name
//! as an item of kind `dyn MaterialSpec`. Bodies made of it get a [`MaterialState`] component (parameters plus
//! one history entry per point) and the schedule gets one update system for that type, added
//! only if some body uses it. Built-in materials register exactly this way.

pub mod elastic;
pub mod granular;
pub mod nonlocal;

use std::fmt::Debug;

use bevy_ecs::prelude::*;
use bevy_ecs::schedule::ScheduleConfigs;
use bevy_ecs::system::ScheduleSystem;
use bevy_ecs::world::EntityWorldMut;
use glam::DMat2;
use rayon::prelude::*;
use serde::Serialize;
use serde::de::DeserializeOwned;

use crate::body::{Phase, PointStates, Points, inertial_number};
use crate::field::Field;
use crate::grid_field::{FieldColumns, FieldValues};
use crate::registry::{DynItem, Item};
use crate::resources::Clock;
use crate::stress::Stress;

/// What the constitutive update of one point sees.
#[derive(Clone, Copy, Debug)]
pub struct PointStep<'a> {
    /// Velocity gradient of this step.
    pub velocity_gradient: DMat2,
    pub dt: f64,
    /// Current mass density with the volume already updated this step: the point's `m/V`,
    /// or the mean over its cell with cell-averaged dilatation.
    pub density: f64,
    /// The values at the point of the field columns the material reads
    /// ([`Material::point_fields`]), by name: `step.fields.get("fluidity_interpolated")`.
    pub fields: FieldValues<'a>,
}

impl PointStep<'static> {
    /// A step that reads no field.
    pub fn new(velocity_gradient: DMat2, dt: f64, density: f64) -> Self {
        PointStep {
            velocity_gradient,
            dt,
            density,
            fields: FieldValues::NONE,
        }
    }
}

/// A material model: an [`Item`] (its scene name and parameter checks) that implements
/// this, registered with `app.register::<dyn MaterialSpec, YourType>()`.
pub trait Material: Item {
    /// Per-point state the update carries from step to step.
    type History: Clone + Default + Debug + Send + Sync + Serialize + DeserializeOwned + 'static;

    /// The mass density a body of this material is filled with (kg/m^3).
    fn density(&self) -> f64;
    /// Elastic p-wave speed (m/s) for the CFL condition.
    fn wave_speed(&self) -> f64;
    /// Lateral-to-vertical stress ratio of the lithostatic initial state.
    fn lithostatic_ratio(&self) -> f64;
    /// Initial volume of a point of mass `mass` starting at `stress` (quiet start hook):
    /// by default `mass / density`.
    fn initial_volume(&self, mass: f64, _stress: &Stress) -> f64 {
        mass / self.density()
    }
    /// `d sqrt(rho_s)` for granular materials (see [`crate::body::Body::inertial_number`]).
    fn inertial_scale(&self) -> Option<f64> {
        None
    }
    /// Whether the material is granular: its stress keeps no memory of where its points sit
    /// beyond the elastic strain at yield, so the delta-correction (the scene's `spacing`,
    /// `step::spacing`) may shift them; false by default (an elastic body's points are not
    /// moved, which would deform it without a stress).
    fn granular(&self) -> bool {
        false
    }
    /// Whether steps of at most `max_dt` (s) on cells of `cell_size` (m) suit this material
    /// (the scene check asks, before a run); by default any do.
    fn check_step(&self, _cell_size: f64, _max_dt: f64) -> Result<(), String> {
        Ok(())
    }
    /// The field columns this material reads in [`Material::update`] (`PointStep::fields`),
    /// by name: a field of the body must carry each (its own, [`Material::fields`], or one
    /// the scene lists); none by default.
    fn point_fields() -> &'static [&'static str] {
        &[]
    }
    /// The fields this material brings to each of its bodies (`crate::field`: `Nonlocal`'s
    /// fluidity); none by default.
    fn fields(&self) -> Vec<Box<dyn Field>> {
        Vec::new()
    }
    /// Advances one point's stress and history over one step; returns the point's plastic
    /// shear strain rate and phase.
    fn update(
        &self,
        stress: &mut Stress,
        history: &mut Self::History,
        step: &PointStep,
    ) -> PointOutcome;
}

/// What one constitutive update reports about its point.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PointOutcome {
    /// Equivalent plastic shear strain rate (1/s), `>= 0`.
    pub plastic_strain_rate: f64,
    pub phase: Phase,
}

/// A material as the scene and the simulation builder see it: object safe, and implemented
/// for every [`Material`] (whose typed history is not).
pub trait MaterialSpec: DynItem {
    fn density(&self) -> f64;
    fn wave_speed(&self) -> f64;
    fn lithostatic_ratio(&self) -> f64;
    fn initial_volume(&self, mass: f64, stress: &Stress) -> f64;
    fn inertial_scale(&self) -> Option<f64>;
    fn granular(&self) -> bool;
    fn check_step(&self, cell_size: f64, max_dt: f64) -> Result<(), String>;
    /// Inserts the body's [`MaterialState`] for `points` points.
    fn attach(&self, entity: &mut EntityWorldMut, points: usize);
    /// This material's update system (the step runs one per material type of a scene).
    fn update_system(&self) -> ScheduleConfigs<ScheduleSystem>;
    /// The field columns the material reads ([`Material::point_fields`]).
    fn point_fields(&self) -> &'static [&'static str];
    /// The fields the material brings to its bodies ([`Material::fields`]).
    fn fields(&self) -> Vec<Box<dyn Field>>;
    /// Bytes of history per point (for memory estimates).
    fn history_bytes(&self) -> usize;
    /// The body's per-point history, encoded for a checkpoint.
    fn save_history(&self, world: &World, entity: Entity) -> Vec<u8>;
    /// Restores a history saved by [`MaterialSpec::save_history`].
    fn load_history(&self, world: &mut World, entity: Entity, bytes: &[u8]) -> Result<(), String>;
}

item_kind!(MaterialSpec, "material");

impl<M: Material> MaterialSpec for M {
    fn density(&self) -> f64 {
        Material::density(self)
    }
    fn wave_speed(&self) -> f64 {
        Material::wave_speed(self)
    }
    fn lithostatic_ratio(&self) -> f64 {
        Material::lithostatic_ratio(self)
    }
    fn initial_volume(&self, mass: f64, stress: &Stress) -> f64 {
        Material::initial_volume(self, mass, stress)
    }
    fn inertial_scale(&self) -> Option<f64> {
        Material::inertial_scale(self)
    }
    fn granular(&self) -> bool {
        Material::granular(self)
    }
    fn check_step(&self, cell_size: f64, max_dt: f64) -> Result<(), String> {
        Material::check_step(self, cell_size, max_dt)
    }
    fn attach(&self, entity: &mut EntityWorldMut, points: usize) {
        entity.insert(MaterialState::<M> {
            params: self.clone(),
            history: vec![M::History::default(); points],
        });
    }
    fn update_system(&self) -> ScheduleConfigs<ScheduleSystem> {
        // It only touches bodies carrying this material's state, so the step may run it in
        // any order with other materials' updates.
        update_stress::<M>.into_configs()
    }
    fn point_fields(&self) -> &'static [&'static str] {
        M::point_fields()
    }
    fn fields(&self) -> Vec<Box<dyn Field>> {
        Material::fields(self)
    }
    fn history_bytes(&self) -> usize {
        std::mem::size_of::<M::History>()
    }
    fn save_history(&self, world: &World, entity: Entity) -> Vec<u8> {
        let history = world
            .get::<MaterialState<M>>(entity)
            .map(|s| s.history.as_slice())
            .unwrap_or(&[]);
        bincode::serialize(history).expect("material history serialises")
    }
    fn load_history(&self, world: &mut World, entity: Entity, bytes: &[u8]) -> Result<(), String> {
        let history: Vec<M::History> = bincode::deserialize(bytes)
            .map_err(|e| format!("material history of {}: {e}", M::NAME))?;
        match world.get_mut::<MaterialState<M>>(entity) {
            Some(mut state) if state.history.len() == history.len() => {
                state.history = history;
                Ok(())
            }
            _ => Err(format!(
                "the checkpoint's {} history does not fit the body",
                M::NAME
            )),
        }
    }
}

/// A body's material parameters and per-point history.
#[derive(Component, Clone, Debug)]
pub struct MaterialState<M: Material> {
    pub params: M,
    pub history: Vec<M::History>,
}

/// The constitutive update of every body made of `M` (docs/model.md §2, step 7).
pub fn update_stress<M: Material>(
    clock: Res<Clock>,
    mut bodies: Query<(
        &mut Points,
        &mut PointStates,
        &mut MaterialState<M>,
        Option<&FieldColumns>,
    )>,
) {
    let dt = clock.dt;
    for (mut points, mut states, mut state, columns) in &mut bodies {
        // The columns the material reads, found by name once per body (the scene check has
        // made sure the body's fields carry them).
        let read: Vec<(&str, &[f64])> = M::point_fields()
            .iter()
            .map(|&name| {
                let column = columns.and_then(|c| c.get(name));
                (
                    name,
                    column.unwrap_or_else(|| panic!("no field carries column {name}")),
                )
            })
            .collect();
        // The stress update never moves a point, so it leaves `Points` unmarked: the cells
        // found after this step's move stay current for the next step (`step::Location`).
        let points = points.bypass_change_detection();
        let states = &mut *states;
        let state = &mut *state;
        let params = &state.params;
        let scale = params.inertial_scale();
        points
            .stress
            .par_iter_mut()
            .zip(state.history.par_iter_mut())
            .zip(points.velocity_gradient.par_iter())
            .zip(points.density.par_iter())
            .zip(
                states
                    .plastic_strain_rate
                    .par_iter_mut()
                    .zip(states.plastic_strain.par_iter_mut())
                    .zip(states.phase.par_iter_mut()),
            )
            .enumerate()
            .for_each(
                |(k, ((((stress, history), &l), &density), ((rate, strain), phase)))| {
                    let step = PointStep {
                        velocity_gradient: l,
                        dt,
                        density,
                        fields: FieldValues::new(&read, k),
                    };
                    let outcome = params.update(stress, history, &step);
                    *rate = outcome.plastic_strain_rate;
                    *strain += outcome.plastic_strain_rate * dt;
                    let p = stress.pressure();
                    *phase = outcome.phase.at_inertial_number(
                        scale.map(|s| inertial_number(s, outcome.plastic_strain_rate, p)),
                    );
                },
            );
    }
}
