//! Body shapes as plugins: anything that can say whether a point is inside it.
//!
//! Bodies are filled with material points on a lattice aligned with the grid; a shape only
//! answers "is this position inside" and gives its bounding box. Built-in shapes
//! (rectangle, disc, polygon) register through [`ShapePlugin`] exactly as a user's would.

pub mod builtin;
pub mod intruder;

use std::fmt::Debug;
use std::marker::PhantomData;

use glam::DVec2;
use serde::de::DeserializeOwned;

use crate::plugin::Plugin;
use crate::registry::{IntoSpec, Registries, construct};

/// A body shape. Implement this, then add `ShapePlugin::<YourType>::default()`.
pub trait Shape: Clone + Debug + Send + Sync + DeserializeOwned + 'static {
    /// The name used in scene files, e.g. `Disc`.
    const NAME: &'static str;
    /// Checks the parameters; the message says which one is wrong and what was expected.
    fn validate(&self) -> Result<(), String>;
    /// Whether `p` lies inside the shape.
    fn contains(&self, p: DVec2) -> bool;
    /// Axis-aligned bounding box `(min, max)`.
    fn bounds(&self) -> (DVec2, DVec2);
    /// The exact area, when known: the body's points then share `density x area` between
    /// them, so its mass does not depend on how the lattice happens to cut the outline.
    fn area(&self) -> Option<f64> {
        None
    }
}

/// A shape as the scene and the body filler see it (object safe).
pub trait ShapeSpec: Debug + Send + Sync {
    fn name(&self) -> &'static str;
    fn clone_spec(&self) -> Box<dyn ShapeSpec>;
    fn validate(&self) -> Result<(), String>;
    fn contains(&self, p: DVec2) -> bool;
    fn bounds(&self) -> (DVec2, DVec2);
    fn area(&self) -> Option<f64>;
}

crate::impl_named_spec!(ShapeSpec);

impl<S: Shape> ShapeSpec for S {
    fn name(&self) -> &'static str {
        S::NAME
    }
    fn clone_spec(&self) -> Box<dyn ShapeSpec> {
        Box::new(self.clone())
    }
    fn validate(&self) -> Result<(), String> {
        Shape::validate(self)
    }
    fn contains(&self, p: DVec2) -> bool {
        Shape::contains(self, p)
    }
    fn bounds(&self) -> (DVec2, DVec2) {
        Shape::bounds(self)
    }
    fn area(&self) -> Option<f64> {
        Shape::area(self)
    }
}

impl<S: Shape> IntoSpec<dyn ShapeSpec> for S {
    fn into_spec(self) -> Box<dyn ShapeSpec> {
        Box::new(self)
    }
}

/// Registers shape `S` under `S::NAME`.
pub struct ShapePlugin<S>(PhantomData<fn() -> S>);

impl<S> Default for ShapePlugin<S> {
    fn default() -> Self {
        ShapePlugin(PhantomData)
    }
}

impl<S: Shape> Plugin for ShapePlugin<S> {
    fn build(&self, registries: &mut Registries) {
        registries
            .shapes
            .insert(S::NAME, construct::<S, dyn ShapeSpec>);
    }
}

/// Checks that a value is a finite number, naming it in the message.
pub fn finite(name: &str, v: f64) -> Result<(), String> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(format!("{name} must be a finite number, got {v}"))
    }
}

/// Checks that a value is a finite positive number, naming it in the message.
pub fn positive(name: &str, v: f64) -> Result<(), String> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(format!("{name} must be a positive number, got {v}"))
    }
}
