//! Criterion benchmark of whole steps on the benchmark scene (30 k points, 100 x 100 cells).
//! Run: cargo bench --bench step -- --quick

use criterion::{Criterion, criterion_group, criterion_main};
use regolith::{Regolith, Scene, Simulation};

fn scene(integration: &str) -> Scene {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/bench_elastic_block.ron");
    let sets = vec![
        format!("integration={integration}"),
        "time.end=1.0".to_string(),
    ];
    Scene::load(&path, &sets, &Regolith::default().registries())
        .unwrap()
        .0
}

fn step(c: &mut Criterion) {
    for integration in ["Linear", "CpdiFixed"] {
        let mut sim = Simulation::new(&scene(integration));
        c.bench_function(&format!("step_30k_points_{integration}"), |b| {
            b.iter(|| sim.step().unwrap())
        });
    }
}

criterion_group!(benches, step);
criterion_main!(benches);
