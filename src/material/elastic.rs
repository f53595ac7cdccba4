//! Linear hypoelastic solid: the Jaumann-rate law with constant moduli, no yield and no
//! density cut-off (the paper's intruder; docs/model.md §4.3).

use serde::Deserialize;

use super::{Material, PointOutcome, PointStep};
use crate::registry::Item;
use crate::stress::Stress;

/// `LinearElastic(density: .., youngs_modulus: .., poisson_ratio: ..)` in a scene.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LinearElastic {
    /// Mass density (kg/m^3; for a thin plate in 2D, its areal density over the bed thickness).
    pub density: f64,
    /// Young's modulus E (Pa).
    pub youngs_modulus: f64,
    /// Poisson's ratio nu, in (-1, 0.5).
    pub poisson_ratio: f64,
}

/// Shear and bulk moduli from E and nu.
pub fn moduli(youngs: f64, poisson: f64) -> (f64, f64) {
    let shear = youngs / (2.0 * (1.0 + poisson));
    let bulk = youngs / (3.0 * (1.0 - 2.0 * poisson));
    (shear, bulk)
}

/// Plane-strain p-wave modulus `M = K + 4G/3 = E (1 - nu) / ((1 + nu)(1 - 2 nu))`.
pub fn p_wave_modulus(youngs: f64, poisson: f64) -> f64 {
    youngs * (1.0 - poisson) / ((1.0 + poisson) * (1.0 - 2.0 * poisson))
}

/// Checks E, nu and a density; shared by every material with these parameters.
pub fn validate_elastic(density: f64, youngs: f64, poisson: f64) -> Result<(), String> {
    if !(density.is_finite() && density > 0.0) {
        return Err(format!(
            "density must be a positive number (kg/m^3), got {density}"
        ));
    }
    if !(youngs.is_finite() && youngs > 0.0) {
        return Err(format!(
            "youngs_modulus must be a positive number (Pa), got {youngs}"
        ));
    }
    if !(poisson.is_finite() && poisson > -1.0 && poisson < 0.5) {
        return Err(format!(
            "poisson_ratio must lie strictly between -1 and 0.5, got {poisson}"
        ));
    }
    Ok(())
}

impl Item for LinearElastic {
    const NAME: &'static str = "LinearElastic";
    fn validate(&self) -> Result<(), String> {
        validate_elastic(self.density, self.youngs_modulus, self.poisson_ratio)
    }
}

impl Material for LinearElastic {
    type History = ();

    fn density(&self) -> f64 {
        self.density
    }

    fn wave_speed(&self) -> f64 {
        (p_wave_modulus(self.youngs_modulus, self.poisson_ratio) / self.density).sqrt()
    }

    fn lithostatic_ratio(&self) -> f64 {
        self.poisson_ratio / (1.0 - self.poisson_ratio)
    }

    fn update(&self, stress: &mut Stress, _history: &mut (), step: &PointStep) -> PointOutcome {
        let (shear, bulk) = moduli(self.youngs_modulus, self.poisson_ratio);
        *stress = stress.jaumann_elastic_trial(step.velocity_gradient, step.dt, shear, bulk);
        PointOutcome::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn moduli_match_the_paper_ps1_values() {
        // docs/model.md §7: PS-1 (E = 20 MPa, nu = 0.45) has G = 6.897 MPa, K = 66.67 MPa.
        let (g, k) = moduli(20e6, 0.45);
        assert!((g - 6.897e6).abs() < 1e3);
        assert!((k - 66.67e6).abs() < 1e4);
        assert!((p_wave_modulus(20e6, 0.45) - (k + 4.0 * g / 3.0)).abs() < 1e-6 * k);
    }

    #[test]
    fn rejects_incompressible_and_negative_values() {
        assert!(validate_elastic(1000.0, 1e6, 0.5).is_err());
        assert!(validate_elastic(1000.0, -1e6, 0.3).is_err());
        assert!(validate_elastic(0.0, 1e6, 0.3).is_err());
        assert!(validate_elastic(f64::NAN, 1e6, 0.3).is_err());
        assert!(validate_elastic(1000.0, 1e6, 0.3).is_ok());
    }
}
