//! The paper's force-propagation experiment (section 4.3.1), coarse: the pressure front under
//! the impact point crosses the bed at the p-wave speed `sqrt(M / rho_c)`.

use regolith::Simulation;
use regolith::output::front::PressureRecord;

#[test]
fn the_pressure_front_travels_at_the_p_wave_speed() {
    let scene = crate::common::scene("force_propagation_coarse", &[]);
    let mut sim = Simulation::new(&scene);
    sim.run(|_| {}).unwrap();
    let front = sim
        .world
        .get_resource::<PressureRecord>()
        .and_then(|r| r.front())
        .expect("the front was seen");
    // PS-1 as the scene (and the paper): E = 20 MPa, nu = 0.45, rho_c = 0.79 x 1280.
    let (e, nu, rho_c): (f64, f64, f64) = (2.0e7, 0.45, 0.79 * 1280.0);
    let m = e * (1.0 - nu) / ((1.0 + nu) * (1.0 - 2.0 * nu));
    let c = (m / rho_c).sqrt();
    assert!(
        front.bins_reached >= 12,
        "front seen in {} bins",
        front.bins_reached
    );
    assert!(
        (front.speed / c - 1.0).abs() < 0.10,
        "front speed {:.1} m/s vs p-wave speed {c:.1} m/s",
        front.speed
    );
}
