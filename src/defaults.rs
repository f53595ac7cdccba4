//! The built-in items (materials, shapes, outputs, shape functions, contact laws, transfers),
//! registered exactly as a user's plugin registers its own.
//!
//! This is the one module that names every item, so it stands above all of them: the items
//! install themselves through [`crate::plugin`] below, and never import this list.

use crate::contact::{Contact, Frictional, NoSlip};
use crate::error::SceneError;
use crate::geometry::Shape;
use crate::geometry::builtin::{Disc, Polygon, Rectangle};
use crate::geometry::intruder::TippedIntruder;
use crate::integration::ShapeFunctions;
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
use crate::plugin::{Plugin, Regolith};
use crate::scene::Scene;
use crate::shape_functions::{CpdiFixed, Linear, QuadraticBspline};
use crate::transfer::{AffineFlip, Apic, Flip, Transfer};

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

impl Default for Regolith {
    /// With [`DefaultPlugins`].
    fn default() -> Self {
        Regolith::empty().add_plugin(DefaultPlugins)
    }
}

/// Parses scene text against the default plugins (a convenience for tests and examples).
pub fn parse_scene(text: &str) -> Result<Scene, SceneError> {
    Scene::parse(text, "<scene>", &Regolith::default().registries())
}
