//! How point velocities follow the grid: the transfer schemes, as scene items
//! (`transfer: AffineFlip(relaxation: 25)`, `Flip`, `Apic`; docs/model.md §6).
//!
//! Every transfer updates a point's velocity the same way: its FLIP update `v + dt a_grid`
//! is pulled part of the way to the grid's velocity at the point ([`Transfer::pull`]). They
//! differ in how far, and in whether the point hands the grid an affine field too
//! ([`Transfer::affine`]). A plugin may register its own, as the built-ins are.

use serde::Deserialize;

use crate::registry::{DynItem, Item};

/// A grid-to-point velocity transfer.
pub trait Transfer: DynItem {
    /// Whether points carry an affine field `C_p` and hand it to the grid.
    fn affine(&self) -> bool;
    /// The fraction of the way from its FLIP update to the grid's velocity that a point's
    /// velocity moves in a step `dt`, for a body of p-wave speed `c` on cells of size `h`;
    /// `flip` is the scene's FLIP fraction.
    fn pull(&self, flip: f64, dt: f64, h: f64, c: f64) -> f64;
    /// Whether the scene's `flip` blend means anything with this transfer.
    fn blends(&self) -> bool {
        false
    }
}

item_kind!(Transfer, "transfer");

/// FLIP (the paper's transfer): each point keeps its velocity and adds the grid's
/// acceleration, optionally blended with PIC by `flip` at every step, a damping whose size is
/// set by the step: `pull = 1 - flip`.
#[derive(Clone, Copy, Debug, Deserialize)]
pub struct Flip;

impl Item for Flip {
    const NAME: &'static str = "Flip";
    const UNIT: bool = true;
}

impl Transfer for Flip {
    fn affine(&self) -> bool {
        false
    }
    fn pull(&self, flip: f64, _dt: f64, _h: f64, _c: f64) -> f64 {
        1.0 - flip
    }
    fn blends(&self) -> bool {
        true
    }
}

/// APIC (Jiang et al. 2015): each point takes the grid velocity at its position and the
/// affine field `C_p` around it, which it hands back to the grid in the next scatter.
/// Conserves linear and angular momentum and reproduces affine fields; but the projection is
/// made at every step, so what it dissipates grows as the step shrinks (the impact's depth
/// falls from 0.31 to 0.18 m between CFL 1 and 0.05).
#[derive(Clone, Copy, Debug, Deserialize)]
pub struct Apic;

impl Item for Apic {
    const NAME: &'static str = "Apic";
    const UNIT: bool = true;
}

impl Transfer for Apic {
    fn affine(&self) -> bool {
        true
    }
    fn pull(&self, _flip: f64, _dt: f64, _h: f64, _c: f64) -> f64 {
        1.0
    }
}

/// The default (`relaxation: 25`): APIC's affine scatter with FLIP's velocity update, whose
/// departure from the grid's velocity relaxes over `relaxation` p-wave crossings of a cell,
/// `tau = relaxation h / c` (the unit of the CFL number, so a step removes the fraction
/// `1 - exp(-CFL / relaxation)`). The damping is fixed in time, so the answer converges in the
/// step, and `tau` shrinks with the cell.
#[derive(Clone, Copy, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AffineFlip {
    pub relaxation: f64,
}

/// The default transfer's relaxation, in p-wave crossings of a cell (docs/numerics.md,
/// "Affine FLIP": how it was chosen).
pub const DEFAULT_RELAXATION: f64 = 25.0;

impl Default for AffineFlip {
    fn default() -> Self {
        AffineFlip {
            relaxation: DEFAULT_RELAXATION,
        }
    }
}

impl Item for AffineFlip {
    const NAME: &'static str = "AffineFlip";
    fn validate(&self) -> Result<(), String> {
        if self.relaxation.is_finite() && self.relaxation > 0.0 {
            Ok(())
        } else {
            Err(format!(
                "relaxation must be a positive number of p-wave crossings of a cell, got {}",
                self.relaxation
            ))
        }
    }
}

impl Transfer for AffineFlip {
    fn affine(&self) -> bool {
        true
    }
    fn pull(&self, _flip: f64, dt: f64, h: f64, c: f64) -> f64 {
        -(-dt * c / (self.relaxation * h)).exp_m1()
    }
}
