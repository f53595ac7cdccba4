//! An example plugin: a Bingham material, elastic below a yield stress and viscous above it.
//!
//! Written only against regolith's public API, as a user's material would be: an [`Item`]
//! (its scene name and checks) implementing [`Material`], registered by [`BinghamPlugin`].
//! A scene writes
//! `material: Bingham(density: 2000.0, youngs_modulus: 1.0e6, poisson_ratio: 0.3,
//! yield_stress: 300.0, viscosity: 100.0)`.
//!
//! The update is the trans-phase model's with the mu(I) flow rule replaced by Bingham's
//! (a mud, a paste, a dense suspension): an elastic trial by the Jaumann rate; if its
//! equivalent shear stress `tau*` exceeds the yield stress `tau_y`, the plastic shear rate
//! `g` solves `tau = tau* - G dt g` together with the flow rule `tau = tau_y + eta g`:
//!
//! ```text
//! g = (tau* - tau_y) / (G dt + eta),   tau = tau* - G dt g
//! ```
//!
//! and the deviator is scaled by `tau / tau*` (radial return), the pressure left as the
//! trial's. The rate is implicit in the step, so the update is stable for any viscosity.
//! There is no density cut-off: the material stays connected (no granular gas).

use regolith::body::Phase;
use regolith::material::MaterialSpec;
use regolith::material::elastic::{LinearElastic, moduli};
use regolith::material::{Material, PointOutcome, PointStep};
use regolith::plugin::{Plugin, Regolith};
use regolith::registry::Item;
use regolith::stress::Stress;
use serde::Deserialize;

/// `Bingham(density, youngs_modulus, poisson_ratio, yield_stress, viscosity)`.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Bingham {
    /// Mass density (kg/m^3).
    pub density: f64,
    /// Young's modulus E (Pa) of the elastic part.
    pub youngs_modulus: f64,
    /// Poisson's ratio nu, in (-1, 0.5).
    pub poisson_ratio: f64,
    /// Yield stress tau_y (Pa), on the equivalent shear stress `sqrt(T0 : T0 / 2)`.
    pub yield_stress: f64,
    /// Plastic viscosity eta (Pa s): `tau = tau_y + eta g` while flowing.
    pub viscosity: f64,
}

impl Item for Bingham {
    const NAME: &'static str = "Bingham";
    fn validate(&self) -> Result<(), String> {
        let positive = |name: &str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(format!("{name} must be a positive number, got {v}"))
            }
        };
        positive("density", self.density)?;
        positive("youngs_modulus", self.youngs_modulus)?;
        if !(self.poisson_ratio > -1.0 && self.poisson_ratio < 0.5) {
            return Err(format!(
                "poisson_ratio must lie in (-1, 0.5), got {}",
                self.poisson_ratio
            ));
        }
        if !(self.yield_stress.is_finite() && self.yield_stress >= 0.0) {
            return Err(format!(
                "yield_stress must be zero or positive, got {}",
                self.yield_stress
            ));
        }
        positive("viscosity", self.viscosity)
    }
}

impl Bingham {
    /// The elastic part alone: the material below its yield stress, the trial of its update.
    pub fn elastic(&self) -> LinearElastic {
        LinearElastic {
            density: self.density,
            youngs_modulus: self.youngs_modulus,
            poisson_ratio: self.poisson_ratio,
        }
    }

    /// The plastic shear rate `g` and the returned equivalent shear stress for a trial
    /// equivalent shear stress `trial`, over a step `dt` with shear modulus `shear`.
    pub fn flow(&self, trial: f64, shear: f64, dt: f64) -> Option<(f64, f64)> {
        (trial > self.yield_stress).then(|| {
            let rate = (trial - self.yield_stress) / (shear * dt + self.viscosity);
            (rate, trial - shear * dt * rate)
        })
    }
}

impl Material for Bingham {
    type History = ();

    fn density(&self) -> f64 {
        self.density
    }

    fn wave_speed(&self) -> f64 {
        Material::wave_speed(&self.elastic())
    }

    fn lithostatic_ratio(&self) -> f64 {
        Material::lithostatic_ratio(&self.elastic())
    }

    fn update(&self, stress: &mut Stress, _history: &mut (), step: &PointStep) -> PointOutcome {
        let mut trial = *stress;
        Material::update(&self.elastic(), &mut trial, &mut (), step);
        let tau_trial = trial.equivalent_shear();
        let (shear, _) = moduli(self.youngs_modulus, self.poisson_ratio);
        let Some((rate, tau)) = self.flow(tau_trial, shear, step.dt) else {
            *stress = trial;
            return PointOutcome::default();
        };
        let p = trial.pressure();
        let dev = trial.deviator().scaled(tau / tau_trial);
        *stress = Stress {
            xx: dev.xx - p,
            yy: dev.yy - p,
            xy: dev.xy,
            zz: dev.zz - p,
        };
        PointOutcome {
            plastic_strain_rate: rate,
            phase: Phase::Flowing,
        }
    }
}

/// Adds the `Bingham` material.
pub struct BinghamPlugin;

impl Plugin for BinghamPlugin {
    fn build(&self, app: &mut Regolith) {
        app.register::<dyn MaterialSpec, Bingham>();
    }
}
