//! Rerun recordings of regolith runs: `Rerun(..)` in a scene's `outputs`, or the `regolith`
//! command's `--rrd FILE` / `--spawn` flags, which add the same output.
//!
//! This crate is the only place rerun is linked, so the core crate (`regolith`) builds and
//! tests in seconds; the workspace's `regolith` command (cli/) adds [`RerunPlugin`]. The
//! recorder is an ordinary output plugin: it adds one system to the Output set, which does
//! nothing between recorded steps, and nothing of rerun runs unless a scene or a flag asks.
//!
//! What is recorded (entity paths and timelines are also listed in the README):
//! * timelines `sim_time` (simulated seconds) and `step`;
//! * `world/<body>/points`: every material point of the body (`Points2D`: position, a radius
//!   from its area `sqrt(V / pi)`, a colour from the chosen field) with the field's value per
//!   point as the component `<field>` (selecting a point in the viewer shows it);
//! * `world/domain`: the box outline (static);
//! * `world/legend/<body>` (pressure, speed: each body on its own scale, the top of the
//!   scale as the component `scale_top`) or `world/legend/all` (the fixed log scales, the
//!   phase and body swatches): the colour legend, beside the domain;
//! * `world` and `grid` carry a static mirror in y (`Transform3D`, scale (1, -1, 1)):
//!   Rerun's 2D views draw y downward, the simulation's y points up;
//! * `plots/<body>/kinetic_energy` for every body; for tracked bodies also
//!   `plots/<body>/depth` (downward displacement of the centre of mass since the first
//!   frame: t = 0, or for a recording first asked for when a run resumed, that time),
//!   `plots/<body>/velocity/{x,y}`, `plots/<body>/acceleration/{x,y}` (centre-of-mass velocity
//!   differenced between recorded frames) and `plots/<body>/contact_force/{x,y}` (the force
//!   the other bodies exert through contact, N per metre of thickness);
//!   `plots/time_step`;
//! * with `grid: true`: `grid/<body>/velocity` (arrows from each node with mass, showing the
//!   displacement over 10 ms) and `grid/<body>/mass` (nodes coloured by mass, with the
//!   nodal mass per node);
//! * `scene`: the scene text and the resolved setup (static, Markdown).
//!
//! The layout (points beside the plots, the scene document in a tab) is sent with the
//! recording and activated, so the viewer opens arranged rather than in its automatic grid.

mod colour;
mod document;
mod legend;
mod record;

use regolith::bevy_ecs::prelude::*;
use regolith::carry::{Carried, carried, restored};
use regolith::output::Output;
use regolith::output::summary::Section;
use regolith::plugin::{Install, Plugin, Regolith};
use regolith::registry::Item;
use regolith::step::StepSet;
use serde::Deserialize;

pub use colour::{Field, upper_percentile};
/// The rerun crate this recorder was built with (for reading recordings back).
pub use rerun;

/// The recorder's scene parameters: `Rerun(file: "run.rrd", every: 10, color: Pressure)`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Rerun {
    /// The .rrd file to write; a relative path is taken inside the run's output directory.
    #[serde(default)]
    pub file: Option<String>,
    /// Also stream to a Rerun viewer started from PATH (`rerun`, same version as the crate).
    #[serde(default)]
    pub spawn: bool,
    /// Record every this many steps; by default at the scene's `time.output_every`.
    #[serde(default)]
    pub every: Option<u64>,
    /// The field the points are coloured by.
    #[serde(default)]
    pub color: Field,
    /// Also record nodal velocities and masses.
    #[serde(default)]
    pub grid: bool,
}

impl Item for Rerun {
    const NAME: &'static str = "Rerun";
    fn validate(&self) -> Result<(), String> {
        if self.file.is_none() && !self.spawn {
            return Err("give a file (an .rrd path) or spawn: true, or both".into());
        }
        if self.file.as_deref().is_some_and(str::is_empty) {
            return Err("file must not be empty".into());
        }
        if self.every == Some(0) {
            return Err("every must be at least 1 step".into());
        }
        Ok(())
    }
}

impl Output for Rerun {
    fn install(&self, sim: &mut Install) {
        sim.insert_resource(record::Recorder::new(self.clone()));
        sim.add_systems(StepSet::Output, record::record);
    }

    /// The recording's id, the file's length and what the plots difference against: a
    /// resumed run appends to the same recording (`record` module docs).
    fn save(&self, world: &World) -> Carried {
        carried(&world.resource::<record::Recorder>().saved())
    }

    fn restore(&self, world: &mut World, state: &[u8]) -> Result<(), String> {
        let saved = restored(state)?;
        world.resource_mut::<record::Recorder>().restore(saved);
        Ok(())
    }

    /// `"recording"`: the file's absolute path, and the run's last lines say where it is
    /// and how to open it.
    fn summary(&self, world: &World) -> Section {
        let Some(path) = world.resource::<record::Recorder>().file_path() else {
            return Section::default();
        };
        let path = std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
        let mut section = Section::entry("recording", path.display().to_string().into());
        section.headline = Some(format!(
            "recording: {} (open it with: rerun '{}')",
            path.display(),
            path.display()
        ));
        section
    }
}

/// Registers the `Rerun` output.
pub struct RerunPlugin;

impl Plugin for RerunPlugin {
    fn build(&self, app: &mut Regolith) {
        app.register::<dyn Output, Rerun>();
    }
}
