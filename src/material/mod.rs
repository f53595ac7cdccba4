//! Materials: the constitutive update of a body's points, as plugins.
//!
//! A material is a parameter type implementing [`Material`]; [`MaterialPlugin`] registers it
//! under its scene name. Bodies made of it get a [`MaterialState`] component (parameters plus
//! one history entry per point) and the schedule gets one update system for that type, added
//! only if some body uses it. Built-in materials register exactly this way.

pub mod elastic;
pub mod granular;

use std::fmt::Debug;
use std::marker::PhantomData;

use bevy_ecs::prelude::*;
use bevy_ecs::world::EntityWorldMut;
use glam::DMat2;
use rayon::prelude::*;
use serde::Serialize;
use serde::de::DeserializeOwned;

use crate::body::{Phase, PointStates, Points};
use crate::plugin::Plugin;
use crate::registry::{IntoSpec, Registries, construct};
use crate::sim::Clock;
use crate::step::{MaterialUpdates, StepSet};
use crate::stress::Stress;

/// What the constitutive update of one point sees.
#[derive(Clone, Copy, Debug)]
pub struct PointStep {
    /// Velocity gradient of this step.
    pub velocity_gradient: DMat2,
    pub dt: f64,
    /// Current mass density with the volume already updated this step: the point's `m/V`,
    /// or the mean over its cell with cell-averaged dilatation.
    pub density: f64,
}

/// A material model. Implement this, then add `MaterialPlugin::<YourType>::default()`.
pub trait Material: Clone + Debug + Send + Sync + DeserializeOwned + 'static {
    /// The name used in scene files, e.g. `LinearElastic`.
    const NAME: &'static str;
    /// Per-point state the update carries from step to step.
    type History: Clone + Default + Debug + Send + Sync + Serialize + DeserializeOwned + 'static;

    /// Checks the parameters; the message says which one is wrong and what was expected.
    fn validate(&self) -> Result<(), String>;
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

/// A material as the scene and the simulation builder see it (object safe).
pub trait MaterialSpec: Debug + Send + Sync {
    fn name(&self) -> &'static str;
    fn clone_spec(&self) -> Box<dyn MaterialSpec>;
    fn validate(&self) -> Result<(), String>;
    fn density(&self) -> f64;
    fn wave_speed(&self) -> f64;
    fn lithostatic_ratio(&self) -> f64;
    fn initial_volume(&self, mass: f64, stress: &Stress) -> f64;
    fn inertial_scale(&self) -> Option<f64>;
    /// Inserts the body's [`MaterialState`] for `points` points.
    fn attach(&self, entity: &mut EntityWorldMut, points: usize);
    /// Adds this material's update system (called once per material type in a scene).
    fn add_systems(&self, schedule: &mut Schedule);
    /// Bytes of history per point (for memory estimates).
    fn history_bytes(&self) -> usize;
    /// The body's per-point history, encoded for a checkpoint.
    fn save_history(&self, world: &World, entity: Entity) -> Vec<u8>;
    /// Restores a history saved by [`MaterialSpec::save_history`].
    fn load_history(&self, world: &mut World, entity: Entity, bytes: &[u8]) -> Result<(), String>;
}

crate::impl_named_spec!(MaterialSpec);

impl<M: Material> MaterialSpec for M {
    fn name(&self) -> &'static str {
        M::NAME
    }
    fn clone_spec(&self) -> Box<dyn MaterialSpec> {
        Box::new(self.clone())
    }
    fn validate(&self) -> Result<(), String> {
        Material::validate(self)
    }
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
    fn attach(&self, entity: &mut EntityWorldMut, points: usize) {
        entity.insert(MaterialState::<M> {
            params: self.clone(),
            history: vec![M::History::default(); points],
        });
    }
    fn add_systems(&self, schedule: &mut Schedule) {
        schedule.add_systems(
            update_stress::<M>
                .in_set(StepSet::ConstitutiveUpdate)
                .in_set(MaterialUpdates)
                // Each material's system only touches bodies carrying its own state.
                .ambiguous_with(MaterialUpdates),
        );
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

impl<M: Material> IntoSpec<dyn MaterialSpec> for M {
    fn into_spec(self) -> Box<dyn MaterialSpec> {
        Box::new(self)
    }
}

/// A body's material parameters and per-point history.
#[derive(Component, Clone, Debug)]
pub struct MaterialState<M: Material> {
    pub params: M,
    pub history: Vec<M::History>,
}

/// Registers material `M` under `M::NAME`.
pub struct MaterialPlugin<M>(PhantomData<fn() -> M>);

impl<M> Default for MaterialPlugin<M> {
    fn default() -> Self {
        MaterialPlugin(PhantomData)
    }
}

impl<M: Material> Plugin for MaterialPlugin<M> {
    fn build(&self, registries: &mut Registries) {
        registries
            .materials
            .insert(M::NAME, construct::<M, dyn MaterialSpec>);
    }
}

/// The constitutive update of every body made of `M` (SCIENCE.md 2, step 7).
pub fn update_stress<M: Material>(
    clock: Res<Clock>,
    mut bodies: Query<(&mut Points, &mut PointStates, &mut MaterialState<M>)>,
) {
    let dt = clock.dt;
    for (mut points, mut states, mut state) in &mut bodies {
        let points = &mut *points;
        let states = &mut *states;
        let state = &mut *state;
        let params = &state.params;
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
            .for_each(
                |((((stress, history), &l), &density), ((rate, strain), phase))| {
                    let step = PointStep {
                        velocity_gradient: l,
                        dt,
                        density,
                    };
                    let outcome = params.update(stress, history, &step);
                    *rate = outcome.plastic_strain_rate;
                    *strain += outcome.plastic_strain_rate * dt;
                    *phase = outcome.phase;
                },
            );
    }
}
