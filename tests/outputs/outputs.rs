//! Every built-in output can run in one scene: outputs share the Output set without an
//! ordering between them, so none may take exclusive access to a shared resource (this
//! once stopped a scene with two file-writing outputs before its first step).

use regolith::Simulation;

#[test]
fn all_built_in_outputs_run_together_and_write_their_files() {
    let dir = tempfile::tempdir().unwrap();
    let scene = crate::common::scene(
        "flow_field_coarse",
        &[
            "time.end=0.01",
            "outputs=[Impact(body: \"disc\", surface: 0.6825), \
             FlowField(body: \"bed\", intruder: \"disc\", scale: 0.127, at: [0.005]), \
             FreeSurface(body: \"bed\", every: 0.005), Snapshots(every: 0.005), \
             Vtk(every: 0.005, grid: true), \
             PressureFront(body: \"bed\", centre: (0.455, 0.6825), radius: 0.2, bins: 4, every: 0.002), \
             Runout(body: \"bed\", every: 0.005), VelocityProfile(body: \"bed\", every: 0.005)]",
        ],
    );
    let mut sim = Simulation::with_output(&scene, dir.path()).unwrap();
    sim.run(|_| {}).unwrap();
    for f in [
        "flow_field_0.csv",
        "free_surface.csv",
        "pressure_front.csv",
        "runout.csv",
        "velocity_profile.csv",
        "snapshots/snapshot_00000.csv",
        "vtk/points.pvd",
        "vtk/grid.pvd",
        "vtk/bed_00000.vtu",
        "vtk/disc_grid_00000.vti",
    ] {
        assert!(dir.path().join(f).exists(), "{f} not written");
    }
}

/// An output that cannot write stops the run with the reason, whichever output it is.
#[test]
fn an_output_that_cannot_write_stops_the_run() {
    let dir = tempfile::tempdir().unwrap();
    let scene = crate::common::scene(
        "flow_field_coarse",
        &[
            "time.end=0.01",
            "outputs=[FreeSurface(body: \"bed\", every: 0.005)]",
        ],
    );
    std::fs::create_dir(dir.path().join("free_surface.csv")).unwrap();
    let mut sim = Simulation::with_output(&scene, dir.path()).unwrap();
    let fault = sim.run(|_| {}).unwrap_err();
    assert!(
        fault.message.contains("free_surface.csv"),
        "{}",
        fault.message
    );
}

/// The free surface is the bed's top at rest (to the one-cell resolution of the measure),
/// drops under the disc as it enters, and is where the points are: each recorded height is
/// the top of a cell holding points of that column, and no cell above it holds as many as
/// half a full cell's. (The far surface is not held still: the impact's p-wave, reflected by
/// the rigid floor, lifts it at about 0.8 m/s from 5.5 ms, docs/numerics.md "The impact
/// bulks the bed".)
#[test]
fn the_free_surface_starts_flat_opens_under_the_disc_and_follows_the_points() {
    use regolith::output::free_surface::SurfaceRecord;
    let scene = crate::common::scene(
        "flow_field_coarse",
        &[
            "time.end=0.02",
            "outputs=[FreeSurface(body: \"bed\", every: 0.01)]",
        ],
    );
    let mut sim = Simulation::new(&scene);
    let grid = sim.grid().clone();
    let h = grid.cell_size;
    let full = 4; // 2 x 2 points per cell
    sim.run(|_| {}).unwrap();
    let record = sim.world.get_resource::<SurfaceRecord>().unwrap().clone();
    assert_eq!(record.times.len(), 3);
    for z in &record.heights[0] {
        assert!((z - 0.6825).abs() <= h, "surface at {z} m at rest");
    }
    let last = &record.heights[2];
    let centre = last[last.len() / 2];
    assert!(
        centre < 0.6825 - 2.0 * h,
        "surface under the disc at {centre} m"
    );
    let points = sim.points("bed").unwrap();
    for (i, &z) in last.iter().enumerate() {
        let (left, right) = (
            grid.origin.x + i as f64 * h,
            grid.origin.x + (i + 1) as f64 * h,
        );
        let column: Vec<f64> = points
            .position
            .iter()
            .filter(|x| x.x >= left && x.x < right)
            .map(|x| x.y)
            .collect();
        let in_top_cell = column.iter().filter(|&&y| y >= z - h && y < z).count();
        assert!(
            in_top_cell >= full / 2,
            "column {i}: surface at {z} m but {in_top_cell} points in the cell below it"
        );
        for j in 0..4 {
            let (lo, hi) = (z + j as f64 * h, z + (j + 1) as f64 * h);
            let above = column.iter().filter(|&&y| y >= lo && y < hi).count();
            assert!(
                above < full / 2,
                "column {i}: {above} points in the cell {lo}-{hi} m above the surface at {z} m"
            );
        }
    }
}

/// A layer that has compacted at constant point volume (here made so by hand: its points
/// moved 10% closer to the bed with their volumes unchanged) completes with its health in
/// the summary and a warning as the run's last line; the same layer untouched has none.
#[test]
fn a_compacted_layer_is_reported_in_the_summary_and_the_last_line() {
    use regolith::run::{Provenance, summarize};
    let scene = crate::common::scene("chute_flow_mui", &[]);
    let from = Provenance {
        file: "chute_flow_mui.ron",
        text: "",
        overrides: &[],
    };
    let mut sim = Simulation::new(&scene);
    let honest = summarize(&mut sim, &scene, &from, 0.0, "completed", None);
    let health = honest.bodies[0]
        .health
        .clone()
        .expect("a granular body's health");
    assert!((health.bulk_volume_ratio - 1.0).abs() < 1e-3, "{health:?}");
    assert!(health.height_drift.unwrap().abs() < 1e-3, "{health:?}");
    assert!(honest.warnings.is_empty(), "{:?}", honest.warnings);
    let layer = sim
        .world
        .query::<(&regolith::body::Body, &mut regolith::body::Points)>()
        .iter_mut(&mut sim.world)
        .next()
        .unwrap()
        .1
        .into_inner();
    for x in &mut layer.position {
        x.y *= 0.9;
    }
    let sunk = summarize(&mut sim, &scene, &from, 0.0, "completed", None);
    let health = sunk.bodies[0].health.clone().unwrap();
    assert!(health.bulk_volume_ratio > 1.05, "{health:?}");
    assert_eq!(sunk.warnings.len(), 2, "{:?}", sunk.warnings);
    let last = sunk.headlines.last().unwrap();
    assert!(
        last.starts_with("WARNING: layer: the layer's thickness"),
        "{last}"
    );
    let json = serde_json::to_value(&sunk).unwrap();
    assert_eq!(json["warnings"].as_array().unwrap().len(), 2);
    assert!(
        json["bodies"][0]["health"]["bulk_volume_ratio"]
            .as_f64()
            .unwrap()
            > 1.05
    );
}

/// `Runout` measures a column at rest at its shape exactly (the points reach half their
/// spacing beyond their centres), then the collapse: the pile spreads and lowers, and the
/// summary's ratios are those of the first and last records.
#[test]
fn the_runout_of_a_collapsing_column_starts_at_its_shape_and_spreads() {
    use regolith::output::runout::RunoutRecord;
    let scene = crate::common::scene(
        "granular_column_collapse_a2",
        &[
            "domain.cells=(60, 30)",
            "time.end=0.4",
            "outputs=[Runout(body: \"column\", every: 0.02)]",
        ],
    );
    let mut sim = Simulation::new(&scene);
    sim.run(|_| {}).unwrap();
    let record = sim.world.resource::<RunoutRecord>();
    let first = record.extents[0];
    assert_eq!(record.times[0], 0.0);
    assert!((first.left - 0.0).abs() < 1e-12, "{first:?}");
    assert!((first.right - 0.1).abs() < 1e-12, "{first:?}");
    assert!((first.height - 0.2).abs() < 1e-12, "{first:?}");
    assert_eq!(record.times.len(), 21);
    let s = record.summary().unwrap();
    assert!((s.aspect_ratio - 2.0).abs() < 1e-9, "{s:?}");
    // At 0.4 s the a = 2 pile has spread to several widths and lost half its height
    // (docs/GRANULAR.md: at rest by 0.6 s, (Lf - L0)/L0 about 3.6 on 10 mm cells).
    assert!(s.runout_ratio > 1.5, "{s:?}");
    assert!(s.height_ratio < 0.7, "{s:?}");
    // Never wider than every point, never narrower than the pile was.
    let last = record.extents.last().unwrap();
    assert!(last.left >= -1e-12 && last.right <= 0.6, "{last:?}");
}

/// `VelocityProfile` reads a layer's velocity row by row: a layer given `vx = 20 y` (shear
/// at 20/s) measures `20 y` at each row's centre (2 x 2 points per cell sit symmetrically
/// about it), its mass-weighted mean `20 ybar`, and its surface is its top row.
#[test]
fn the_velocity_profile_reads_a_sheared_layer_row_by_row() {
    use regolith::body::Points;
    use regolith::output::profile::Profile;
    let scene = crate::common::scene("chute_flow_mui", &[]);
    let mut sim = Simulation::new(&scene);
    let grid = sim.grid().clone();
    let mut q = sim.world.query::<&mut Points>();
    let mut points = q.iter_mut(&mut sim.world).next().unwrap();
    for k in 0..points.len() {
        points.velocity[k].x = 20.0 * points.position[k].y;
    }
    let p = Profile::measure(&points, &grid);
    let h = grid.cell_size;
    // The layer is 0.1 m deep on 5 mm cells: rows 0 to 19 hold points, 20 to 29 none.
    for j in 0..20 {
        let centre = (j as f64 + 0.5) * h;
        assert!(
            (p.speeds[j] - 20.0 * centre).abs() < 1e-12,
            "row {j}: {}",
            p.speeds[j]
        );
    }
    assert!(p.speeds[20..].iter().all(|v| v.is_nan()));
    assert_eq!(p.surface(), Some(19));
    let mass: f64 = points.mass.iter().sum();
    let ybar = (0..points.len())
        .map(|k| points.mass[k] * points.position[k].y)
        .sum::<f64>()
        / mass;
    assert!((p.mean_speed - 20.0 * ybar).abs() < 1e-12);
}
