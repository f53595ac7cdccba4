//! The RON scene format: what a user writes to describe a run (documented in docs/scenes.md).
//!
//! Parsing has three layers, each reporting where it can: RON syntax and types (line and
//! column from `ron`), each plugin item's own physical checks (run while it is deserialised,
//! so they get a position too), and whole-scene checks such as a body outside the domain
//! (reported with the body's name and the line it is declared on).

mod check;
pub mod overrides;
mod preset;

pub use preset::Preset;

use std::path::Path;
use std::sync::Arc;

use glam::DVec2;
use serde::{Deserialize, Serialize};

use crate::condition::Condition;
use crate::contact::Contact;
use crate::error::SceneError;
use crate::geometry::Shape;
use crate::material::MaterialSpec;
use crate::output::Output;
use crate::registry::{Named, Registries, with_registries};
use crate::shape_functions::Integration;

/// A whole scene file.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Used for the default output directory `out/<name>/`.
    pub name: String,
    /// Free text shown by `regolith check` (e.g. "coarse CI variant of ...").
    #[serde(default)]
    pub description: String,
    pub domain: Domain,
    pub time: TimeSettings,
    /// Body force per unit mass (m/s^2); default `(0.0, -9.81)`.
    #[serde(default = "default_gravity")]
    pub gravity: DVec2,
    pub walls: Walls,
    /// Shape-function scheme; default `CpdiFixed` (the paper's).
    #[serde(default)]
    pub integration: Integration,
    /// Where the velocity gradient comes from: `Usl` (the paper) or `Musl`; default `Usl`.
    #[serde(default)]
    pub update: StressUpdate,
    /// How the dilatation `tr L` is taken: `CellAveraged` (default) or `PerPoint`.
    #[serde(default)]
    pub dilatation: Dilatation,
    /// How bodies interact where they share grid nodes: `NoSlip` (default) or
    /// `Frictional(friction: mu)`.
    #[serde(default)]
    pub contact: Contact,
    /// How velocities go from the grid back to the points: `AffineFlip(relaxation: 25)` (the
    /// default), `Flip` (the paper's) or `Apic` (affine particle-in-cell); docs/numerics.md.
    #[serde(default)]
    pub transfer: Transfer,
    /// FLIP fraction of the point velocity update with `transfer: Flip`: 1 is pure FLIP (the
    /// paper), 0 pure PIC.
    #[serde(default = "default_flip")]
    pub flip: f64,
    pub bodies: Vec<BodySpec>,
    /// Divergence bounds; see [`Limits`].
    #[serde(default)]
    pub limits: Limits,
    /// Numerical preset (`Fast`, `Paper`, `Fine`) applied before the command line's
    /// overrides; none by default (the scene's own settings).
    #[serde(default)]
    pub preset: Option<Preset>,
    /// Extra outputs (e.g. `Snapshots(every: 0.01)`); `summary.json` and `trajectory.csv`
    /// are always written.
    #[serde(default)]
    pub outputs: Vec<Named<dyn Output>>,
    /// What the scene imposes on its bodies beyond material and shape (plugin items such as
    /// `Driven(body: "intruder", velocity: (0.0, -0.5))`); none by default.
    #[serde(default)]
    pub conditions: Vec<Named<dyn Condition>>,
    /// The plugins the scene was parsed against: their item catalogues, and the systems and
    /// resources they add to every simulation built from it. Not part of the file.
    #[serde(skip)]
    pub registries: Arc<Registries>,
}

fn default_gravity() -> DVec2 {
    DVec2::new(0.0, -9.81)
}

fn default_flip() -> f64 {
    1.0
}

/// The update-stress-last variant (docs/numerics.md).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
pub enum StressUpdate {
    /// `L` from the updated grid velocity `(mv)/m` (the paper's choice). With `Linear`
    /// integration, nodes of tiny mass make it unstable (docs/numerics.md).
    #[default]
    Usl,
    /// Modified USL: `L` from the updated point velocities mapped back to the grid, which
    /// stays bounded at nodes of tiny mass; costs one more scatter and gather per step.
    Musl,
}

/// The grid-to-point velocity transfer (docs/numerics.md, "Dense flow").
///
/// Every transfer updates a point's velocity the same way: its FLIP update `v + dt a_grid`
/// is pulled part of the way to the grid's velocity at the point ([`Transfer::pull`]). They
/// differ in how far, and in whether the point hands the grid an affine field too.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
pub enum Transfer {
    /// FLIP (the paper's transfer): each point keeps its velocity and adds the grid's
    /// acceleration, optionally blended with PIC by `flip` at every step, a damping whose
    /// size is set by the step.
    Flip,
    /// APIC (Jiang et al. 2015): each point takes the grid velocity at its position and the
    /// affine field `C_p` around it, which it hands back to the grid in the next scatter.
    /// Conserves linear and angular momentum and reproduces affine fields; but the
    /// projection is made at every step, so what it dissipates grows as the step shrinks
    /// (the impact's depth falls from 0.31 to 0.18 m between CFL 1 and 0.05).
    Apic,
    /// The default (`relaxation: 25`): APIC's affine scatter with FLIP's velocity update,
    /// whose departure from the grid's velocity relaxes over `relaxation` p-wave crossings
    /// of a cell, `tau = relaxation h / c` (the unit of the CFL number, so a step removes
    /// the fraction `1 - exp(-CFL / relaxation)`). The damping is fixed in time, so the
    /// answer converges in the step, and `tau` shrinks with the cell.
    AffineFlip { relaxation: f64 },
}

/// The default transfer's relaxation, in p-wave crossings of a cell (docs/numerics.md,
/// "Affine FLIP": how it was chosen).
pub const DEFAULT_RELAXATION: f64 = 25.0;

impl Default for Transfer {
    fn default() -> Self {
        Transfer::AffineFlip {
            relaxation: DEFAULT_RELAXATION,
        }
    }
}

impl Transfer {
    /// Whether points carry an affine field `C_p` and hand it to the grid.
    pub fn affine(&self) -> bool {
        !matches!(self, Transfer::Flip)
    }

    /// The fraction of the way from its FLIP update to the grid's velocity that a point's
    /// velocity moves in a step `dt`, for a body of p-wave speed `c` on cells of size `h`:
    /// `1 - flip` with FLIP, 1 with APIC, `1 - exp(-dt c / (relaxation h))` with affine FLIP.
    pub fn pull(&self, flip: f64, dt: f64, h: f64, c: f64) -> f64 {
        match *self {
            Transfer::Flip => 1.0 - flip,
            Transfer::Apic => 1.0,
            Transfer::AffineFlip { relaxation } => -(-dt * c / (relaxation * h)).exp_m1(),
        }
    }
}

/// How the volumetric part of the velocity gradient is taken (docs/numerics.md).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
pub enum Dilatation {
    /// Each point's own `tr L` (the paper's formulation).
    PerPoint,
    /// The volume-weighted mean `tr L` of the points in the point's cell; removes the
    /// checkerboard pressure mode of several points per cell.
    #[default]
    CellAveraged,
}

/// The rectangular domain and its grid of square cells.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Domain {
    /// Lower-left corner; default `(0.0, 0.0)`.
    #[serde(default)]
    pub origin: DVec2,
    /// Width and height (m).
    pub size: DVec2,
    /// Cells along x and y; cells must be square.
    pub cells: (usize, usize),
}

/// End time, time step and output interval.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TimeSettings {
    /// Simulated end time (s).
    pub end: f64,
    pub step: TimeStep,
    /// Interval between rows of `trajectory.csv` (s).
    pub output_every: f64,
    /// Run a `Fixed` step above the CFL limit anyway (with a warning) instead of refusing
    /// the scene; default false. The command line's `--allow-unstable` sets it.
    #[serde(default)]
    pub allow_unstable: bool,
}

/// Bounds past which a run is declared diverging and stopped.
#[derive(Clone, Copy, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Limits {
    /// Largest total kinetic energy (J per metre of thickness). Default: ten times the
    /// kinetic plus potential energy after the first step, plus the kinetic energy of every
    /// body moving at 1% of its p-wave speed (the energy of a 1% elastic strain).
    #[serde(default)]
    pub max_kinetic_energy: Option<f64>,
}

/// How the time step is chosen.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum TimeStep {
    /// A fixed step (s).
    Fixed(f64),
    /// `dt = C h / max_b (c_b + max |v_p|)`, recomputed every step.
    Cfl(f64),
}

impl TimeStep {
    /// The step the rule gives on cells of size `h` for the fastest signal `signal`
    /// (`c + |v|`); `otherwise` when a CFL rule has no signal to go by (nothing moves and no
    /// material has a wave speed).
    pub fn dt(self, h: f64, signal: f64, otherwise: f64) -> f64 {
        match self {
            TimeStep::Fixed(dt) => dt,
            TimeStep::Cfl(c) if signal > 0.0 => c * h / signal,
            TimeStep::Cfl(_) => otherwise,
        }
    }
}

/// The four sides of the domain.
#[derive(Clone, Copy, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Walls {
    pub left: Wall,
    pub right: Wall,
    pub bottom: Wall,
    pub top: Wall,
}

/// Boundary condition on one side.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
pub enum Wall {
    /// No constraint: material leaving the domain stops the run.
    Free,
    /// No constraint, and material crossing it leaves the simulation: its points are
    /// retired (mass, velocity, stress set to zero, parked on the boundary) and counted in
    /// `summary.json` (an open box top that a splash may leave).
    Open,
    /// Frictionless: the normal velocity is zero, the tangential one free.
    Slip,
    /// Both velocity components are zero.
    NoSlip,
    /// Wraps to the opposite side (which must be periodic too).
    Periodic,
}

/// One body.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BodySpec {
    pub name: String,
    pub shape: Named<dyn Shape>,
    pub material: Named<dyn MaterialSpec>,
    /// Material points per cell along each direction (2 gives the paper's 2x2 at quadrant
    /// centres); default 2.
    #[serde(default = "default_ppc")]
    pub points_per_cell: usize,
    /// Initial velocity (m/s); default zero.
    #[serde(default)]
    pub velocity: DVec2,
    /// Initial stress; default `None`.
    #[serde(default)]
    pub initial_stress: InitialStress,
    /// With `Lithostatic`: `T_xx = T_zz = k T_yy` with this `k` instead of the material's
    /// own ratio (1 for the granular materials, `nu / (1 - nu)` for `LinearElastic`). A
    /// free-standing column is in equilibrium with `k = 0`.
    #[serde(default)]
    pub lateral_stress_ratio: Option<f64>,
    /// Whether the body's centre of mass goes into `trajectory.csv`; default false.
    #[serde(default)]
    pub tracked: bool,
}

fn default_ppc() -> usize {
    2
}

/// How a body's stress starts.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
pub enum InitialStress {
    /// Stress free.
    #[default]
    None,
    /// In equilibrium under gravity (which must point along -y): `T_yy = -rho g (H - y)` below
    /// the body's top surface `H` at each x, lateral components from the material's ratio.
    Lithostatic,
}

/// The RON dialect of regolith's files: optional values are written bare
/// (`critical_density: 1011.2`, `jobs: 2`), not `Some(..)`.
pub fn ron_options() -> ron::Options {
    ron::Options::default().with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME)
}

impl Scene {
    /// Parses RON text; `origin` names the file in messages.
    pub fn parse(
        text: &str,
        origin: &str,
        registries: &Arc<Registries>,
    ) -> Result<Scene, SceneError> {
        let mut scene: Scene = with_registries(registries, || ron_options().from_str(text))
            .map_err(|e| {
                SceneError::at(
                    origin,
                    e.span.start.line,
                    e.span.start.col,
                    e.code.to_string(),
                )
            })?;
        scene.registries = registries.clone();
        scene.check(text, origin)?;
        Ok(scene)
    }

    /// Reads and parses a scene file after applying `key.path=value` overrides (the command
    /// line's `--set`). Values are RON (`0.5`, `(0.0, -3.5)`, `Cfl(0.2)`, `"name"`); list
    /// items are addressed by index or, for items with a `name`, by name
    /// (`bodies.intruder.velocity=(0, -3)`). Returns the scene and the text it was read from.
    pub fn load(
        path: &Path,
        sets: &[String],
        registries: &Arc<Registries>,
    ) -> Result<(Scene, String), SceneError> {
        let origin = path.display().to_string();
        let written = std::fs::read_to_string(path)
            .map_err(|e| SceneError::file(&origin, format!("cannot read the scene: {e}")))?;
        let apply = |sets: &[String]| {
            let mut text = written.clone();
            for s in sets {
                text = overrides::set_in_text(&text, s)
                    .map_err(|e| SceneError::file(&format!("{origin} (--set {s})"), e))?;
            }
            let origin = if sets.is_empty() {
                origin.clone()
            } else {
                format!("{origin} (after --set {})", sets.join(" --set "))
            };
            Ok::<_, SceneError>((Scene::parse(&text, &origin, registries)?, text))
        };
        let (scene, text) = apply(sets)?;
        let Some(preset) = scene.preset else {
            return Ok((scene, text));
        };
        // The preset's overrides go first so that explicit ones still win.
        let mut all = preset.overrides(&scene);
        all.extend(sets.iter().cloned());
        apply(&all)
    }

    /// Adds `output` after checking it, replacing the scene's own output of the same name
    /// (the command line's `--rrd` or `--vtk`); returns whether one was replaced.
    pub fn set_output(&mut self, output: Box<dyn Output>) -> Result<bool, String> {
        output
            .validate()
            .map_err(|e| format!("{}: {e}", output.name()))?;
        let before = self.outputs.len();
        self.outputs.retain(|o| o.name() != output.name());
        let replaced = self.outputs.len() < before;
        self.outputs.push(Named(output));
        Ok(replaced)
    }
}
