//! Body shapes as plugins: anything that can say whether a point is inside it.
//!
//! Bodies are filled with material points on a lattice aligned with the grid; a shape only
//! answers "is this position inside" and gives its bounding box. Built-in shapes
//! (rectangle, disc, polygon, the tipped intruder) register exactly as a user's would.

pub mod builtin;
pub mod intruder;

use glam::DVec2;

use crate::registry::DynItem;

/// A body shape: an [`Item`](crate::registry::Item) (its scene name and parameter checks)
/// that implements this, registered with `app.register::<dyn Shape, YourType>()`.
pub trait Shape: DynItem {
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

crate::item_kind!(Shape, "shape");

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
