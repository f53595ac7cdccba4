//! Outputs: the always-written `summary.json` and `trajectory.csv`, and plugin outputs.
//!
//! Plugin outputs (like the built-in `Snapshots`) are named in the scene's `outputs` list and
//! install their own resources and systems in the Output set, exactly as a user's would.
//! Files are written atomically (temporary file, then rename) so a crash never leaves a
//! truncated file that looks complete; the trajectory grows in `trajectory.csv.part` and is
//! renamed when the run ends.

pub mod snapshots;
pub mod summary;
pub mod trajectory;

use std::fmt::Debug;
use std::io::Write;
use std::marker::PhantomData;
use std::path::{Path, PathBuf};

use bevy_ecs::prelude::*;
use serde::de::DeserializeOwned;

use crate::plugin::Plugin;
use crate::registry::{IntoSpec, Registries, construct};

/// The directory a run writes into, if it writes files at all (tests run without one).
#[derive(Resource, Clone, Debug, Default)]
pub struct RunDir(pub Option<PathBuf>);

/// An extra output. Implement this, then add `OutputPlugin::<YourType>::default()`.
pub trait Output: Clone + Debug + Send + Sync + DeserializeOwned + 'static {
    /// The name used in scene files, e.g. `Snapshots`.
    const NAME: &'static str;
    fn validate(&self) -> Result<(), String>;
    /// Adds the output's resources and its systems (in [`crate::step::StepSet::Output`]).
    fn install(&self, world: &mut World, schedule: &mut Schedule);
    /// Re-aligns the output's own schedule with a run resumed at `time` (the state it
    /// would have had then); by default nothing.
    fn resume(&self, _world: &mut World, _time: f64) {}
}

/// An output as the scene and the simulation builder see it (object safe).
pub trait OutputSpec: Debug + Send + Sync {
    fn name(&self) -> &'static str;
    fn clone_spec(&self) -> Box<dyn OutputSpec>;
    fn validate(&self) -> Result<(), String>;
    fn install(&self, world: &mut World, schedule: &mut Schedule);
    fn resume(&self, world: &mut World, time: f64);
}

crate::impl_named_spec!(OutputSpec);

impl<O: Output> OutputSpec for O {
    fn name(&self) -> &'static str {
        O::NAME
    }
    fn clone_spec(&self) -> Box<dyn OutputSpec> {
        Box::new(self.clone())
    }
    fn validate(&self) -> Result<(), String> {
        Output::validate(self)
    }
    fn install(&self, world: &mut World, schedule: &mut Schedule) {
        Output::install(self, world, schedule)
    }
    fn resume(&self, world: &mut World, time: f64) {
        Output::resume(self, world, time)
    }
}

impl<O: Output> IntoSpec<dyn OutputSpec> for O {
    fn into_spec(self) -> Box<dyn OutputSpec> {
        Box::new(self)
    }
}

/// Registers output `O` under `O::NAME`.
pub struct OutputPlugin<O>(PhantomData<fn() -> O>);

impl<O> Default for OutputPlugin<O> {
    fn default() -> Self {
        OutputPlugin(PhantomData)
    }
}

impl<O: Output> Plugin for OutputPlugin<O> {
    fn build(&self, registries: &mut Registries) {
        registries
            .outputs
            .insert(O::NAME, construct::<O, dyn OutputSpec>);
    }
}

/// Writes `bytes` to `path` through a temporary file in the same directory and a rename.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let mut tmp = path.as_os_str().to_owned();
    tmp.push(".tmp");
    let tmp = PathBuf::from(tmp);
    {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
    }
    std::fs::rename(&tmp, path)
}
