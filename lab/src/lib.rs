//! regolith's lab: what is built on top of single runs. Sweeps and studies of many runs
//! (planned as directories of self-contained runs for GNU parallel, Slurm or the local
//! workers, claimed, collected into tables), the Poncelet drag fit, the Beverloo fit of silo discharge, the paper's figures and
//! the measures of the verification problems.
//!
//! It depends on the engine (`regolith`) and never the other way round: the engine steps one
//! scene and writes its files; everything here only reads scenes, runs them through
//! [`regolith::run`] and reads their outputs back.

pub mod batch;
pub mod beverloo;
pub mod claim;
pub mod collect;
pub mod figures;
pub mod plan;
pub mod poncelet;
pub mod study;
pub mod sweep;
pub mod verify;
pub mod workers;
