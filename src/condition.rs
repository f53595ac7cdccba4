//! Conditions: what a scene imposes on its bodies beyond their material and shape, as
//! plugins (`conditions: [Driven(body: "intruder", velocity: (0.0, -0.5))]`).
//!
//! A driven body, a prescribed displacement or a boundary condition acts inside the step:
//! a condition installs its own resources and systems into named step sets through
//! [`Install`](crate::plugin::Install), as outputs do, and may add its own section to
//! `summary.json`. The engine has no built-in condition; the kind exists for plugins
//! (plugins/driven_intruder is one) and goes through the same generic catalogue as every
//! other kind of scene item.

use bevy_ecs::prelude::*;

use crate::carry::Carried;
use crate::output::summary::Section;
use crate::plugin::Install;
use crate::registry::DynItem;
use crate::scene_view::SceneView;

/// A condition: an [`Item`](crate::registry::Item) (its scene name and parameter checks)
/// that implements this, registered with `app.register::<dyn Condition, YourType>()`.
pub trait Condition: DynItem {
    /// What must hold between the condition and the rest of the scene (e.g. that the body it
    /// names exists); `check` reports a failure at the condition's line. By default nothing.
    fn check_scene(&self, _scene: &SceneView) -> Result<(), String> {
        Ok(())
    }
    /// Adds the condition's resources and systems.
    fn install(&self, sim: &mut Install);
    /// The condition's entries in `summary.json`; by default none.
    fn summary(&self, _world: &World) -> Section {
        Section::default()
    }
    /// What the condition carries across a checkpoint (`crate::carry`), as
    /// `Output::save`: by default it says it cannot, and a
    /// resumed run is marked partial.
    fn save(&self, _world: &World) -> Carried {
        Carried::Lost(format!(
            "the {} condition does not save its state in checkpoints: it restarted at the resume",
            self.name()
        ))
    }
    /// Puts back the state `save` returned, before the first resumed step.
    fn restore(&self, _world: &mut World, _state: &[u8]) -> Result<(), String> {
        Err(format!(
            "the {} condition cannot restore a state",
            self.name()
        ))
    }
}

item_kind!(Condition, "condition");
