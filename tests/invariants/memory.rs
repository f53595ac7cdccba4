//! The state a point carries stays within the budget issue 22 set: no speed-up may buy its
//! gain with more memory per point than the full model took before it (325 bytes: the point
//! columns with the affine field, phase and rates, the footprint, cell, band and band slot;
//! the paper's materials keep no further history).

use regolith::Simulation;
use regolith::run::memory_estimate;

#[test]
fn the_full_model_keeps_within_its_bytes_per_point() {
    let scene = crate::common::full_model_coarse();
    let mut sim = Simulation::new(&scene);
    let memory = memory_estimate(&mut sim, &scene);
    assert_eq!(memory.points, sim.particle_count());
    let per_point = memory.per_point();
    assert!(
        per_point <= 325.0,
        "{per_point} bytes of state per point, above the budget of 325"
    );
    assert!(memory.grid_bytes > 0 && memory.total() > memory.point_bytes);
}

/// The delta-correction's arrays are counted: 40 bytes more per point (a place and a
/// gradient), and a fill and a slope per node of its grid, four times as many nodes with
/// `refinement: 2`.
#[test]
fn the_delta_correction_is_counted() {
    let estimate = |sets: &[&str]| {
        let scene = crate::common::full_model_coarse_with(sets);
        let mut sim = Simulation::new(&scene);
        memory_estimate(&mut sim, &scene)
    };
    let off = estimate(&[]);
    let on = estimate(&["spacing=DeltaCorrection(refinement: 2)"]);
    assert_eq!(on.point_bytes - off.point_bytes, 40 * off.points);
    assert_eq!(on.grid_bytes - off.grid_bytes, 16 * 81 * 81);
}
