//! The trans-phase constitutive update alone, driven by prescribed L, dt and density
//! (docs/model.md §4.1). Parameters are the paper's PS-1 discs.

use proptest::prelude::*;
use regolith::body::Phase;
use regolith::glam::{DMat2, DVec2};
use regolith::material::PointStep;
use regolith::material::elastic::moduli;
use regolith::material::granular::{TransPhase, mu_of_i};
use regolith::stress::Stress;

fn ps1(rate_independent: bool) -> TransPhase {
    let (shear, bulk) = moduli(20e6, 0.45);
    TransPhase {
        shear,
        bulk,
        critical_density: 1011.2,
        grain_density: 1280.0,
        grain_diameter: 5e-3,
        mu_s: 0.32,
        mu_2: if rate_independent { 0.32 } else { 0.598 },
        i_0: 0.278,
    }
}

fn l_from(e: [f64; 4]) -> DMat2 {
    DMat2::from_cols(DVec2::new(e[0], e[1]), DVec2::new(e[2], e[3]))
}

/// A stress of pressure `p` with a random deviator of stress ratio `ratio`.
fn stress_from(p: f64, ratio: f64, dir: [f64; 3]) -> Stress {
    // traceless (xx, yy, zz) from two directions, plus xy
    let (a, b, c) = (dir[0], dir[1], -dir[0] - dir[1]);
    let dev = Stress {
        xx: a,
        yy: b,
        xy: dir[2],
        zz: c,
    };
    let tau = dev.equivalent_shear();
    let k = if tau > 0.0 {
        ratio * p.abs() / tau
    } else {
        0.0
    };
    dev.scaled(k) + Stress::isotropic(p)
}

fn step(l: DMat2, dt: f64, density: f64) -> PointStep<'static> {
    PointStep::new(l, dt, density)
}

fn log_uniform(lo: f64, hi: f64) -> impl Strategy<Value = f64> {
    (lo.log10()..hi.log10()).prop_map(|e| 10f64.powf(e))
}

fn signed_rate() -> impl Strategy<Value = f64> {
    (log_uniform(1e-3, 1e6), any::<bool>()).prop_map(|(m, neg)| if neg { -m } else { m })
}

proptest! {
    #![proptest_config(crate::property::config(4000, file!()))]

    /// The return lands between mu_s p* and min(mu_2 p*, tau*), tau/p* equals mu(I(gdp)) to
    /// round-off, gdp >= 0, the pressure is unchanged by the correction, and each phase is
    /// what its condition says; never a NaN or infinity.
    #[test]
    fn plastic_return_properties(
        p0 in log_uniform(1e-6, 1e7),
        ratio in 0.0f64..1.5,
        dir in prop::array::uniform3(-1.0f64..1.0),
        l in prop::array::uniform4(signed_rate()),
        dt in log_uniform(1e-9, 1e-3),
        dens in -0.02f64..0.02,
        rate_independent in any::<bool>(),
    ) {
        let m = ps1(rate_independent);
        let t0 = stress_from(p0, ratio, dir);
        let lm = l_from(l);
        let density = m.critical_density * (1.0 + dens);
        let trial = t0.jaumann_elastic_trial(lm, dt, m.shear, m.bulk);
        let (p_trial, tau_trial) = (trial.pressure(), trial.equivalent_shear());
        let mut t = t0;
        let out = m.update(&mut t, &step(lm, dt, density));
        prop_assert!(t.is_finite());
        prop_assert!(out.plastic_strain_rate.is_finite() && out.plastic_strain_rate >= 0.0);
        match out.phase {
            Phase::Disconnected => {
                prop_assert!(density < m.critical_density || p_trial <= 0.0);
                prop_assert_eq!(t, Stress::ZERO);
            }
            Phase::Solid => {
                prop_assert!(tau_trial <= m.mu_s * p_trial);
                prop_assert_eq!(t, trial);
                prop_assert_eq!(out.plastic_strain_rate, 0.0);
            }
            Phase::Flowing => {
                let tau = t.equivalent_shear();
                let slack = 1e-12 * tau_trial;
                prop_assert!(tau >= m.mu_s * p_trial - slack, "tau {tau} below mu_s p {}", m.mu_s * p_trial);
                prop_assert!(tau <= (m.mu_2 * p_trial).min(tau_trial) + slack);
                prop_assert!((t.pressure() - p_trial).abs() <= 1e-12 * p_trial);
                let i = m.inertial_number(out.plastic_strain_rate, p_trial);
                let mu = mu_of_i(m.mu_s, m.mu_2, m.i_0, i);
                prop_assert!((tau / p_trial - mu).abs() <= 1e-9, "tau/p {} vs mu(I) {mu}", tau / p_trial);
                if rate_independent {
                    prop_assert!((tau - m.mu_s * p_trial).abs() <= 1e-12 * tau_trial);
                }
            }
        }
    }

    /// A pure rigid rotation keeps the pressure exactly and the shear stress to second order
    /// in the rotation angle (the Jaumann update is a first-order rotation):
    /// `|tau'/tau - 1| <= 2 (w dt)^2`.
    #[test]
    fn rigid_rotation_keeps_the_invariants(
        p0 in log_uniform(1.0, 1e6),
        ratio in 0.0f64..0.3,
        dir in prop::array::uniform3(-1.0f64..1.0),
        omega in -1e3f64..1e3,
        dt in log_uniform(1e-9, 1e-4),
    ) {
        let m = ps1(false);
        let mut t = stress_from(p0, ratio, dir);
        let (p, tau) = (t.pressure(), t.equivalent_shear());
        let l = DMat2::from_cols(DVec2::new(0.0, omega), DVec2::new(-omega, 0.0));
        let out = m.update(&mut t, &step(l, dt, m.critical_density * 1.001));
        prop_assert_eq!(out.phase, Phase::Solid);
        prop_assert!((t.pressure() - p).abs() <= 1e-12 * p);
        let angle = omega * dt;
        prop_assert!((t.equivalent_shear() - tau).abs() <= 2.0 * angle * angle * tau + 1e-12 * p);
    }
}

/// The extremes the issue lists; every result must be finite with the phase it should have.
#[test]
fn limits_never_give_nan() {
    for rate_independent in [false, true] {
        let m = ps1(rate_independent);
        let rc = m.critical_density;
        for p0 in [1e-300, 1e-12, 1e-3, -1e3, 0.0] {
            for rate in [1e-6, 1.0, 1e6, -1e6] {
                for dt in [1e-9, 1e-6, 1e-3] {
                    for density in [
                        rc * (1.0 - 1e-12),
                        rc,
                        rc * (1.0 + 1e-12),
                        0.5 * rc,
                        2.0 * rc,
                    ] {
                        for shape in [
                            [rate, 0.0, 0.0, -rate],
                            [0.0, rate, 0.0, 0.0],
                            [rate, 0.0, 0.0, rate],
                        ] {
                            let mut t = stress_from(p0, 0.9, [0.3, -0.1, 0.5]);
                            let out = m.update(&mut t, &step(l_from(shape), dt, density));
                            assert!(
                                t.is_finite() && out.plastic_strain_rate.is_finite(),
                                "p0 {p0} rate {rate} dt {dt} rho {density}: {t:?} {out:?}"
                            );
                            assert!(out.plastic_strain_rate >= 0.0);
                            if density < rc {
                                assert_eq!(out.phase, Phase::Disconnected);
                            }
                        }
                    }
                }
            }
        }
        // Pure tension: stress free.
        let mut t = Stress::isotropic(-1e4);
        let out = m.update(&mut t, &step(DMat2::ZERO, 1e-6, rc * 1.01));
        assert_eq!((t, out.phase), (Stress::ZERO, Phase::Disconnected));
    }
}

/// Steady simple shear at rate `g` (no volume change, so p stays p0) ends with
/// `gdp = g` and `tau/p = mu(I(g))`. The steady plastic rate differs from `g` only by the
/// elastic part the Jaumann spin keeps up, of relative order `tau / G`, hence 0.2%.
#[test]
fn simple_shear_reaches_the_steady_mu_of_i() {
    let m = ps1(false);
    let p0 = 1000.0;
    for rate in [0.1, 10.0, 1000.0] {
        // enough steps for a shear strain of 0.2, far past the yield strain mu p / G ~ 5e-5
        let steps = 20_000;
        let dt = 0.2 / rate / steps as f64;
        let l = DMat2::from_cols(DVec2::ZERO, DVec2::new(rate, 0.0));
        let mut t = Stress::isotropic(p0);
        let mut out = Default::default();
        for _ in 0..steps {
            out = m.update(&mut t, &step(l, dt, m.critical_density * 1.01));
        }
        assert_eq!(out.phase, Phase::Flowing);
        let p = t.pressure();
        assert!((p - p0).abs() < 1e-9 * p0, "pressure drifted to {p}");
        let expected = mu_of_i(m.mu_s, m.mu_2, m.i_0, m.inertial_number(rate, p0));
        let ratio = t.equivalent_shear() / p;
        assert!(
            (ratio / expected - 1.0).abs() < 2e-3,
            "rate {rate}: tau/p {ratio} vs mu(I) {expected}"
        );
        assert!(
            (out.plastic_strain_rate / rate - 1.0).abs() < 2e-3,
            "rate {rate}: gdp {}",
            out.plastic_strain_rate
        );
    }
}

/// Quiet start: density and pressure agree with `p = K ln(rho / rho_c)`.
#[test]
fn quiet_start_volume_matches_the_pressure() {
    let m = ps1(false);
    for p in [0.0, 10.0, 1e4, 1e6] {
        let mass = 0.3;
        let v = m.initial_volume(mass, &Stress::isotropic(p));
        let rho = mass / v;
        assert!((m.bulk * (rho / m.critical_density).ln() - p).abs() < 1e-14 * m.bulk + 1e-12 * p);
    }
}
