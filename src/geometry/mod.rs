//! Body shapes as plugins: anything that can say whether a point is inside it.
//!
//! Bodies are filled with material points on a lattice aligned with the grid; a shape only
//! answers "is this position inside" and gives its bounding box. A shape used as a fixed
//! obstacle (module `obstacle`) also gives the outward normal of its boundary, which every
//! shape has by default from `contains` alone and the built-in ones give exactly. Built-in
//! shapes (rectangle, disc, polygon, the tipped intruder) register exactly as a user's would.

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
    /// The outward unit normal of the boundary nearest to `p`, at a place `reach` (m, about
    /// a grid cell) or less from it: what a fixed obstacle's surface pushes along. The
    /// default needs only [`contains`](Shape::contains): it samples rings around `p` out to
    /// `reach` (then twice, four and eight times as far while it finds no outside, or no
    /// inside) and returns the mean direction to the outside samples, which on a straight
    /// stretch of boundary is its normal and at a corner the corner's bisector. Zero where
    /// it cannot tell (no boundary within `8 reach`).
    fn outward_normal(&self, p: DVec2, reach: f64) -> DVec2 {
        sampled_normal(|q| self.contains(q), p, reach)
    }
}

/// The default [`Shape::outward_normal`]: the mean direction from `p` to the samples outside
/// the shape, on 8 rings of 32 directions each out to `reach`, widened up to 8 times.
pub fn sampled_normal(contains: impl Fn(DVec2) -> bool, p: DVec2, reach: f64) -> DVec2 {
    const RINGS: usize = 8;
    const DIRECTIONS: usize = 32;
    let mut r = reach;
    for _ in 0..4 {
        let (mut out, mut outside, mut inside) = (DVec2::ZERO, 0, 0);
        for ring in 1..=RINGS {
            for k in 0..DIRECTIONS {
                // Rings turned against each other by half a direction, so that no
                // direction is sampled by every ring.
                let angle = std::f64::consts::TAU * (k as f64 + 0.5 * (ring % 2) as f64)
                    / DIRECTIONS as f64;
                let dir = DVec2::from_angle(angle);
                if contains(p + r * ring as f64 / RINGS as f64 * dir) {
                    inside += 1;
                } else {
                    out += dir;
                    outside += 1;
                }
            }
        }
        if outside > 0 && inside > 0 {
            return out.normalize_or_zero();
        }
        r *= 2.0;
    }
    DVec2::ZERO
}

item_kind!(Shape, "shape");

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
