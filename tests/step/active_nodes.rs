//! The clear and the grid update visit only a field's active nodes (`GridField::active`: those
//! the last two scatters could reach). That is only right if every other node is empty and at
//! rest, whatever the bodies do; here a disc rises through the empty upper grid, so its active
//! rows move band after band, and the invariant is checked at every step.

use regolith::Simulation;
use regolith::body::Body;
use regolith::glam::DVec2;
use regolith::grid::GridField;

#[test]
fn nodes_outside_the_active_range_are_empty_and_at_rest() {
    let scene = crate::common::full_model_coarse_with(&["bodies.disc.velocity=(0.0, 10.0)"]);
    let mut sim = Simulation::new(&scene);
    let mut disc_ranges = Vec::new();
    for step in 0..250 {
        sim.step().unwrap();
        let mut fields = sim.world.query::<(&Body, &GridField)>();
        for (body, field) in fields.iter(&sim.world) {
            let active = field.active();
            if body.name == "disc" {
                disc_ranges.push(active.clone());
            }
            for n in (0..field.mass.len()).filter(|n| !active.contains(n)) {
                let at_rest = field.mass[n] == 0.0
                    && [
                        field.momentum[n],
                        field.force[n],
                        field.velocity[n],
                        field.acceleration[n],
                    ]
                    .iter()
                    .all(|v| *v == DVec2::ZERO);
                assert!(
                    at_rest,
                    "step {step}: {}'s node {n}, outside the active nodes {active:?}, is not \
                     empty and at rest",
                    body.name
                );
            }
        }
    }
    let (first, last) = (&disc_ranges[0], &disc_ranges[disc_ranges.len() - 1]);
    assert!(
        last.start > first.start,
        "the disc's active nodes never moved ({first:?} to {last:?}): the test checks nothing"
    );
}
