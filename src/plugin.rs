//! Plugins: how materials, shapes and outputs become available to scenes.
//!
//! [`Regolith`] collects plugins; each registers what it provides by name in the
//! [`Registries`]. Scenes are then parsed against those names, and a simulation built from a
//! scene adds only the systems its bodies and outputs need. The built-in items come in
//! [`DefaultPlugins`] and register exactly as a user's plugin would.

use std::path::Path;
use std::rc::Rc;

use crate::error::SceneError;
use crate::flow_field::FlowField;
use crate::free_surface::FreeSurface;
use crate::front::PressureFront;
use crate::impact::Impact;
use crate::material::MaterialPlugin;
use crate::material::elastic::LinearElastic;
use crate::material::granular::{DruckerPrager, MuI};
use crate::output::OutputPlugin;
use crate::output::snapshots::Snapshots;
use crate::output::vtk::Vtk;
use crate::registry::Registries;
use crate::scene::Scene;
use crate::shape::ShapePlugin;
use crate::shape::builtin::{Disc, Polygon, Rectangle};
use crate::shape::intruder::TippedIntruder;

/// Something that registers scene items.
pub trait Plugin {
    fn build(&self, registries: &mut Registries);
}

/// The built-in materials, shapes and outputs.
pub struct DefaultPlugins;

impl Plugin for DefaultPlugins {
    fn build(&self, r: &mut Registries) {
        MaterialPlugin::<LinearElastic>::default().build(r);
        MaterialPlugin::<MuI>::default().build(r);
        MaterialPlugin::<DruckerPrager>::default().build(r);
        ShapePlugin::<Rectangle>::default().build(r);
        ShapePlugin::<Disc>::default().build(r);
        ShapePlugin::<Polygon>::default().build(r);
        ShapePlugin::<TippedIntruder>::default().build(r);
        OutputPlugin::<Snapshots>::default().build(r);
        OutputPlugin::<Vtk>::default().build(r);
        OutputPlugin::<Impact>::default().build(r);
        OutputPlugin::<PressureFront>::default().build(r);
        OutputPlugin::<FlowField>::default().build(r);
        OutputPlugin::<FreeSurface>::default().build(r);
    }
}

/// The set of plugins a program uses, and the scene loader that knows their names.
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
        plugin.build(&mut self.registries);
        self
    }

    /// The registered catalogues, ready for parsing.
    pub fn registries(self) -> Rc<Registries> {
        Rc::new(self.registries)
    }
}

/// Parses scene text against the default plugins (a convenience for tests and examples).
pub fn parse_scene(text: &str) -> Result<Scene, SceneError> {
    Scene::parse(text, "<scene>", &Regolith::default().registries())
}

/// Loads a scene file against the default plugins.
pub fn load_scene(path: &Path) -> Result<Scene, SceneError> {
    Ok(Scene::load(path, &[], &Regolith::default().registries())?.0)
}
