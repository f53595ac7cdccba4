//! A Bingham layer on an incline, against its analytic steady state: a plug riding on a
//! sheared layer of thickness `H_y = H - tau_y / (rho g sin th)`, with the velocity
//! `u(y) = rho g sin th (H_y y - y^2 / 2) / eta` below the plug and
//! `rho g sin th H_y^2 / (2 eta)` in it; and a layer whose yield stress exceeds the basal
//! shear stress `rho g H sin th`, which does not flow.

use bingham_material::BinghamPlugin;
use regolith::{Regolith, Scene, Simulation};

const RHO: f64 = 2000.0;
const H: f64 = 0.1;
const ETA: f64 = 100.0;

fn g_along() -> f64 {
    9.81 * 20f64.to_radians().sin()
}

fn scene(sets: &[String]) -> Scene {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/bingham_incline.ron");
    let registries = Regolith::default().add_plugin(BinghamPlugin).registries();
    Scene::load(&path, sets, &registries).unwrap().0
}

/// Mean along-slope velocity of the points in each of `bins` slices of the layer's depth,
/// averaged over the last `window` seconds of a run to `end`.
fn profile(sim: &mut Simulation, end: f64, window: f64, bins: usize) -> Vec<f64> {
    let mut sums = vec![0.0; bins];
    let mut samples = 0;
    let mut next = end - window;
    while !sim.finished() {
        sim.step().unwrap();
        if sim.clock().time >= next {
            next += 0.01;
            samples += 1;
            let p = sim.points("layer").unwrap();
            let mut bin = vec![(0.0, 0usize); bins];
            for (x, v) in p.position.iter().zip(&p.velocity) {
                let k = ((x.y / H * bins as f64) as usize).min(bins - 1);
                bin[k].0 += v.x;
                bin[k].1 += 1;
            }
            for (s, (sum, n)) in sums.iter_mut().zip(bin) {
                *s += sum / n.max(1) as f64;
            }
        }
    }
    sums.iter().map(|s| s / samples as f64).collect()
}

#[test]
fn a_plug_rides_on_a_sheared_layer_at_the_analytic_speed() {
    let tau_y = 0.5 * RHO * g_along() * H;
    let mut sim = Simulation::new(&scene(&[format!(
        "bodies.layer.material.yield_stress={tau_y}"
    )]));
    let bins = 10;
    let u = profile(&mut sim, 1.0, 0.2, bins);
    let h_y = H - tau_y / (RHO * g_along());
    let exact = |y: f64| {
        let y = y.min(h_y);
        RHO * g_along() * (h_y * y - 0.5 * y * y) / ETA
    };
    let plug = exact(h_y);
    let mut worst: f64 = 0.0;
    for (k, &uk) in u.iter().enumerate() {
        let y = (k as f64 + 0.5) * H / bins as f64;
        worst = worst.max((uk - exact(y)).abs() / plug);
        eprintln!("y = {y:.3} m: {uk:.5} m/s, exact {:.5}", exact(y));
    }
    assert!(
        worst < 0.02,
        "profile off by {:.1}% of the plug speed",
        100.0 * worst
    );
}

#[test]
fn a_layer_below_its_yield_stress_stays_put() {
    let tau_y = 1.2 * RHO * g_along() * H;
    let mut sim = Simulation::new(&scene(&[format!(
        "bodies.layer.material.yield_stress={tau_y}"
    )]));
    let u = profile(&mut sim, 1.0, 0.2, 1);
    let flowing = RHO * g_along() * (0.5 * H) * (0.5 * H) / (2.0 * ETA);
    eprintln!("mean speed {:.2e} m/s", u[0]);
    assert!(u[0].abs() < 0.01 * flowing, "mean speed {} m/s", u[0]);
}
