//! `regolith._regolith`: the compiled half of the Python package (the other half,
//! `regolith/__init__.py`, reads run directories with numpy alone).
//!
//! It wraps the library as the command line uses it: scenes are loaded with the default
//! plugins and `--set`-style overrides, a run writes the same files as `regolith run`, and a
//! `Simulation` steps the same schedule, so a scene stepped from Python reaches the same
//! `state_hash` as the command line. Errors become Python exceptions carrying the library's
//! one-line message (`file:line:col: what was expected` for scenes).

use std::path::PathBuf;
use std::sync::Arc;

use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1};
use pyo3::create_exception;
use pyo3::exceptions::{PyKeyError, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyModule};

use regolith::body::{PointStates, Points};
use regolith::error::Error;
use regolith::registry::Registries;
use regolith::run::{CheckpointEvery, Provenance, run_scene, summarize};
use regolith::scene::Scene as CoreScene;
use regolith::sim::Simulation as CoreSimulation;

create_exception!(
    _regolith,
    SceneError,
    PyValueError,
    "A scene that cannot run: the message says where (file:line:col) and what was expected."
);
create_exception!(
    _regolith,
    RunError,
    PyRuntimeError,
    "A run that stopped on a fault (non-finite state, escaped point, a file not written)."
);

fn scene_error(e: impl std::fmt::Display) -> PyErr {
    SceneError::new_err(e.to_string())
}

fn run_error(e: impl std::fmt::Display) -> PyErr {
    RunError::new_err(e.to_string())
}

/// The plugins of the `regolith` command, less the Rerun recorder (the package does not
/// link the Rerun SDK).
fn registries() -> Arc<Registries> {
    regolith::Regolith::default().registries()
}

/// A scene read from a file, with overrides applied and every check passed.
#[pyclass(unsendable, module = "regolith")]
#[derive(Clone)]
struct Scene {
    scene: CoreScene,
    /// The text that runs (overrides applied), written to the run's scene.ron.
    #[pyo3(get)]
    text: String,
    #[pyo3(get)]
    file: String,
    #[pyo3(get)]
    overrides: Vec<String>,
}

impl Scene {
    /// Where the scene came from, for the run's summary.
    fn provenance(&self) -> Provenance<'_> {
        Provenance {
            file: &self.file,
            text: &self.text,
            overrides: &self.overrides,
        }
    }
}

#[pymethods]
impl Scene {
    #[getter]
    fn name(&self) -> String {
        self.scene.name.clone()
    }

    /// The bodies' names in scene order.
    #[getter]
    fn bodies(&self) -> Vec<String> {
        self.scene.bodies.iter().map(|b| b.name.clone()).collect()
    }

    fn __repr__(&self) -> String {
        format!("<regolith.Scene {:?} from {}>", self.scene.name, self.file)
    }
}

/// Reads the scene at `path` with `overrides` (`"path.to.key=value"`, as `--set`).
#[pyfunction]
#[pyo3(signature = (path, overrides = None))]
fn load_scene(path: PathBuf, overrides: Option<Vec<String>>) -> PyResult<Scene> {
    let overrides = overrides.unwrap_or_default();
    let (scene, text) = CoreScene::load(&path, &overrides, &registries()).map_err(scene_error)?;
    Ok(Scene {
        scene,
        text,
        file: path.display().to_string(),
        overrides,
    })
}

/// Runs `scene` to its end writing `out` as `regolith run` does; returns summary.json's
/// text. A run that stops on a fault raises `RunError` after writing its files.
#[pyfunction]
#[pyo3(signature = (scene, out, checkpoint_every = None))]
fn run_to_dir(scene: &Scene, out: PathBuf, checkpoint_every: Option<u64>) -> PyResult<String> {
    let summary = run_scene(
        &scene.scene,
        &scene.provenance(),
        &out,
        CheckpointEvery(checkpoint_every),
        &mut |_: &regolith::resources::Clock| {},
    )
    .map_err(|e| match e {
        Error::Scene(e) => scene_error(e),
        other => run_error(other),
    })?;
    serde_json::to_string(&summary).map_err(run_error)
}

/// A simulation stepped from Python, its points read as numpy arrays (copies).
#[pyclass(unsendable, module = "regolith")]
struct Simulation {
    sim: CoreSimulation,
    scene: Scene,
}

impl Simulation {
    /// What the body called `name` has, or a `KeyError`.
    fn body<'a, T>(found: Option<&'a T>, name: &str) -> PyResult<&'a T> {
        found.ok_or_else(|| PyKeyError::new_err(format!("no body called {name:?}")))
    }
}

/// An n x 2 array of vectors.
fn vectors<'py>(py: Python<'py>, v: &[regolith::glam::DVec2]) -> Bound<'py, PyAny> {
    let flat: Vec<f64> = v.iter().flat_map(|x| [x.x, x.y]).collect();
    Array2::from_shape_vec((v.len(), 2), flat)
        .expect("two values per vector")
        .into_pyarray(py)
        .into_any()
}

#[pymethods]
impl Simulation {
    /// A simulation of `scene` at t = 0; with `out`, it writes that scene's outputs there.
    #[new]
    #[pyo3(signature = (scene, out = None))]
    fn new(scene: &Scene, out: Option<PathBuf>) -> PyResult<Self> {
        let sim = match &out {
            Some(dir) => {
                std::fs::create_dir_all(dir).map_err(run_error)?;
                CoreSimulation::with_output(&scene.scene, dir).map_err(run_error)?
            }
            None => CoreSimulation::new(&scene.scene),
        };
        Ok(Simulation {
            sim,
            scene: scene.clone(),
        })
    }

    /// Takes `n` steps, fewer if the end time comes first; returns the steps taken.
    #[pyo3(signature = (n = 1))]
    fn step(&mut self, n: u64) -> PyResult<u64> {
        let mut taken = 0;
        while taken < n && !self.sim.finished() {
            self.sim.step().map_err(run_error)?;
            taken += 1;
        }
        Ok(taken)
    }

    /// Steps until the simulated time reaches `time` (or the end time); returns the steps.
    fn run_until(&mut self, py: Python<'_>, time: f64) -> PyResult<u64> {
        let mut taken = 0;
        while self.sim.clock().time < time && !self.sim.finished() {
            self.sim.step().map_err(run_error)?;
            taken += 1;
            if taken % 256 == 0 {
                py.check_signals()?;
            }
        }
        Ok(taken)
    }

    /// Whether the scene's end time has been reached.
    #[getter]
    fn finished(&self) -> bool {
        self.sim.finished()
    }

    /// Simulated time (s).
    #[getter]
    fn time(&self) -> f64 {
        self.sim.clock().time
    }

    /// Steps taken.
    #[getter]
    fn steps(&self) -> u64 {
        self.sim.clock().step
    }

    /// The bodies' names in scene order.
    #[getter]
    fn bodies(&mut self) -> Vec<String> {
        self.sim
            .bodies()
            .into_iter()
            .map(|(b, ..)| b.name)
            .collect()
    }

    /// The points of body `name` as numpy arrays: position and velocity (n x 2), stress
    /// (n x 4: xx, yy, xy, zz; Pa, tension positive), pressure, mass, volume,
    /// plastic_strain_rate, plastic_strain (n) and phase (n, uint8: 0 solid, 1 flowing,
    /// 2 disconnected).
    fn points<'py>(&mut self, py: Python<'py>, name: &str) -> PyResult<Bound<'py, PyDict>> {
        let p: &Points = Self::body(self.sim.points(name), name)?;
        let d = PyDict::new(py);
        d.set_item("position", vectors(py, &p.position))?;
        d.set_item("velocity", vectors(py, &p.velocity))?;
        let stress: Vec<f64> = p
            .stress
            .iter()
            .flat_map(|s| [s.xx, s.yy, s.xy, s.zz])
            .collect();
        let stress = Array2::from_shape_vec((p.len(), 4), stress).expect("four per point");
        d.set_item("stress", stress.into_pyarray(py))?;
        let pressure: Vec<f64> = p.stress.iter().map(|s| s.pressure()).collect();
        d.set_item("pressure", PyArray1::from_vec(py, pressure))?;
        d.set_item("mass", PyArray1::from_slice(py, &p.mass))?;
        d.set_item("volume", PyArray1::from_slice(py, &p.volume))?;
        let st: &PointStates = Self::body(self.sim.point_states(name), name)?;
        d.set_item(
            "plastic_strain_rate",
            PyArray1::from_slice(py, &st.plastic_strain_rate),
        )?;
        d.set_item(
            "plastic_strain",
            PyArray1::from_slice(py, &st.plastic_strain),
        )?;
        let phase: Vec<u8> = st.phase.iter().map(|f| f.code()).collect();
        d.set_item("phase", PyArray1::from_vec(py, phase))?;
        Ok(d)
    }

    /// Each body's `state_hash`, as summary.json gives it: equal hashes, bitwise equal
    /// states.
    fn state_hash(&mut self) -> Vec<(String, String)> {
        let names = self.bodies();
        names
            .into_iter()
            .map(|n| {
                // every body listed by `bodies` has points
                let hash = self.sim.state_hash(&n).unwrap_or_default();
                (n, hash)
            })
            .collect()
    }

    /// The summary of the simulation as it stands, as summary.json would hold it (status
    /// "completed" once the end time is reached, else "running"), as a dict.
    fn summary<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let status = if self.sim.finished() {
            "completed"
        } else {
            "running"
        };
        let from = self.scene.provenance();
        let summary = summarize(&mut self.sim, &self.scene.scene, &from, 0.0, status, None);
        let text = serde_json::to_string(&summary).map_err(run_error)?;
        py.import("json")?.call_method1("loads", (text,))
    }

    fn __repr__(&self) -> String {
        format!(
            "<regolith.Simulation {:?} at t = {} s, step {}>",
            self.scene.scene.name,
            self.sim.clock().time,
            self.sim.clock().step
        )
    }
}

#[pymodule]
fn _regolith(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Scene>()?;
    m.add_class::<Simulation>()?;
    m.add_function(wrap_pyfunction!(load_scene, m)?)?;
    m.add_function(wrap_pyfunction!(run_to_dir, m)?)?;
    m.add("SceneError", m.py().get_type::<SceneError>())?;
    m.add("RunError", m.py().get_type::<RunError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
