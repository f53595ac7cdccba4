//! regolith: a 2D plane-strain Material Point Method for projectiles hitting dry granular
//! media, after Dunatunga & Kamrin (2017).
//!
//! A simulation is a bevy_ecs [`World`](bevy_ecs::world::World) stepped by a
//! [`Schedule`](bevy_ecs::schedule::Schedule) of ordered system sets ([`step::StepSet`]).
//! Bodies are entities whose material points ([`body::Points`]) and nodal field
//! ([`grid::GridField`]) are struct-of-arrays components. Materials, shapes and outputs are
//! plugins ([`plugin::Plugin`]) named in RON scene files ([`scene::Scene`]).
//! See ARCHITECTURE.md for the layout and docs/scenes.md for the scene format.

// First, so that its `item_kind!` macro is in scope in every module below (each item kind
// declares itself with it); plugins name it `regolith::item_kind!`.
#[macro_use]
pub mod registry;
pub mod body;
pub mod carry;
pub mod checkpoint;
pub mod condition;
pub mod contact;
pub mod defaults;
pub mod diagnostics;
pub mod error;
pub mod field;
pub mod fill;
pub mod format;
pub mod geometry;
pub mod grid;
pub mod grid_field;
pub mod integration;
pub mod kernels;
pub mod linefit;
pub mod material;
pub mod obstacle;
pub mod output;
pub mod plugin;
pub mod resources;
pub mod run;
pub mod scene;
mod scene_view;
pub mod schedule;
pub mod shape_functions;
pub mod sim;
pub mod step;
pub mod stress;
pub mod transfer;

/// Re-exported for plugin crates: the ECS and vector types of the public API.
pub use bevy_ecs;
pub use glam;

pub use defaults::DefaultPlugins;
pub use plugin::{Plugin, Regolith};
pub use scene::Scene;
pub use sim::Simulation;

/// The `transfer` item's old path, kept so that code written against it still builds.
#[doc(hidden)]
pub use transfer as velocity;
