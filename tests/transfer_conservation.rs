//! P2G then G2P conserves mass and momentum to round-off, for every scheme and variant.
//!
//! Mass: `sum_i m_i = sum_p m_p` because the weights are a partition of unity. Momentum: the
//! nodal forces of a stress field sum to zero (gradients sum to zero), so without gravity a
//! step leaves `sum_p m_p v_p` unchanged whatever the stresses and velocities, for FLIP
//! (`sum_p m_p sum_i S a_i = sum_i f_i = 0`) and PIC (`sum_p m_p sum_i S v_i = sum_i m_i v_i`).

use regolith::Simulation;
use regolith::glam::DVec2;
use regolith::plugin::parse_scene;
use regolith::stress::Stress;

/// A small deterministic generator (xorshift), uniform in [-1, 1).
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    }
}

fn scene(integration: &str, update: &str, flip: f64) -> regolith::Scene {
    parse_scene(&format!(
        r#"(
        name: "conservation",
        domain: (size: (1.0, 1.0), cells: (16, 16)),
        time: (end: 1.0, step: Fixed(1e-5), output_every: 1.0),
        gravity: (0.0, 0.0),
        walls: (left: Free, right: Free, bottom: Free, top: Free),
        integration: {integration},
        update: {update},
        flip: {flip},
        bodies: [(
            name: "disc",
            shape: Disc(centre: (0.5, 0.5), radius: 0.3),
            material: LinearElastic(density: 1000.0, youngs_modulus: 1e6, poisson_ratio: 0.3),
            points_per_cell: 3,
        )],
    )"#
    ))
    .unwrap()
}

fn momentum(sim: &mut Simulation) -> (DVec2, f64) {
    let p = sim.points("disc").unwrap();
    let mut total = DVec2::ZERO;
    let mut scale = 0.0;
    for k in 0..p.len() {
        total += p.mass[k] * p.velocity[k];
        scale += p.mass[k] * p.velocity[k].length();
    }
    (total, scale)
}

#[test]
fn one_step_conserves_mass_and_momentum() {
    for integration in ["Linear", "CpdiFixed"] {
        for update in ["Usl", "Musl"] {
            for flip in [0.0, 1.0] {
                let mut sim = Simulation::new(&scene(integration, update, flip));
                let mut rng = Rng(0x9E3779B97F4A7C15);
                let spacing = 1.0 / 16.0 / 3.0;
                {
                    let mut p = sim.points_mut("disc").unwrap();
                    for k in 0..p.len() {
                        p.position[k] += DVec2::new(rng.next(), rng.next()) * 0.3 * spacing;
                        p.velocity[k] = DVec2::new(rng.next(), rng.next());
                        p.stress[k] = Stress {
                            xx: 1e4 * rng.next(),
                            yy: 1e4 * rng.next(),
                            xy: 1e4 * rng.next(),
                            zz: 1e4 * rng.next(),
                        };
                    }
                }
                let before = momentum(&mut sim);
                let point_mass: f64 = sim.points("disc").unwrap().mass.iter().sum();
                sim.step().unwrap();
                let node_mass: f64 = sim.grid_field("disc").unwrap().mass.iter().sum();
                let after = momentum(&mut sim);
                let tag = format!("{integration} {update} flip {flip}");
                assert!(
                    (node_mass - point_mass).abs() < 1e-13 * point_mass,
                    "{tag}: grid mass {node_mass} vs points {point_mass}"
                );
                let drift = (after.0 - before.0).length();
                assert!(
                    drift < 1e-13 * before.1,
                    "{tag}: momentum drift {drift:e} of {:e}",
                    before.1
                );
            }
        }
    }
}
