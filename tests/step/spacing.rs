//! The delta-correction in the step (`spacing: DeltaCorrection(..)`, `step::spacing`): a
//! clump of points in a flowing chute spreads, a bed at rest is not touched, and the state is
//! the same at every thread count and after a resume.

use std::collections::HashMap;

use regolith::glam::DVec2;
use regolith::{Scene, Simulation};

const ON: &str = "spacing=DeltaCorrection()";
const TWO_SIDED: &str = "spacing=DeltaCorrection(pull_above: 0.75, refinement: 2)";

/// The shipped chute at 25 degrees on 10 mm cells (10 across the 0.1 m layer, 5 along the
/// periodic slope), released from rest without stress, with `extra` overrides.
fn chute(end: f64, extra: &[&str]) -> Scene {
    let th = 25f64.to_radians();
    let gravity = format!("gravity=({}, {})", 9.81 * th.sin(), -9.81 * th.cos());
    let mut sets = vec![gravity.as_str(), "domain.cells=(5, 15)"];
    let end = format!("time.end={end}");
    sets.push(&end);
    sets.extend_from_slice(extra);
    crate::common::scene("chute_flow_mui", &sets)
}

/// The points of the 3 x 3 cells around `(0.025, 0.05)` pulled to half their distance from
/// it: 36 points in about two cells, as crowding leaves them.
fn crowd(sim: &mut Simulation) {
    let centre = DVec2::new(0.025, 0.05);
    let mut p = sim.points_mut("layer").unwrap();
    for x in &mut p.position {
        let d = *x - centre;
        if d.x.abs() < 0.015 && d.y.abs() < 0.015 {
            *x = centre + 0.5 * d;
        }
    }
}

fn most_in_a_cell(sim: &mut Simulation, cell: f64) -> usize {
    let mut count = HashMap::new();
    for x in &sim.points("layer").unwrap().position {
        *count
            .entry(((x.x / cell).floor() as i64, (x.y / cell).floor() as i64))
            .or_insert(0usize) += 1;
    }
    count.into_values().max().unwrap()
}

/// A clump of 36 points (four per cell at the start) carried down a chute for 0.2 s: the
/// flow alone keeps it (the cell-averaged dilatation gives it no stiffness), the correction
/// spreads it. On the step's grid it stops short of four per cell, since linear hats on
/// 10 mm cells cannot see a clump smaller than a cell; on a grid twice as fine it gets closer.
/// Measured: 12 in a cell at the start; at 0.2 s 10 without, 8 with, 6 with `refinement: 2`,
/// 6 with that and the two-sided form.
#[test]
fn a_clump_in_a_chute_spreads_with_the_correction_and_stays_without() {
    let mut most = Vec::new();
    for spacing in [
        "spacing=Off",
        ON,
        "spacing=DeltaCorrection(refinement: 2)",
        TWO_SIDED,
    ] {
        let scene = chute(0.2, &[spacing]);
        let mut sim = Simulation::new(&scene);
        crowd(&mut sim);
        let start = most_in_a_cell(&mut sim, 0.01);
        assert!(start >= 12, "the clump holds {start} points in a cell");
        sim.run(|_| {}).unwrap();
        most.push(most_in_a_cell(&mut sim, 0.01));
    }
    eprintln!("most in a cell at the end: {most:?}");
    let [off, on, finer, two_sided] = most[..] else {
        unreachable!()
    };
    assert!(
        off >= 10,
        "without the correction: {off} points in a cell at the end"
    );
    assert!(
        on <= 8,
        "with the correction: {on} points in a cell at the end"
    );
    assert!(
        finer <= 6,
        "with the correction on a grid twice as fine: {finer}"
    );
    assert!(
        two_sided <= 6,
        "with the two-sided form on a grid twice as fine: {two_sided}"
    );
}

/// A bed at rest over-fills no node (its points are compressed by their own weight), so the
/// correction moves nothing, in either form (the two-sided one leaves the compression's
/// under-fill, `p / K`, alone): the state is the uncorrected one to the bit.
#[test]
fn a_bed_at_rest_is_not_touched() {
    let fingerprint = |extra: &[&str]| {
        let mut sets = vec![
            "domain.cells=(50, 50)",
            "time.step=Cfl(0.5)",
            "time.end=0.02",
        ];
        sets.extend_from_slice(extra);
        let mut sim = Simulation::new(&crate::common::scene("granular_bed_at_rest", &sets));
        sim.run(|_| {}).unwrap();
        sim.points("bed").unwrap().fingerprint()
    };
    let off = fingerprint(&[]);
    assert_eq!(off, fingerprint(&[ON]));
    assert_eq!(off, fingerprint(&[TWO_SIDED]));
}

/// The crowded chute with the correction, 1, 2 and 4 threads: the same state to the bit
/// (periodic sides included).
#[test]
fn the_corrected_step_does_not_depend_on_the_thread_count() {
    let run = |threads: usize| {
        crate::common::with_threads(threads, || {
            let mut sim = Simulation::new(&chute(0.01, &[ON]));
            crowd(&mut sim);
            sim.run(|_| {}).unwrap();
            sim.points("layer").unwrap().fingerprint()
        })
    };
    let one = run(1);
    assert_eq!(one, run(2));
    assert_eq!(one, run(4));
}

/// Checkpointed halfway and resumed, the crowded chute with the correction ends bitwise where
/// the straight run ends (the correction keeps no state of its own between steps).
#[test]
fn a_corrected_run_resumes_bitwise() {
    let scene = chute(0.01, &[ON]);
    let mut straight = Simulation::new(&scene);
    crowd(&mut straight);
    straight.run(|_| {}).unwrap();
    let steps = straight.clock().step;

    let mut first = Simulation::new(&scene);
    crowd(&mut first);
    for _ in 0..steps / 2 {
        first.step().unwrap();
    }
    let mut resumed = crate::common::checkpoint_and_restore(&mut first, &scene);
    drop(first);
    resumed.run(|_| {}).unwrap();
    assert_eq!(resumed.clock().step, steps);
    assert_eq!(
        resumed.points("layer").unwrap().fingerprint(),
        straight.points("layer").unwrap().fingerprint()
    );
}
