//! The step is deterministic: the state after N steps is bitwise the same with 1 and 2
//! threads (the parallel scatter never reorders a node's contributions). That no step
//! allocates is tested in `allocation.rs`, a binary of its own: its allocation counter is
//! global, and other tests running beside it would count.

mod common;

use regolith::Simulation;

fn run_with_threads(threads: usize, steps: usize) -> [u64; 2] {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| {
        let mut sim = Simulation::new(&common::full_model_coarse());
        for _ in 0..steps {
            sim.step().unwrap();
        }
        common::bed_and_disc_fingerprints(&mut sim)
    })
}

#[test]
fn one_and_two_threads_give_the_same_state() {
    let one = run_with_threads(1, 200);
    let two = run_with_threads(2, 200);
    assert_eq!(
        one, two,
        "the state after 200 steps depends on the thread count"
    );
}

/// The cells found after the move are reused by the next step; finding them again (what
/// `points_mut` forces) must give the same state, bit for bit.
#[test]
fn reused_cells_equal_cells_found_again() {
    let mut reused = Simulation::new(&common::full_model_coarse());
    let mut found = Simulation::new(&common::full_model_coarse());
    for _ in 0..100 {
        reused.step().unwrap();
        found.step().unwrap();
        found.points_mut("bed").unwrap();
        found.points_mut("disc").unwrap();
    }
    assert_eq!(
        common::bed_and_disc_fingerprints(&mut reused),
        common::bed_and_disc_fingerprints(&mut found)
    );
}

/// The parallel survey of the Diagnostics set sums over fixed chunks in order, so the body
/// state it leaves is bitwise what a serial `BodyState::measure` gives.
#[test]
fn the_parallel_survey_equals_the_serial_measure() {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    pool.install(|| {
        let mut sim = Simulation::new(&common::full_model_coarse());
        for _ in 0..30 {
            sim.step().unwrap();
        }
        let bodies = sim.bodies();
        for (body, state, n) in bodies {
            assert!(n > regolith::body::SURVEY_CHUNK || body.name == "disc");
            let serial = regolith::body::BodyState::measure(sim.points(&body.name).unwrap());
            let bits = |s: &regolith::body::BodyState| {
                [
                    s.mass,
                    s.centre_of_mass.x,
                    s.centre_of_mass.y,
                    s.velocity.x,
                    s.velocity.y,
                    s.kinetic_energy,
                    s.max_speed,
                ]
                .map(f64::to_bits)
            };
            assert_eq!(bits(&state), bits(&serial), "body {}", body.name);
        }
    });
}

/// The health screen finds a non-finite value anywhere, here in the bed's last chunk.
#[test]
fn a_non_finite_stress_stops_the_run() {
    let mut sim = Simulation::new(&common::full_model_coarse());
    sim.step().unwrap();
    {
        let mut bed = sim.points_mut("bed").unwrap();
        let last = bed.len() - 1;
        bed.stress[last].xy = f64::NAN;
    }
    let fault = sim.step().expect_err("a NaN stress must stop the run");
    assert!(fault.message.contains("not finite"), "{fault}");
}
