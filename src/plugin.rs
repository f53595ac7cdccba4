//! Plugins: how scene items, systems and resources become part of regolith.
//!
//! A [`Plugin`] receives the [`Regolith`] being assembled and adds to it: scene items of any
//! kind ([`Regolith::register`]: materials, shapes, outputs, conditions, or a kind of the
//! plugin's own), systems for a named step set ([`Regolith::add_systems`]) and resources
//! ([`Regolith::insert_resource`]). A scene is parsed against the result and carries it
//! ([`Scene::registries`](crate::scene::Scene)), so a simulation built from the scene runs the
//! systems its plugins added. The built-in items come in [`DefaultPlugins`] and register
//! exactly as a user's plugin would.

use std::sync::Arc;

use bevy_ecs::prelude::*;
use bevy_ecs::schedule::ScheduleConfigs;
use bevy_ecs::system::ScheduleSystem;

use crate::contact::{Contact, Frictional, NoSlip};
use crate::error::SceneError;
use crate::geometry::Shape;
use crate::geometry::builtin::{Disc, Polygon, Rectangle};
use crate::geometry::intruder::TippedIntruder;
use crate::material::MaterialSpec;
use crate::material::elastic::LinearElastic;
use crate::material::granular::{DruckerPrager, MuI};
use crate::material::nonlocal::Nonlocal;
use crate::output::Output;
use crate::output::discharge::Discharge;
use crate::output::flow_field::FlowField;
use crate::output::free_surface::FreeSurface;
use crate::output::front::PressureFront;
use crate::output::impact::Impact;
use crate::output::profile::VelocityProfile;
use crate::output::runout::Runout;
use crate::output::snapshots::Snapshots;
use crate::output::vtk::Vtk;
use crate::registry::{IntoKind, Item, Kind, Registries};
use crate::scene::Scene;
use crate::shape_functions::{CpdiFixed, Linear, QuadraticBspline, ShapeFunctions};
use crate::step::{Core, StepSet};
use crate::velocity::{AffineFlip, Apic, Flip, Transfer};

/// Something that adds scene items, systems or resources to regolith.
pub trait Plugin {
    fn build(&self, app: &mut Regolith);
}

/// The built-in materials, shapes, outputs, shape functions, contact laws and transfers.
pub struct DefaultPlugins;

impl Plugin for DefaultPlugins {
    fn build(&self, app: &mut Regolith) {
        app.register::<dyn MaterialSpec, LinearElastic>()
            .register::<dyn MaterialSpec, MuI>()
            .register::<dyn MaterialSpec, DruckerPrager>()
            .register::<dyn MaterialSpec, Nonlocal>()
            .register::<dyn Shape, Rectangle>()
            .register::<dyn Shape, Disc>()
            .register::<dyn Shape, Polygon>()
            .register::<dyn Shape, TippedIntruder>()
            .register::<dyn Output, Snapshots>()
            .register::<dyn Output, Vtk>()
            .register::<dyn Output, Impact>()
            .register::<dyn Output, PressureFront>()
            .register::<dyn Output, FlowField>()
            .register::<dyn Output, FreeSurface>()
            .register::<dyn Output, Discharge>()
            .register::<dyn Output, Runout>()
            .register::<dyn Output, VelocityProfile>()
            .register::<dyn ShapeFunctions, Linear>()
            .register::<dyn ShapeFunctions, CpdiFixed>()
            .register::<dyn ShapeFunctions, QuadraticBspline>()
            .register::<dyn Contact, NoSlip>()
            .register::<dyn Contact, Frictional>()
            .register::<dyn Transfer, Flip>()
            .register::<dyn Transfer, Apic>()
            .register::<dyn Transfer, AffineFlip>();
    }
}

/// The set of plugins a program uses, being assembled; [`Regolith::registries`] freezes it
/// for parsing scenes.
pub struct Regolith {
    registries: Registries,
}

impl Default for Regolith {
    /// With [`DefaultPlugins`].
    fn default() -> Self {
        Regolith::empty().add_plugin(DefaultPlugins)
    }
}

impl Regolith {
    /// No plugins at all (not even the built-ins).
    pub fn empty() -> Self {
        Regolith {
            registries: Registries::default(),
        }
    }

    pub fn add_plugin(mut self, plugin: impl Plugin) -> Self {
        plugin.build(&mut self);
        self
    }

    /// Makes item `P` available to scenes under `P::NAME` as an item of kind `K`, e.g.
    /// `app.register::<dyn Shape, Ellipse>()`. A later registration of the same name
    /// replaces an earlier one (a user's plugin may override a built-in).
    pub fn register<K: ?Sized + Kind, P: Item + IntoKind<K>>(&mut self) -> &mut Self {
        self.registries.register::<K, P>();
        self
    }

    /// Adds `systems` to step set `set` of every simulation, after the set's core systems,
    /// e.g. `app.add_systems(StepSet::Prepare, drive_points)`. The schedule's ambiguity
    /// check rejects two systems that touch the same data in no defined order (naming
    /// both); order yours with bevy's `before`/`after`.
    pub fn add_systems<M>(
        &mut self,
        set: StepSet,
        systems: impl IntoScheduleConfigs<ScheduleSystem, M> + Clone + Send + Sync + 'static,
    ) -> &mut Self {
        self.registries.push_systems(Arc::new(move |schedule| {
            schedule.add_systems(after_core(set, systems.clone()));
        }));
        self
    }

    /// Inserts `resource` into every simulation's world (a copy each).
    pub fn insert_resource<R: Resource + Clone>(&mut self, resource: R) -> &mut Self {
        self.registries.push_resource(Arc::new(move |world| {
            world.insert_resource(resource.clone())
        }));
        self
    }

    /// What the plugins added, ready for parsing scenes.
    pub fn registries(self) -> Arc<Registries> {
        Arc::new(self.registries)
    }
}

/// What a scene item (an output, a condition) may add to the simulation being built: its
/// resources, and its systems in a named step set, after the set's core systems.
pub struct Install<'a> {
    world: &'a mut World,
    schedule: &'a mut Schedule,
}

impl<'a> Install<'a> {
    pub(crate) fn new(world: &'a mut World, schedule: &'a mut Schedule) -> Self {
        Install { world, schedule }
    }

    /// Adds `systems` to step set `set`, after the set's core systems.
    pub fn add_systems<M>(
        &mut self,
        set: StepSet,
        systems: impl IntoScheduleConfigs<ScheduleSystem, M>,
    ) -> &mut Self {
        self.schedule.add_systems(after_core(set, systems));
        self
    }

    pub fn insert_resource<R: Resource>(&mut self, resource: R) -> &mut Self {
        self.world.insert_resource(resource);
        self
    }

    /// The world as built so far: the bodies (with their points at t = 0), the grid.
    pub fn world(&mut self) -> &mut World {
        self.world
    }
}

/// `systems` in step set `set`, after its core systems: where every system a plugin or a
/// scene item adds goes.
fn after_core<M>(
    set: StepSet,
    systems: impl IntoScheduleConfigs<ScheduleSystem, M>,
) -> ScheduleConfigs<ScheduleSystem> {
    systems.in_set(set).after(Core(set))
}

/// Parses scene text against the default plugins (a convenience for tests and examples).
pub fn parse_scene(text: &str) -> Result<Scene, SceneError> {
    Scene::parse(text, "<scene>", &Regolith::default().registries())
}
