//! The scene's `integration` item: which shape functions the scatter and the gather use
//! (`integration: CpdiFixed`).
//!
//! Every weight rule of `shape_functions` ([`Scheme`]) is one, and a plugin may add its
//! own. The step is monomorphised per rule, so the item hands the step's builder
//! (`schedule.rs`) the systems compiled for its weights; the builder places them.

use bevy_ecs::prelude::*;
use bevy_ecs::schedule::ScheduleConfigs;
use bevy_ecs::system::ScheduleSystem;

use crate::registry::DynItem;
use crate::shape_functions::Scheme;
use crate::step::{locate_points, scatter_gather};

/// The shape functions a scene selects: a kind of scene item.
pub trait ShapeFunctions: DynItem {
    /// The step's systems that depend on the weights, compiled for these.
    fn weighted_systems(&self) -> WeightedSystems;
}

item_kind!(ShapeFunctions, "shape-function scheme");

/// The systems of a step that are compiled for one weight rule; the builder places each.
pub struct WeightedSystems {
    /// Each point's footprint, cell and band (the scatter's first system).
    pub locate: ScheduleConfigs<ScheduleSystem>,
    /// The APIC or affine-FLIP gather (`update: Usl` with an affine transfer).
    pub affine_gather: ScheduleConfigs<ScheduleSystem>,
    /// MUSL's gradient pass with an affine transfer.
    pub musl_apic_gradient: ScheduleConfigs<ScheduleSystem>,
}

impl<S: Scheme> ShapeFunctions for S {
    fn weighted_systems(&self) -> WeightedSystems {
        WeightedSystems {
            locate: locate_points::<S>.into_configs(),
            affine_gather: scatter_gather::affine_to_particle::<S>.into_configs(),
            musl_apic_gradient: scatter_gather::musl_apic_gradient::<S>.into_configs(),
        }
    }
}
