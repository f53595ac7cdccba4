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

/// A field's columns are counted: the `Nonlocal` bed carries the fluidity's three columns
/// and a slot in the bands kept for its scatter, 28 bytes a point more than `MuI` (neither
/// keeps a material history); after a step its nodal scalars are counted on the grid's side.
#[test]
fn a_fields_columns_are_counted() {
    let estimate = |material: &str, steps: usize| {
        let set = format!(
            "bodies.bed.material={material}(youngs_modulus: 2.0e7, poisson_ratio: 0.45, \
             grain_density: 1280.0, packing_fraction: 0.79, grain_diameter: 5.0e-3, \
             mu_s: 0.32, mu_2: 0.598, i_0: 0.278)"
        );
        let scene = crate::common::full_model_coarse_with(&[&set]);
        let mut sim = Simulation::new(&scene);
        for _ in 0..steps {
            sim.step().unwrap();
        }
        let bed = sim.points("bed").unwrap().len();
        (memory_estimate(&mut sim, &scene), bed)
    };
    let (mui, bed) = estimate("MuI", 0);
    let (nonlocal, _) = estimate("Nonlocal", 0);
    assert_eq!(nonlocal.point_bytes - mui.point_bytes, 28 * bed);
    let (stepped, _) = estimate("Nonlocal", 1);
    assert!(stepped.grid_bytes > nonlocal.grid_bytes);
    eprintln!(
        "per point: MuI {:.1} B, Nonlocal {:.1} B; grid {} B, {} B after a step",
        mui.per_point(),
        nonlocal.per_point(),
        nonlocal.grid_bytes,
        stepped.grid_bytes
    );
}
