//! What an output or a condition carries across a checkpoint, so that a resumed run goes on
//! with its record instead of starting a new one.
//!
//! Outputs keep records in memory between steps: a pressure diagram, a surface history, the
//! frames a VTK collection lists, the instant of first contact, a recording's file. A run
//! resumed from the points alone would restart them from nothing and, at its end, write a
//! clean-looking wrong answer (issue 35: a resumed `PressureFront` reported another front
//! speed). So every output and condition says what it carries ([`Carried`]) through the
//! `save` and `restore` methods of its kind's trait, and `checkpoint.bin` holds what they
//! return. One that cannot carry its state says why, and a run resumed past it is marked
//! partial in `summary.json` ([`Partial`]) instead of looking complete.

use bevy_ecs::prelude::*;
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

/// What a scene item hands a checkpoint.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Carried {
    /// The item keeps no state between steps beyond what the engine saves itself.
    Nothing,
    /// The item's state, serialised by the item ([`carried`] writes a value with bincode).
    State(Vec<u8>),
    /// The item cannot carry its state: a run resumed past this checkpoint restarts the
    /// item's record, and its summary says so with this reason.
    Lost(String),
}

/// `value` as a [`Carried::State`] (bincode: floats keep every bit).
pub fn carried<T: Serialize>(value: &T) -> Carried {
    Carried::State(bincode::serialize(value).expect("an item's state serialises"))
}

/// Reads back a state written by [`carried`].
pub fn restored<T: DeserializeOwned>(bytes: &[u8]) -> Result<T, String> {
    bincode::deserialize(bytes).map_err(|e| format!("its saved state does not read back: {e}"))
}

/// Why a resumed run's results are not those of an uninterrupted run, one sentence per
/// item that could not carry its state over a resume (`"partial": true` and
/// `"partial_because"` in `summary.json`). Saved in checkpoints, so a run resumed twice keeps
/// the reasons of the first resume.
#[derive(Resource, Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Partial(pub Vec<String>);
