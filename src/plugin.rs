//! Plugins: how scene items, systems and resources become part of regolith.
//!
//! A [`Plugin`] receives the [`Regolith`] being assembled and adds to it: scene items of any
//! kind ([`Regolith::register`]: materials, shapes, outputs, conditions, or a kind of the
//! plugin's own), systems for a named step set ([`Regolith::add_systems`]) and resources
//! ([`Regolith::insert_resource`]). A scene is parsed against the result and carries it (the
//! scene's `registries`), so a simulation built from the scene runs the systems its plugins
//! added. The built-in items come in `DefaultPlugins` (module `defaults`, above every item)
//! and register exactly as a user's plugin would.
//!
//! This module sits below the items: an item installs itself through [`Install`], and nothing
//! here names an item.

use std::sync::Arc;

use bevy_ecs::prelude::*;
use bevy_ecs::schedule::ScheduleConfigs;
use bevy_ecs::system::ScheduleSystem;

use crate::registry::{IntoKind, Item, Kind, Registries};
use crate::step::{Core, StepSet};

/// Something that adds scene items, systems or resources to regolith.
pub trait Plugin {
    fn build(&self, app: &mut Regolith);
}

/// The set of plugins a program uses, being assembled; [`Regolith::registries`] freezes it
/// for parsing scenes. `Regolith::default()` starts from the built-in items
/// (`DefaultPlugins`), [`Regolith::empty`] from none.
pub struct Regolith {
    registries: Registries,
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

    /// The entity of the body called `name`, found once here so that the item's systems
    /// reach its components directly every step (`Query::get`) instead of comparing names;
    /// `None` for a name no body has (the scene check refuses an item naming one).
    pub fn body(&mut self, name: &str) -> Option<Entity> {
        let mut bodies = self.world.query::<(Entity, &crate::body::Body)>();
        bodies
            .iter(self.world)
            .find(|(_, b)| b.name == name)
            .map(|(e, _)| e)
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
