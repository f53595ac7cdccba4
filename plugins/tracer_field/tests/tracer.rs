//! The tracer field against the diffusion equation, beside the nonlocal fluidity, and the
//! scene check's refusals; through the public API alone.

use regolith::body::Points;
use regolith::grid_field::FieldColumns;
use regolith::material::nonlocal::FLUIDITY;
use regolith::{Regolith, Scene, Simulation};
use tracer_field::{COLUMN, TracerPlugin};

/// A fully periodic square of `cells` x `cells` cells of 5 mm, filled with an elastic block
/// at rest without gravity, with `fields` (RON).
fn periodic_block(cells: usize, fields: &str) -> String {
    let size = 5e-3 * cells as f64;
    format!(
        "Scene(name: \"block\", domain: (size: ({size}, {size}), cells: ({cells}, {cells})), \
         time: (end: 1.0, step: Cfl(0.5), output_every: 1.0), gravity: (0.0, 0.0), \
         walls: (left: Periodic, right: Periodic, bottom: Periodic, top: Periodic), \
         bodies: [(name: \"block\", shape: Rectangle(min: (0.0, 0.0), max: ({size}, {size})), \
         material: LinearElastic(density: 1500.0, youngs_modulus: 1.0e6, poisson_ratio: 0.3), \
         points_per_cell: 2)], fields: [{fields}])"
    )
}

fn parse(text: &str) -> Result<Scene, String> {
    let registries = Regolith::default().add_plugin(TracerPlugin).registries();
    Scene::parse(text, "scene.ron", &registries).map_err(|e| e.to_string())
}

/// Each point's position and volume, and its tracer.
fn tracer(sim: &mut Simulation) -> Vec<(f64, f64, f64)> {
    let mut q = sim.world.query::<(&Points, &FieldColumns)>();
    let (points, columns) = q.single(&sim.world).unwrap();
    let c = columns.get(COLUMN).unwrap();
    (0..c.len())
        .map(|k| (points.position[k].x, points.volume[k], c[k]))
        .collect()
}

/// The left half of a periodic block dyed, on `cells` x `cells` cells: a square wave along
/// x, whose first Fourier mode `sin(k x)` decays (the higher ones are orthogonal to it on the
/// points' uniform lattice). Returns the measured decay rate against `D k^2`, and the drift
/// of the volume-weighted total; checks the block stays at rest.
fn dyed_half(cells: usize) -> (f64, f64, f64) {
    let size = 5e-3 * cells as f64;
    let d = 0.01;
    let text = periodic_block(
        cells,
        &format!(
            "Tracer(body: \"block\", diffusivity: {d}, \
             marked: Rectangle(min: (0.0, 0.0), max: ({}, {size})))",
            size / 2.0
        ),
    );
    let mut sim = Simulation::new(&parse(&text).unwrap());
    let k = 2.0 * std::f64::consts::PI / size;
    let mode = |points: &[(f64, f64, f64)]| {
        let (mut dot, mut norm) = (0.0, 0.0);
        for &(x, _, c) in points {
            dot += c * (k * x).sin();
            norm += (k * x).sin().powi(2);
        }
        dot / norm
    };
    let total = |points: &[(f64, f64, f64)]| points.iter().map(|&(_, v, c)| v * c).sum::<f64>();
    let start = tracer(&mut sim);
    let (a0, total0) = (mode(&start), total(&start));
    // The square wave's first mode: 2/pi.
    assert!((a0 - 2.0 / std::f64::consts::PI).abs() < 1e-3, "a0 = {a0}");
    // About one e-folding of the mode.
    let t0 = sim.clock().time;
    while sim.clock().time - t0 < 1.0 / (d * k * k) {
        sim.step().unwrap();
    }
    let t1 = sim.clock().time;
    let end = tracer(&mut sim);
    assert!(
        end.iter()
            .zip(&start)
            .all(|(a, b)| a.0 == b.0 && a.1 == b.1),
        "the block moved"
    );
    let measured = (a0 / mode(&end)).ln() / (t1 - t0);
    (measured, d * k * k, (total(&end) - total0) / total0)
}

/// The mode decays at `D k^2` to within 1% at 40 cells per wavelength, the error falling as
/// `h^2` (about four times from 20 to 40 cells), and the total stays put to round-off.
#[test]
fn a_dyed_half_diffuses_at_d_k_squared_and_keeps_its_total() {
    let error = |cells: usize| {
        let (measured, expected, drift) = dyed_half(cells);
        eprintln!(
            "{cells} cells: decay rate {measured:.5} /s against D k^2 = {expected:.5} /s, \
             total drift {drift:e}"
        );
        assert!(
            drift.abs() < 1e-12,
            "{cells} cells: the total moved by {drift:e}"
        );
        (measured - expected) / expected
    };
    let (coarse, fine) = (error(20), error(40));
    assert!(
        fine.abs() < 0.01,
        "40 cells: {:.3}% off D k^2",
        100.0 * fine
    );
    let order = (coarse / fine).log2();
    assert!(
        (1.6..2.4).contains(&order),
        "errors {coarse:.2e} and {fine:.2e}: order {order:.2}, not 2"
    );
}

/// The tracer is passive: a `Nonlocal` chute (the shipped one with `Nonlocal` for `MuI`)
/// carrying a tracer beside its fluidity, both fields in the `Fields` set, flows bit for bit
/// as it does without one, and the tracer does move.
#[test]
fn a_tracer_beside_the_fluidity_leaves_the_flow_bit_for_bit() {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/chute_flow_mui.ron");
    let text = std::fs::read_to_string(path).unwrap();
    let text = text.replace("material: MuI(", "material: Nonlocal(");
    let with = text.replace(
        "outputs: [",
        "fields: [Tracer(body: \"layer\", diffusivity: 1e-3, \
         marked: Rectangle(min: (0.0, 0.05), max: (0.05, 0.1)))], outputs: [",
    );
    assert_ne!(with, text);
    let run = |text: &str| {
        let mut sim = Simulation::new(&parse(text).unwrap());
        for _ in 0..200 {
            sim.step().unwrap();
        }
        let hash = sim.state_hash("layer").unwrap();
        let mut q = sim.world.query::<&FieldColumns>();
        let columns = q.single(&sim.world).unwrap();
        let fluidity: Vec<u64> = columns
            .get(FLUIDITY)
            .unwrap()
            .iter()
            .map(|g| g.to_bits())
            .collect();
        let dyed = columns.get(COLUMN).map(|c| c.to_vec());
        (hash, fluidity, dyed)
    };
    let (hash, fluidity, none) = run(&text);
    let (hash_dyed, fluidity_dyed, dyed) = run(&with);
    assert!(none.is_none());
    assert_eq!(hash, hash_dyed, "the tracer changed the flow");
    assert!(fluidity == fluidity_dyed, "the tracer changed the fluidity");
    assert!(
        fluidity.iter().any(|&g| f64::from_bits(g) > 0.0),
        "nothing flows"
    );
    let dyed = dyed.unwrap();
    assert!(
        dyed.iter().any(|&c| c > 1e-6 && c < 1.0 - 1e-6),
        "the tracer did not diffuse"
    );
}

/// A scene's mistakes are refused before a run, at the tracer's line, saying what to change.
#[test]
fn the_scene_check_refuses_what_cannot_run() {
    let tracer = |body: &str, d: f64| {
        format!(
            "Tracer(body: \"{body}\", diffusivity: {d}, marked: Rectangle(min: (0.0, 0.0), max: (0.1, 0.2)))"
        )
    };
    let refused = |fields: &str| parse(&periodic_block(40, fields)).unwrap_err();
    let e = refused(&tracer("bed", 0.01));
    assert!(
        e.contains("Tracer") && e.contains("\"bed\"") && e.contains("block"),
        "{e}"
    );
    let e = refused(&tracer("block", 100.0));
    assert!(
        e.contains("diffusion number") && e.contains("smaller diffusivity"),
        "{e}"
    );
    let e = refused(&format!(
        "{}, {}",
        tracer("block", 0.01),
        tracer("block", 0.02)
    ));
    assert!(e.contains("column \"tracer\" already"), "{e}");
    let e = refused(&tracer("block", -1.0));
    assert!(e.contains("diffusivity must be zero or more"), "{e}");
    // Without the plugin, the field is unknown.
    let builtin = Regolith::default().registries();
    let e = Scene::parse(
        &periodic_block(40, &tracer("block", 0.01)),
        "scene.ron",
        &builtin,
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("unknown field `Tracer`"), "{e}");
}
