//! Point-wise properties of the Bingham update on random states: what the return must
//! satisfy at every point, whatever the stress, the velocity gradient and the step.

#[path = "../../../tests/common/property.rs"]
mod property;

use bingham_material::Bingham;
use proptest::prelude::*;
use regolith::body::Phase;
use regolith::glam::DMat2;
use regolith::material::elastic::moduli;
use regolith::material::{Material, PointStep};
use regolith::stress::Stress;

fn material(yield_stress: f64, viscosity: f64) -> Bingham {
    Bingham {
        density: 2000.0,
        youngs_modulus: 1.0e6,
        poisson_ratio: 0.3,
        yield_stress,
        viscosity,
    }
}

fn stress() -> impl Strategy<Value = Stress> {
    (-2e3..2e3f64, -2e3..2e3f64, -1e3..1e3f64, -2e3..2e3f64).prop_map(|(xx, yy, xy, zz)| Stress {
        xx,
        yy,
        xy,
        zz,
    })
}

fn gradient() -> impl Strategy<Value = DMat2> {
    (
        -50.0..50.0f64,
        -50.0..50.0f64,
        -50.0..50.0f64,
        -50.0..50.0f64,
    )
        .prop_map(|(a, b, c, d)| DMat2::from_cols_array(&[a, b, c, d]))
}

proptest! {
    #![proptest_config(property::config(256, file!()))]

    #[test]
    fn the_return_obeys_the_flow_rule(
        start in stress(),
        l in gradient(),
        dt in 1e-6..1e-3f64,
        yield_stress in 0.0..1500.0f64,
        viscosity in 1e-3..1e3f64,
    ) {
        let m = material(yield_stress, viscosity);
        let (shear, bulk) = moduli(m.youngs_modulus, m.poisson_ratio);
        let trial = start.jaumann_elastic_trial(l, dt, shear, bulk);
        let tau_trial = trial.equivalent_shear();
        let mut s = start;
        let step = PointStep::new(l, dt, m.density);
        let out = m.update(&mut s, &mut (), &step);
        let tau = s.equivalent_shear();
        let scale = 1.0 + tau_trial + yield_stress;
        // The pressure is the elastic trial's: the flow is isochoric.
        prop_assert!((s.pressure() - trial.pressure()).abs() <= 1e-12 * (1.0 + trial.pressure().abs()));
        if tau_trial <= yield_stress {
            // Below the yield stress the update is the elastic trial, bit for bit.
            prop_assert_eq!(s, trial);
            prop_assert_eq!(out.plastic_strain_rate, 0.0);
            prop_assert_eq!(out.phase, Phase::Solid);
        } else {
            let g = out.plastic_strain_rate;
            prop_assert!(g > 0.0);
            prop_assert_eq!(out.phase, Phase::Flowing);
            // On the flow rule, and between the yield stress and the trial.
            prop_assert!((tau - (yield_stress + viscosity * g)).abs() <= 1e-9 * scale);
            prop_assert!(tau >= yield_stress - 1e-9 * scale && tau <= tau_trial + 1e-9 * scale);
            // The elastic relaxation took exactly what the flow took.
            prop_assert!((tau_trial - tau - shear * dt * g).abs() <= 1e-9 * scale);
            // Radial return: the deviator keeps its direction.
            let (d, dt_) = (s.deviator(), trial.deviator());
            let k = tau / tau_trial;
            for (a, b) in [(d.xx, dt_.xx), (d.yy, dt_.yy), (d.xy, dt_.xy), (d.zz, dt_.zz)] {
                prop_assert!((a - k * b).abs() <= 1e-9 * scale);
            }
        }
    }

    #[test]
    fn a_vanishing_viscosity_is_perfect_plasticity(
        start in stress(),
        l in gradient(),
        yield_stress in 1.0..1500.0f64,
    ) {
        // eta << G dt: the stress returns onto the yield surface itself, to within the
        // viscous overstress eta g <= eta tau* / (G dt) and round-off.
        let (eta, dt) = (1e-9, 1e-3);
        let m = material(yield_stress, eta);
        let (shear, bulk) = moduli(m.youngs_modulus, m.poisson_ratio);
        let tau_trial = start.jaumann_elastic_trial(l, dt, shear, bulk).equivalent_shear();
        let mut s = start;
        let step = PointStep::new(l, dt, m.density);
        m.update(&mut s, &mut (), &step);
        let bound = yield_stress
            + eta * tau_trial / (shear * dt)
            + 1e-12 * tau_trial;
        prop_assert!(s.equivalent_shear() <= bound);
        if tau_trial > yield_stress {
            prop_assert!(s.equivalent_shear() >= yield_stress - 1e-12 * tau_trial);
        }
    }
}

#[test]
fn bad_parameters_are_refused_by_name() {
    use regolith::registry::Item;
    let m = Bingham {
        viscosity: 0.0,
        ..material(10.0, 1.0)
    };
    assert!(m.validate().unwrap_err().contains("viscosity"));
    let m = Bingham {
        yield_stress: -1.0,
        ..material(10.0, 1.0)
    };
    assert!(m.validate().unwrap_err().contains("yield_stress"));
}
