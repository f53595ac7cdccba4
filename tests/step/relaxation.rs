//! The damping of a transfer must be set per unit time, not per step (the dense-flow
//! issue's item 3): `transfer: AffineFlip(relaxation: n)` relaxes each point's departure
//! from the grid's velocity over `tau = n h / c`, whatever the step. FLIP's per-step PIC
//! blend (`flip: 0.95`) removes 5% at every step instead, so the same blend damps ten
//! times as much in the same time when the step is ten times smaller.
//!
//! The probe: an elastic block at rest without gravity whose points carry random velocity
//! noise of zero mean, most of which the grid cannot see. What the relaxation acts on, the
//! points' departure from the grid's velocity at their positions, must after a fixed time
//! not depend on the step. (The block's kinetic energy is no measure: the part of the noise
//! the grid sees rings as elastic waves of the grid's shortest wavelength, whose phase at
//! a given time does depend on the step.)

use crate::common::Rng;
use regolith::Simulation;
use regolith::defaults::parse_scene;
use regolith::shape_functions::{CpdiFixed, Footprint};

/// p-wave speed of the block's material: E = 1 MPa, nu = 0.3, rho = 1000 kg/m^3.
fn wave_speed() -> f64 {
    let (e, nu, rho): (f64, f64, f64) = (1e6, 0.3, 1000.0);
    (e * (1.0 - nu) / ((1.0 + nu) * (1.0 - 2.0 * nu)) / rho).sqrt()
}

const CELL: f64 = 0.05;

/// The energy of the points' departure from the grid's velocity, `sum m |v_p - v(x_p)|^2
/// / 2`, at `end` over the block's initial kinetic energy, for the transfer settings
/// `transfer` (RON fields) and a step of `cfl` wave crossings of a cell.
fn remaining_energy(transfer: &str, cfl: f64, end: f64) -> f64 {
    let scene = parse_scene(&format!(
        r#"(
        name: "relaxation",
        domain: (size: (1.0, 1.0), cells: (20, 20)),
        time: (end: {end}, step: Cfl({cfl}), output_every: 1.0),
        gravity: (0.0, 0.0),
        walls: (left: Slip, right: Slip, bottom: Slip, top: Slip),
        {transfer},
        bodies: [(
            name: "block",
            shape: Rectangle(min: (0.2, 0.2), max: (0.8, 0.8)),
            material: LinearElastic(density: 1000.0, youngs_modulus: 1e6, poisson_ratio: 0.3),
        )],
    )"#
    ))
    .unwrap();
    let mut sim = Simulation::new(&scene);
    let mut rng = Rng(0x0005_eed0_fa11_5a1d);
    let energy = |sim: &mut Simulation| -> f64 {
        let p = sim.points("block").unwrap();
        (0..p.len())
            .map(|k| 0.5 * p.mass[k] * p.velocity[k].length_squared())
            .sum()
    };
    {
        let mut p = sim.points_mut("block").unwrap();
        let noise: Vec<_> = (0..p.len()).map(|_| 1e-3 * rng.vec()).collect();
        let mean = noise.iter().sum::<regolith::glam::DVec2>() / noise.len() as f64;
        for (v, n) in p.velocity.iter_mut().zip(noise) {
            *v = n - mean;
        }
    }
    let start = energy(&mut sim);
    while !sim.finished() {
        sim.step().unwrap();
    }
    let grid = sim.grid().clone();
    let v_grid = sim.grid_field("block").unwrap().velocity.clone();
    let p = sim.points("block").unwrap();
    let departure: f64 = (0..p.len())
        .map(|k| {
            let f = Footprint::new::<CpdiFixed>(&grid, p.position[k], p.half_width[k]);
            0.5 * p.mass[k] * (p.velocity[k] - f.interpolate(&v_grid)).length_squared()
        })
        .sum();
    departure / start
}

#[test]
fn the_affine_flip_relaxation_is_set_per_unit_time() {
    let relaxation = 10.0;
    let tau = relaxation * CELL / wave_speed();
    let transfer = format!("transfer: AffineFlip(relaxation: {relaxation})");
    let coarse = remaining_energy(&transfer, 0.5, tau);
    let fine = remaining_energy(&transfer, 0.05, tau);
    // The departure falls as e^(-t/tau), its energy as e^(-2) = 0.14 in one tau (0.10 is
    // measured: the grid's own round trip takes a little more). Between CFL 1 and 0.02 what
    // is left moves from 0.0997 to 0.1079, 0.0987 at CFL 0.5 and 0.1051 at 0.05 (FLIP's
    // per-step blend: from 0.086 to 0.0002 over the same range).
    assert!(coarse < 0.5, "{coarse:.3} of the energy left after tau");
    assert!(
        (coarse - fine).abs() < 0.1 * fine,
        "energy left after tau: {coarse:.4} at CFL 0.5, {fine:.4} at CFL 0.05"
    );
}

/// The defect the relaxation replaces: the same per-step blend, a tenth of the step, ten
/// times the steps and far less energy left.
#[test]
fn the_flip_blend_is_set_per_step() {
    let tau = 10.0 * CELL / wave_speed();
    let coarse = remaining_energy("transfer: Flip, flip: 0.95", 0.5, tau);
    let fine = remaining_energy("transfer: Flip, flip: 0.95", 0.05, tau);
    assert!(
        fine < 0.5 * coarse,
        "energy left after {tau:.4} s: {coarse:.4} at CFL 0.5, {fine:.4} at CFL 0.05"
    );
}
