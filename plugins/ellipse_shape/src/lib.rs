//! An example plugin: an axis-aligned ellipse as a body shape.
//!
//! It uses only regolith's public API, exactly as a user's plugin would: implement
//! [`regolith::registry::Item`] (its scene name and checks) and [`regolith::geometry::Shape`] for
//! a parameter type and register it with `app.register::<dyn Shape, Ellipse>()`. A scene then
//! writes
//! `shape: Ellipse(centre: (0.5, 0.5), semi_axes: (0.2, 0.1))`.

use regolith::geometry::{Shape, finite, positive};
use regolith::glam::DVec2;
use regolith::registry::Item;
use regolith::{Plugin, Regolith};
use serde::Deserialize;

/// `Ellipse(centre: (x, y), semi_axes: (a, b))`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Ellipse {
    pub centre: DVec2,
    pub semi_axes: DVec2,
}

impl Item for Ellipse {
    const NAME: &'static str = "Ellipse";
    fn validate(&self) -> Result<(), String> {
        finite("centre.x", self.centre.x)?;
        finite("centre.y", self.centre.y)?;
        positive("semi_axes.0", self.semi_axes.x)?;
        positive("semi_axes.1", self.semi_axes.y)
    }
}

impl Shape for Ellipse {
    fn contains(&self, p: DVec2) -> bool {
        ((p - self.centre) / self.semi_axes).length_squared() < 1.0
    }

    fn bounds(&self) -> (DVec2, DVec2) {
        (self.centre - self.semi_axes, self.centre + self.semi_axes)
    }

    /// `pi a b`: the body's mass is then exact, whatever the lattice.
    fn area(&self) -> Option<f64> {
        Some(std::f64::consts::PI * self.semi_axes.x * self.semi_axes.y)
    }
}

/// Adds the `Ellipse` shape.
pub struct EllipsePlugin;

impl Plugin for EllipsePlugin {
    fn build(&self, app: &mut Regolith) {
        app.register::<dyn Shape, Ellipse>();
    }
}
