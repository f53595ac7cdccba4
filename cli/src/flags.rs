//! Flags that add an output to the scene: `--rrd` and the recording flags become a
//! `Rerun(..)` output, `--vtk` a `Vtk(..)` one, so a command-line output and one listed in
//! a scene are the same code.

use std::path::PathBuf;

use regolith::error::{Error, SceneError};
use regolith::output::Output;
use regolith::output::vtk::Vtk;
use regolith::scene::Scene;

/// Recording for the Rerun viewer. The flags become a `Rerun(..)` scene output, so a
/// recording asked for on the command line and one listed in a scene are the same thing.
#[derive(clap::Args, Debug, Default)]
pub(crate) struct RecordArgs {
    /// Record the run for the Rerun viewer into FILE (.rrd); a relative FILE goes into the
    /// run directory (as a scene's Rerun(file: ..) does), and the run's last lines say where.
    #[arg(long, value_name = "FILE")]
    pub(crate) rrd: Option<PathBuf>,
    /// Stream the recording to a Rerun viewer started from PATH (`rerun`).
    #[arg(long)]
    pub(crate) spawn: bool,
    /// Record every N steps (default: at the scene's output interval, time.output_every).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..))]
    pub(crate) record_every: Option<u64>,
    /// Colour the points by: pressure (default), plastic-strain-rate, inertial-number, phase,
    /// speed or body.
    #[arg(long, value_name = "FIELD")]
    pub(crate) color: Option<String>,
    /// Also record the grid: nodal velocities and masses.
    #[arg(long)]
    pub(crate) record_grid: bool,
}

impl RecordArgs {
    /// Adds the recording to `scene` (replacing the scene's own), or says why it cannot be
    /// made.
    pub(crate) fn apply(&self, scene: &mut Scene) -> Result<(), Error> {
        let flags = |message: String| Error::Scene(SceneError::file("command line", message));
        if self.rrd.is_none() && !self.spawn {
            if self.record_every.is_some() || self.color.is_some() || self.record_grid {
                return Err(flags(
                    "--record-every, --color and --record-grid need --rrd FILE or --spawn".into(),
                ));
            }
            return Ok(());
        }
        let recorder = self.recorder().map_err(flags)?;
        if scene.set_output(recorder).map_err(flags)? {
            eprintln!(
                "note: the command line's recording replaces the scene's own Rerun(..) output (one recording per run); only the command line's is written"
            );
        }
        Ok(())
    }

    /// The `Rerun` output these flags stand for.
    #[cfg(feature = "rerun")]
    fn recorder(&self) -> Result<Box<dyn Output>, String> {
        use regolith_rerun::{Field, Rerun};
        // A relative path goes into the run directory, as a scene's `Rerun(file: ..)` does.
        let file = self.rrd.as_ref().map(|f| f.display().to_string());
        let color = match &self.color {
            None => Field::default(),
            Some(name) => Field::parse(name).ok_or_else(|| {
                let names: Vec<String> = Field::ALL
                    .iter()
                    .map(|f| f.name().replace('_', "-"))
                    .collect();
                format!("--color {name}: expected one of {}", names.join(", "))
            })?,
        };
        Ok(Box::new(Rerun {
            file,
            spawn: self.spawn,
            every: self.record_every,
            color,
            grid: self.record_grid,
        }))
    }

    #[cfg(not(feature = "rerun"))]
    fn recorder(&self) -> Result<Box<dyn Output>, String> {
        Err(
            "this program was built without the Rerun recorder; use the `regolith` command \
             of the workspace (cli/), or build yours with regolith-cli's `rerun` feature"
                .to_string(),
        )
    }
}

/// VTK files for ParaView. The flags become a `Vtk(..)` scene output, as the recording
/// flags become a `Rerun(..)` one.
#[derive(clap::Args, Debug, Default)]
pub(crate) struct VtkArgs {
    /// Write VTK files for ParaView every SECONDS of simulated time (open <out>/vtk/points.pvd).
    #[arg(long, value_name = "SECONDS")]
    pub(crate) vtk: Option<f64>,
    /// Also write each body's grid field (<out>/vtk/grid.pvd).
    #[arg(long, requires = "vtk")]
    pub(crate) vtk_grid: bool,
}

impl VtkArgs {
    /// Adds the `Vtk(..)` output to `scene`, replacing the scene's own.
    pub(crate) fn apply(&self, scene: &mut Scene) -> Result<(), Error> {
        let Some(every) = self.vtk else {
            return Ok(());
        };
        let vtk = Vtk {
            every: Some(every),
            at: None,
            fields: None,
            grid: self.vtk_grid,
        };
        let replaced = scene
            .set_output(Box::new(vtk))
            .map_err(|e| Error::Scene(SceneError::file("command line --vtk", e)))?;
        if replaced {
            eprintln!(
                "note: --vtk replaces the scene's own Vtk(..) output (one VTK series per run)"
            );
        }
        Ok(())
    }
}
