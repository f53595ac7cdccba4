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
use serde::Deserialize;

use crate::condition::Condition;
use crate::contact::{Contact, NoSlip};
use crate::error::SceneError;
use crate::field::Field;
use crate::integration::ShapeFunctions;
use crate::obstacle::ObstacleSpec;
use crate::output::Output;
use crate::registry::{Named, Registries, with_registries};
use crate::shape_functions::CpdiFixed;
use crate::step::spacing::Spacing;
use crate::transfer::{AffineFlip, Transfer};

pub use crate::resources::{Dilatation, Segment, Side, StressUpdate, TimeStep, Wall, Walls};
use crate::scene_view::body_named;
pub use crate::scene_view::{BodySpec, InitialStress, SceneView};

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
    /// Fixed boundaries of any shape inside the domain (a hopper's walls), each
    /// `(shape: Polygon(..), wall: Frictional(friction: mu))`; none by default
    /// (`crate::obstacle`).
    #[serde(default)]
    pub obstacles: Vec<ObstacleSpec>,
    /// Shape-function scheme: `CpdiFixed` (the paper's, default), `Linear` or
    /// `QuadraticBspline`, or a plugin's.
    #[serde(default = "default_integration")]
    pub integration: Named<dyn ShapeFunctions>,
    /// Where the velocity gradient comes from: `Usl` (the paper) or `Musl`; default `Usl`.
    #[serde(default)]
    pub update: StressUpdate,
    /// How the dilatation `tr L` is taken: `CellAveraged` (default) or `PerPoint`.
    #[serde(default)]
    pub dilatation: Dilatation,
    /// Whether points are moved off over-filled nodes after each move: `Off` (default) or
    /// `DeltaCorrection(alpha: 1.0, max_shift: 0.1)` (Baumgarten & Kamrin 2023;
    /// `step::spacing`, docs/numerics.md).
    #[serde(default)]
    pub spacing: Spacing,
    /// How bodies interact where they share grid nodes: `NoSlip` (default) or
    /// `Frictional(friction: mu)`, or a plugin's law.
    #[serde(default = "default_contact")]
    pub contact: Named<dyn Contact>,
    /// How velocities go from the grid back to the points: `AffineFlip(relaxation: 25)` (the
    /// default), `Flip` (the paper's) or `Apic` (affine particle-in-cell); docs/numerics.md.
    #[serde(default = "default_transfer")]
    pub transfer: Named<dyn Transfer>,
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
    /// Fields the bodies carry beyond those their materials bring (plugin items such as a
    /// diffused tracer, `Tracer(body: "layer", diffusivity: 1e-4, marked: ..)`; module
    /// `field`); none by default.
    #[serde(default)]
    pub fields: Vec<Named<dyn Field>>,
    /// The plugins the scene was parsed against: their item catalogues, and the systems and
    /// resources they add to every simulation built from it. Not part of the file.
    #[serde(skip)]
    pub registries: Arc<Registries>,
}

fn default_integration() -> Named<dyn ShapeFunctions> {
    Named(Box::new(CpdiFixed))
}

fn default_contact() -> Named<dyn Contact> {
    Named(Box::new(NoSlip))
}

fn default_transfer() -> Named<dyn Transfer> {
    Named(Box::new(AffineFlip::default()))
}

fn default_gravity() -> DVec2 {
    DVec2::new(0.0, -9.81)
}

fn default_flip() -> f64 {
    1.0
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

/// The RON dialect of regolith's files: optional values are written bare
/// (`critical_density: 1011.2`, `jobs: 2`), not `Some(..)`.
pub fn ron_options() -> ron::Options {
    ron::Options::default().with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME)
}

/// RON's messages name the Rust type a field belongs to ("missing field named `end` in
/// `TimeSettings`"); the user wrote the scene's keys, so those are named instead.
fn scene_names(message: &str) -> String {
    const NAMES: [(&str, &str); 6] = [
        ("`BodySpec`", "a body of `bodies`"),
        ("`TimeSettings`", "`time`"),
        ("`Domain`", "`domain`"),
        ("`Limits`", "`limits`"),
        ("`Walls`", "`walls`"),
        ("`Scene`", "the scene"),
    ];
    NAMES
        .iter()
        .fold(message.to_string(), |m, (rust, user)| m.replace(rust, user))
}

impl Scene {
    /// The body called `name`, or a message naming the scene's bodies.
    pub fn body(&self, name: &str) -> Result<&BodySpec, String> {
        body_named(&self.bodies, name)
    }

    /// The fields body `body` carries, in the order they are attached: those its material
    /// brings, then those the scene lists for it (module `field`).
    pub fn fields_of(&self, body: &BodySpec) -> Vec<Box<dyn Field>> {
        let listed = self.fields.iter().map(|f| &f.0);
        let listed = listed.filter(|f| f.body() == Some(body.name.as_str()));
        let mut fields = body.material.fields();
        fields.extend(listed.cloned());
        fields
    }

    /// What an item (an output, a condition) is checked against: the bodies and the grid.
    pub fn view(&self) -> SceneView<'_> {
        SceneView::new(&self.bodies, self.grid())
    }

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
                    scene_names(&e.code.to_string()),
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
        let grid_given = sets.iter().any(|s| {
            let key = s.split_once('=').map_or("", |(key, _)| key.trim());
            key == "domain" || key == "domain.cells"
        });
        let mut all = preset
            .overrides(&scene, grid_given)
            .map_err(|e| check::near(&text, &origin, "preset:", e))?;
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
