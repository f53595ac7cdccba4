//! Fields: quantities a body's points carry from step to step and the grid advances (the
//! nonlocal fluidity today; a temperature, a damage or a passive tracer), as items of their
//! own.
//!
//! A field is an item of kind `dyn Field`. It comes into a scene two ways: a material brings
//! it to each of its bodies (`Material::fields`: `Nonlocal` brings its fluidity, whose law is
//! the material's), or the scene lists it under `fields`, naming its body
//! (`fields: [Tracer(body: "layer", ..)]`, a plugin's). Either way it:
//! - adds named columns to the body's `grid_field::FieldColumns` ([`Field::attach`]), with
//!   their start values: its state, carried from step to step, saved and restored by
//!   checkpoints by name, and read by the body's material by name (`PointStep::fields`);
//! - hands over one system ([`Field::system`]), which the step runs in its own set,
//!   `StepSet::Fields`, after the move and before the constitutive update (the table of
//!   `schedule.rs`), once per kind of field whatever the number of its bodies, as materials'
//!   updates are. A field's system touches only the bodies carrying its own component and
//!   writes only its own columns, so fields need no order among themselves; it finds its
//!   grid operators (scatter, Laplacian, gather over the active nodes) in `grid_field`.
//!
//! The scene check asks each field whether the step suits it ([`Field::check_step`], for an
//! explicit operator's stability, at the field's line), and refuses a listed field whose
//! body the scene lacks, two fields carrying one column on a body, and a material reading a
//! column no field of its body carries. (A field sees no more of the scene than that: this
//! module sits below the scene's view, which holds the materials that bring fields.)

use bevy_ecs::schedule::ScheduleConfigs;
use bevy_ecs::system::ScheduleSystem;
use bevy_ecs::world::EntityWorldMut;

use crate::registry::DynItem;

/// A field: an [`Item`](crate::registry::Item) (its scene name and parameter checks) that
/// implements this, registered with `app.register::<dyn Field, YourType>()` for scenes to
/// list it, or handed over by a material (`Material::fields`).
pub trait Field: DynItem {
    /// The body a scene's field lives on (its `body: "name"`); `None` for a field a material
    /// brings to each body made of it.
    fn body(&self) -> Option<&str> {
        None
    }
    /// The columns the field adds to a body, by name.
    fn columns(&self) -> &'static [&'static str];
    /// Whether steps of at most `max_dt` (s) on cells of `cell_size` (m) suit the field (an
    /// explicit diffusion's stability); by default any do.
    fn check_step(&self, _cell_size: f64, _max_dt: f64) -> Result<(), String> {
        Ok(())
    }
    /// Adds the field to a body whose points are placed: the component its system finds the
    /// body by (its parameters, or a marker) and its columns with their start values
    /// (`FieldColumns::add` on the body's `grid_field::FieldColumns`, which the builder has
    /// inserted).
    fn attach(&self, body: &mut EntityWorldMut);
    /// The field's system for `StepSet::Fields`: it advances the field on every body that
    /// carries it.
    fn system(&self) -> ScheduleConfigs<ScheduleSystem>;
}

item_kind!(Field, "field");
