//! Criterion benchmarks of the step's heavy systems and of whole steps, on the benchmark
//! scenes (30 k points, 100 x 100 cells). Run: cargo bench --bench step -- --quick

use criterion::{Criterion, criterion_group, criterion_main};
use regolith::bevy_ecs::system::RunSystemOnce;
use regolith::contact::frictional;
use regolith::material::granular::MuI;
use regolith::material::update_stress;
use regolith::shape_functions::{CpdiFixed, Footprint, Scheme};
use regolith::sim::on_worker;
use regolith::step::scatter_gather::{affine_to_particle, particle_to_grid};
use regolith::step::{locate_points, update_grid};
use regolith::{Regolith, Scene, Simulation};

const PS1: &str = "bodies.bed.material=MuI(youngs_modulus: 2.0e7, poisson_ratio: 0.45, grain_density: 1280.0, packing_fraction: 0.79, grain_diameter: 5.0e-3, mu_s: 0.32, mu_2: 0.598, i_0: 0.278)";

fn scene(name: &str, sets: &[&str]) -> Scene {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("../scenes/{name}.ron"));
    let mut sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    sets.push("time.end=1.0".to_string());
    Scene::load(&path, &sets, &Regolith::default().registries())
        .unwrap()
        .0
}

fn systems(c: &mut Criterion) {
    // The full model: granular bed, elastic intruder, CPDI, frictional contact.
    let mut sim = Simulation::new(&scene("bench_contact", &[PS1]));
    for _ in 0..3 {
        sim.step().unwrap();
    }
    let world = &mut sim.world;
    c.bench_function("locate_cpdi_30k", |b| {
        b.iter(|| on_worker(|| world.run_system_once(locate_points::<CpdiFixed>).unwrap()))
    });
    c.bench_function("p2g_30k", |b| {
        b.iter(|| on_worker(|| world.run_system_once(particle_to_grid).unwrap()))
    });
    // The default transfer (affine FLIP): the USL gather with the affine field.
    c.bench_function("g2p_affine_30k", |b| {
        b.iter(|| {
            on_worker(|| {
                world
                    .run_system_once(affine_to_particle::<CpdiFixed>)
                    .unwrap()
            })
        })
    });
    c.bench_function("constitutive_mui_30k", |b| {
        b.iter(|| on_worker(|| world.run_system_once(update_stress::<MuI>).unwrap()))
    });
    c.bench_function("grid_update_100x100_two_bodies", |b| {
        b.iter(|| on_worker(|| world.run_system_once(update_grid).unwrap()))
    });
    c.bench_function("contact_frictional_100x100", |b| {
        b.iter(|| on_worker(|| world.run_system_once(frictional).unwrap()))
    });
}

/// The footprints of 30 k points, serially: the shape-function cost without the
/// parallel loop around it.
fn footprints(c: &mut Criterion) {
    let mut sim = Simulation::new(&scene("bench_contact", &[PS1]));
    let grid = sim.grid().clone();
    let points = sim.points("bed").unwrap().clone();
    let mut out = vec![Footprint::default(); points.len()];
    c.bench_function("footprints_cpdi_30k_serial", |b| {
        b.iter(|| {
            for ((f, x), &a) in out.iter_mut().zip(&points.position).zip(&points.half_width) {
                *f = Footprint::new::<CpdiFixed>(&grid, *x, a);
            }
            std::hint::black_box(&out);
        })
    });
    c.bench_function("axis_weights_cpdi_30k_serial", |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for (x, &a) in points.position.iter().zip(&points.half_width) {
                let rel = (*x - grid.origin) / grid.cell_size;
                let al = a / grid.cell_size;
                let ax = CpdiFixed::axis(rel.x, al, grid.cells[0], false);
                let ay = CpdiFixed::axis(rel.y, al, grid.cells[1], false);
                acc += ax.w[1] + ay.dw[2] + ax.base as f64;
            }
            std::hint::black_box(acc);
        })
    });
}

fn steps(c: &mut Criterion) {
    for (label, name, sets) in [
        (
            "step_elastic_linear_30k",
            "bench_elastic_block",
            vec!["integration=Linear"],
        ),
        ("step_elastic_cpdi_30k", "bench_elastic_block", vec![]),
        ("step_full_model_30k", "bench_contact", vec![PS1]),
    ] {
        let mut sim = Simulation::new(&scene(name, &sets));
        c.bench_function(label, |b| b.iter(|| on_worker(|| sim.step().unwrap())));
    }
}

criterion_group!(benches, footprints, systems, steps);
criterion_main!(benches);
