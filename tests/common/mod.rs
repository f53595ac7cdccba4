//! Helpers shared by the integration tests.
#![allow(dead_code)]

pub mod measure;

use std::path::PathBuf;

use regolith::{Regolith, Scene, Simulation};

/// The repository's root: these helpers serve the engine's tests (root package) and the
/// lab's (`lab/`), which include this file by path.
pub fn repository() -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    if dir.join("scenes").is_dir() {
        dir
    } else {
        dir.parent()
            .expect("lab/ sits in the repository")
            .to_path_buf()
    }
}

/// Path of a shipped scene.
pub fn scene_path(name: &str) -> PathBuf {
    repository().join("scenes").join(format!("{name}.ron"))
}

/// Loads a shipped scene with `--set`-style overrides.
pub fn scene(name: &str, sets: &[&str]) -> Scene {
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    Scene::load(&scene_path(name), &sets, &Regolith::default().registries())
        .unwrap_or_else(|e| panic!("{e}"))
        .0
}

/// The full model at a coarse resolution: a PS-1 bed, an elastic intruder, CPDI,
/// frictional contact, cell-averaged dilatation.
pub fn full_model_coarse() -> Scene {
    full_model_coarse_with(&[])
}

/// `full_model_coarse` with further `--set`-style overrides.
pub fn full_model_coarse_with(extra: &[&str]) -> Scene {
    let mut sets = vec![
        "domain.cells=(40, 40)",
        "time=(end: 1.0, step: Cfl(0.5), output_every: 1.0)",
        "bodies.bed.material=MuI(youngs_modulus: 2.0e7, poisson_ratio: 0.45, grain_density: 1280.0, packing_fraction: 0.79, grain_diameter: 5.0e-3, mu_s: 0.32, mu_2: 0.598, i_0: 0.278)",
    ];
    sets.extend_from_slice(extra);
    scene("bench_contact", &sets)
}

/// The fingerprints of the bed and the disc of `full_model_coarse`, to compare two runs
/// bit for bit.
pub fn bed_and_disc_fingerprints(sim: &mut Simulation) -> [u64; 2] {
    ["bed", "disc"].map(|name| sim.points(name).unwrap().fingerprint())
}

/// Runs `f` on a rayon pool of `threads` threads.
pub fn with_threads<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
        .install(f)
}

/// Writes `sim`'s checkpoint (of `scene`) to a temporary file and restores it into a fresh
/// simulation, as `regolith resume` does.
pub fn checkpoint_and_restore(sim: &mut Simulation, scene: &regolith::Scene) -> Simulation {
    use regolith::checkpoint::Checkpoint;
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("checkpoint.bin");
    Checkpoint::capture(sim, scene, "scene.ron", &[])
        .write(&path)
        .unwrap();
    let mut resumed = Simulation::unobserved(scene);
    Checkpoint::read(&path)
        .unwrap()
        .restore(&mut resumed, scene)
        .unwrap();
    resumed
}

/// A small deterministic generator (xorshift), uniform in [-1, 1).
pub struct Rng(pub u64);
impl Rng {
    pub fn next(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    }
    pub fn vec(&mut self) -> regolith::glam::DVec2 {
        regolith::glam::DVec2::new(self.next(), self.next())
    }
}

/// Least-squares acceleration of x(t) = x0 + v0 t + a t^2 / 2 (normal equations solved by
/// Cramer's rule).
pub fn fitted_acceleration(t: &[f64], x: &[f64]) -> f64 {
    let mut m = [[0.0; 3]; 3];
    let mut r = [0.0; 3];
    for (&ti, &xi) in t.iter().zip(x) {
        let row = [1.0, ti, 0.5 * ti * ti];
        for (i, ri) in row.iter().enumerate() {
            r[i] += ri * xi;
            for (j, rj) in row.iter().enumerate() {
                m[i][j] += ri * rj;
            }
        }
    }
    let det = |a: [[f64; 3]; 3]| {
        a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1])
            - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0])
            + a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0])
    };
    let mut third = m;
    for i in 0..3 {
        third[i][2] = r[i];
    }
    det(third) / det(m)
}
