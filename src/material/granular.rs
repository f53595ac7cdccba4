//! The trans-phase granular material of the paper (docs/model.md §4.1): a hypoelastic solid below
//! the yield surface, mu(I) plastic flow on it, and a stress-free disconnected phase below
//! the critical density or in tension.
//!
//! Two scene names share one update: `MuI` (the paper's rate-dependent model) and
//! `DruckerPrager` (appendix A: the same code with `mu_2 = mu_s`, rate independent).
//!
//! The plastic return solves `tau = tau* - G dt gdp` together with `tau = p mu(I)`,
//! `I = gdp d sqrt(rho_s / p)` exactly: it is the smaller root of
//! `tau^2 - B tau + H = 0` with `B = S2 + tau* + alpha`, `H = S2 tau* + S0 alpha`,
//! `S0 = mu_s p`, `S2 = mu_2 p`, `alpha = G dt I_0 sqrt(p / rho_s) / d`, written as
//! `2H / (B + sqrt(B^2 - 4H))` to avoid cancellation. That root lies in
//! `[S0, min(S2, tau*)]`: the quadratic is `>= 0` at `S0` and `<= 0` at `min(S2, tau*)`.

use serde::Deserialize;

use super::elastic::moduli;
use super::{Material, PointOutcome, PointStep};
use crate::body::Phase;
use crate::registry::Item;
use crate::stress::Stress;

/// Resolved parameters of the trans-phase model.
#[derive(Clone, Debug, PartialEq)]
pub struct TransPhase {
    /// Shear modulus G (Pa).
    pub shear: f64,
    /// Bulk modulus K (Pa).
    pub bulk: f64,
    /// Critical (dense) density rho_c (kg/m^3).
    pub critical_density: f64,
    /// Grain density rho_s (kg/m^3).
    pub grain_density: f64,
    /// Grain diameter d (m).
    pub grain_diameter: f64,
    pub mu_s: f64,
    pub mu_2: f64,
    pub i_0: f64,
}

/// `mu(I) = mu_s + (mu_2 - mu_s) / (I_0 / I + 1)`.
pub fn mu_of_i(mu_s: f64, mu_2: f64, i_0: f64, i: f64) -> f64 {
    mu_s + (mu_2 - mu_s) * i / (i_0 + i)
}

impl TransPhase {
    /// Inertial number of plastic rate `gdp` at pressure `p > 0`.
    pub fn inertial_number(&self, gdp: f64, p: f64) -> f64 {
        gdp * self.grain_diameter * (self.grain_density / p).sqrt()
    }

    /// The elastic trial stress of one step (`Ok`), or, below the critical density or in
    /// tension, the disconnected phase: stress set to zero, the whole trial shear taken as
    /// plastic (`Err`, the point's outcome). Every trans-phase flow rule starts here.
    pub fn dense_trial(
        &self,
        stress: &mut Stress,
        step: &PointStep,
    ) -> Result<Stress, PointOutcome> {
        let (g, dt) = (self.shear, step.dt);
        let trial = stress.jaumann_elastic_trial(step.velocity_gradient, dt, g, self.bulk);
        if step.density < self.critical_density || trial.pressure() <= 0.0 {
            *stress = Stress::ZERO;
            return Err(PointOutcome {
                plastic_strain_rate: trial.equivalent_shear() / (g * dt),
                phase: Phase::Disconnected,
            });
        }
        Ok(trial)
    }

    /// One step of the update at one point (docs/model.md §4.1, steps 1-5).
    pub fn update(&self, stress: &mut Stress, step: &PointStep) -> PointOutcome {
        let (g, dt) = (self.shear, step.dt);
        let trial = match self.dense_trial(stress, step) {
            Ok(trial) => trial,
            Err(disconnected) => return disconnected,
        };
        let p = trial.pressure();
        let dev = trial.deviator();
        let tau_trial = trial.equivalent_shear();
        if tau_trial <= self.mu_s * p {
            *stress = trial;
            return PointOutcome {
                plastic_strain_rate: 0.0,
                phase: Phase::Solid,
            };
        }
        let s0 = self.mu_s * p;
        let s2 = self.mu_2 * p;
        let alpha = g * dt * self.i_0 * (p / self.grain_density).sqrt() / self.grain_diameter;
        let b = s2 + tau_trial + alpha;
        let h = s2 * tau_trial + s0 * alpha;
        let tau = 2.0 * h / (b + (b * b - 4.0 * h).max(0.0).sqrt());
        *stress = dev.scaled(tau / tau_trial) + Stress::isotropic(p);
        PointOutcome {
            plastic_strain_rate: ((tau_trial - tau) / (g * dt)).max(0.0),
            phase: Phase::Flowing,
        }
    }

    /// Quiet start: the volume at which density and pressure agree with the hypoelastic law,
    /// `rho = rho_c exp(p / K)` (docs/model.md §1).
    pub fn initial_volume(&self, mass: f64, stress: &Stress) -> f64 {
        mass / self.critical_density * (-stress.pressure() / self.bulk).exp()
    }

    pub fn wave_speed(&self) -> f64 {
        ((self.bulk + 4.0 * self.shear / 3.0) / self.critical_density).sqrt()
    }
}

/// Elastic constants given as `youngs_modulus` and `poisson_ratio`, or as `bulk_modulus` and
/// `shear_modulus`; returns `(G, K)`.
fn resolve_moduli(
    e: Option<f64>,
    nu: Option<f64>,
    k: Option<f64>,
    g: Option<f64>,
) -> Result<(f64, f64), String> {
    let positive = |name: &str, v: f64| {
        if v.is_finite() && v > 0.0 {
            Ok(v)
        } else {
            Err(format!("{name} must be a positive number (Pa), got {v}"))
        }
    };
    match (e, nu, k, g) {
        (Some(e), Some(nu), None, None) => {
            positive("youngs_modulus", e)?;
            if !(nu.is_finite() && nu > -1.0 && nu < 0.5) {
                return Err(format!("poisson_ratio must lie strictly between -1 and 0.5, got {nu}"));
            }
            Ok(moduli(e, nu))
        }
        (None, None, Some(k), Some(g)) => Ok((positive("shear_modulus", g)?, positive("bulk_modulus", k)?)),
        _ => Err("give the elasticity as youngs_modulus and poisson_ratio, or as bulk_modulus and shear_modulus (one pair)".into()),
    }
}

/// `critical_density`, or `packing_fraction` times `grain_density`.
fn resolve_critical_density(
    critical: Option<f64>,
    packing: Option<f64>,
    grain_density: Option<f64>,
) -> Result<f64, String> {
    match (critical, packing, grain_density) {
        (Some(rc), None, _) if rc.is_finite() && rc > 0.0 => Ok(rc),
        (Some(rc), None, _) => Err(format!(
            "critical_density must be a positive number (kg/m^3), got {rc}"
        )),
        (None, Some(phi), Some(rs)) if phi > 0.0 && phi <= 1.0 => Ok(phi * rs),
        (None, Some(phi), Some(_)) => {
            Err(format!("packing_fraction must lie in (0, 1], got {phi}"))
        }
        (None, Some(_), None) => Err("packing_fraction needs grain_density".into()),
        _ => {
            Err("give critical_density, or packing_fraction (with grain_density), not both".into())
        }
    }
}

/// `(G, K, rho_c)` from the elasticity and density parameters both scene names share.
fn resolve_elastic_and_density(
    moduli: [Option<f64>; 4],
    critical: Option<f64>,
    packing: Option<f64>,
    grain_density: Option<f64>,
) -> Result<(f64, f64, f64), String> {
    let [e, nu, k, g] = moduli;
    let (shear, bulk) = resolve_moduli(e, nu, k, g)?;
    if let Some(rs) = grain_density {
        check_positive("grain_density", rs, "kg/m^3")?;
    }
    let critical_density = resolve_critical_density(critical, packing, grain_density)?;
    Ok((shear, bulk, critical_density))
}

pub(super) fn check_positive(name: &str, v: f64, unit: &str) -> Result<(), String> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(format!(
            "{name} must be a positive number ({unit}), got {v}"
        ))
    }
}

fn check_friction(mu_s: f64) -> Result<(), String> {
    if mu_s.is_finite() && mu_s >= 0.0 {
        Ok(())
    } else {
        Err(format!("mu_s must be a non-negative number, got {mu_s}"))
    }
}

/// `MuI(...)`: the paper's trans-phase model with the mu(I) rheology.
#[derive(Clone, Debug, Deserialize)]
#[serde(try_from = "MuIParams")]
pub struct MuI(pub TransPhase);

/// Declares a scene parameter struct `$name` with the fields of `MuI` (elasticity, densities,
/// grain size, mu(I)) and the extra ones given, and its `trans_phase()`, which checks and
/// resolves the shared ones; a material built on the trans-phase model (`nonlocal`) reads its
/// parameters through it, so that `MuI`'s names and checks are written once.
macro_rules! trans_phase_params {
    ($name:ident { $($(#[$meta:meta])* $field:ident: $ty:ty),* $(,)? }) => {
        #[derive(serde::Deserialize)]
        #[serde(deny_unknown_fields)]
        struct $name {
            youngs_modulus: Option<f64>,
            poisson_ratio: Option<f64>,
            bulk_modulus: Option<f64>,
            shear_modulus: Option<f64>,
            grain_density: f64,
            critical_density: Option<f64>,
            packing_fraction: Option<f64>,
            grain_diameter: f64,
            mu_s: f64,
            mu_2: f64,
            i_0: f64,
            $($(#[$meta])* $field: $ty),*
        }

        impl $name {
            /// The shared parameters, checked (`mu_2 >= mu_s`).
            fn trans_phase(&self) -> Result<$crate::material::granular::TransPhase, String> {
                $crate::material::granular::resolve_trans_phase(
                    [self.youngs_modulus, self.poisson_ratio, self.bulk_modulus, self.shear_modulus],
                    self.critical_density,
                    self.packing_fraction,
                    [self.grain_density, self.grain_diameter, self.mu_s, self.mu_2, self.i_0],
                )
            }
        }
    };
}
pub(super) use trans_phase_params;

/// The trans-phase parameters from the elasticity (`[E, nu, K, G]`, one pair), the critical
/// density or packing fraction, and `[rho_s, d, mu_s, mu_2, I_0]`, checked.
pub(super) fn resolve_trans_phase(
    moduli: [Option<f64>; 4],
    critical: Option<f64>,
    packing: Option<f64>,
    [grain_density, grain_diameter, mu_s, mu_2, i_0]: [f64; 5],
) -> Result<TransPhase, String> {
    let (shear, bulk, critical_density) =
        resolve_elastic_and_density(moduli, critical, packing, Some(grain_density))?;
    check_positive("grain_diameter", grain_diameter, "m")?;
    check_friction(mu_s)?;
    if !(mu_2.is_finite() && mu_2 >= mu_s) {
        return Err(format!(
            "mu_2 must be a number no smaller than mu_s = {mu_s}, got {mu_2}"
        ));
    }
    check_positive("i_0", i_0, "dimensionless")?;
    Ok(TransPhase {
        shear,
        bulk,
        critical_density,
        grain_density,
        grain_diameter,
        mu_s,
        mu_2,
        i_0,
    })
}

trans_phase_params!(MuIParams {});

impl TryFrom<MuIParams> for MuI {
    type Error = String;
    fn try_from(p: MuIParams) -> Result<Self, String> {
        p.trans_phase().map(MuI)
    }
}

/// `DruckerPrager(...)`: the rate-independent variant (appendix A), `mu_2 = mu_s`.
#[derive(Clone, Debug, Deserialize)]
#[serde(try_from = "DruckerPragerParams")]
pub struct DruckerPrager(pub TransPhase);

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct DruckerPragerParams {
    youngs_modulus: Option<f64>,
    poisson_ratio: Option<f64>,
    bulk_modulus: Option<f64>,
    shear_modulus: Option<f64>,
    grain_density: Option<f64>,
    critical_density: Option<f64>,
    packing_fraction: Option<f64>,
    mu_s: f64,
}

impl TryFrom<DruckerPragerParams> for DruckerPrager {
    type Error = String;
    fn try_from(p: DruckerPragerParams) -> Result<Self, String> {
        let (shear, bulk, critical_density) = resolve_elastic_and_density(
            [
                p.youngs_modulus,
                p.poisson_ratio,
                p.bulk_modulus,
                p.shear_modulus,
            ],
            p.critical_density,
            p.packing_fraction,
            p.grain_density,
        )?;
        check_friction(p.mu_s)?;
        // With mu_2 = mu_s the return is tau = mu_s p whatever the rate, so the grain
        // scale only has to be finite and positive.
        Ok(DruckerPrager(TransPhase {
            shear,
            bulk,
            critical_density,
            grain_density: p.grain_density.unwrap_or(critical_density),
            grain_diameter: 1.0,
            mu_s: p.mu_s,
            mu_2: p.mu_s,
            i_0: 1.0,
        }))
    }
}

/// The Material methods both names share.
macro_rules! trans_phase_material {
    ($ty:ident, $name:literal, $inertial:expr) => {
        // The parameters were checked when they were resolved (deserialisation).
        impl Item for $ty {
            const NAME: &'static str = $name;
        }

        impl Material for $ty {
            type History = ();

            fn density(&self) -> f64 {
                self.0.critical_density
            }
            fn wave_speed(&self) -> f64 {
                self.0.wave_speed()
            }
            /// Isotropic lithostatic start, as the authors used (docs/model.md §1).
            fn lithostatic_ratio(&self) -> f64 {
                1.0
            }
            fn initial_volume(&self, mass: f64, stress: &Stress) -> f64 {
                self.0.initial_volume(mass, stress)
            }
            fn inertial_scale(&self) -> Option<f64> {
                let f: fn(&TransPhase) -> Option<f64> = $inertial;
                f(&self.0)
            }
            fn granular(&self) -> bool {
                true
            }
            fn update(&self, stress: &mut Stress, _h: &mut (), step: &PointStep) -> PointOutcome {
                self.0.update(stress, step)
            }
        }
    };
}

trans_phase_material!(MuI, "MuI", |m| Some(
    m.grain_diameter * m.grain_density.sqrt()
));
trans_phase_material!(DruckerPrager, "DruckerPrager", |_| None);
