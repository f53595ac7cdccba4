//! The step in one place: every core system, in its set, in order.
//!
//! ```text
//! set                 core systems, in the order they run; {A,B}: only when A and B hold
//! Prepare             choose_time_step clear_grids
//! ParticleToGrid      locate_points<S> average_stress_trace particle_to_grid
//!                     keep_start_bands{Fields}
//! GridUpdate          update_grid
//! Contact             no_slip{NoSlip} frictional{Frictional}
//! GridToParticle      grid_to_particle{Usl,!affine} affine_to_particle<S>{Usl,affine}
//!                     musl_velocity{Musl} musl_remap{Musl} musl_gradient{Musl,!affine}
//!                     musl_apic_gradient<S>{Musl,affine} average_dilatation{CellAveraged}
//! Move                advect_points correct_spacing{DeltaCorrection}
//!                     point_density{PerPoint} cell_density{CellAveraged}
//! Fields              advance_fluidity{Nonlocal} <F>
//! ConstitutiveUpdate  update_stress<M>
//! Clock               advance_clock
//! Diagnostics         survey_bodies check_energy decide_output
//! Output              record_trajectory
//! ```
//!
//! `S` is the scene's shape functions (`integration`), handed over by that item
//! ([`ShapeFunctions::weighted_systems`]); `M` is each material of the scene, once, in any
//! order among themselves (each touches only its own bodies). `<F>` is the system of each
//! kind of field the scene lists (`fields`, a plugin's: [`Field::system`]), once, in any
//! order among themselves and with the fields materials bring (`Nonlocal`'s fluidity,
//! `advance_fluidity`): each writes only its own columns; `Fields` holds when any body
//! carries a field. The Contact set holds the contact law's system
//! ([`Contact::system`]) in scenes of two or more bodies and nothing otherwise. `Usl`/`Musl`
//! is the scene's `update`, `PerPoint`/`CellAveraged` its `dilatation`, `affine` whether its
//! `transfer` carries an affine field, `DeltaCorrection` its `spacing`. The test
//! `tests/step/step_order.rs` builds the step for every combination of these and holds the order
//! that runs against this table.
//!
//! Items hand their systems back; only this module places systems in the core of a set. The
//! core systems of each set sit in its [`Core`] subset; a plugin's or a scene item's systems
//! (`Regolith::add_systems`, `Install::add_systems`) run in the set after its core, so a
//! plugin that moves points in `Prepare` sees this step's time step and cleared grids. Each
//! set is followed by a timing lap ([`Timings`], `timings_s` in the summary, one entry per
//! set, the steps of docs/model.md §2). The executor is single-threaded with ambiguity
//! detection set to error: two systems that touch the same data in no defined order stop
//! the build, named. Systems parallelise inside with rayon. The sets that advance the state
//! (all before `Diagnostics`) are skipped while the clock only observes (the t = 0 output
//! before the first step).

use bevy_ecs::prelude::*;
use bevy_ecs::schedule::{
    LogLevel, ScheduleBuildSettings, ScheduleConfigs, SingleThreadedExecutor,
};
use bevy_ecs::system::ScheduleSystem;

use crate::contact::Contact;
use crate::diagnostics;
use crate::field::Field;
use crate::grid_field::keep_start_bands;
use crate::integration::ShapeFunctions;
use crate::material::MaterialSpec;
use crate::output::trajectory;
use crate::resources::{Dilatation, StressUpdate};
use crate::scene::Scene;
use crate::step::spacing::{self, Spacing};
use crate::step::{
    Core, StepSchedule, StepSet, Timings, cell_average, prepare, scatter_gather, stepping,
    update_grid,
};

/// What decides which core systems a step has.
pub struct StepOptions<'a> {
    pub integration: &'a dyn ShapeFunctions,
    pub update: StressUpdate,
    pub dilatation: Dilatation,
    /// Whether points carry an affine field (the transfer's `affine`).
    pub affine: bool,
    /// Whether the delta-correction follows the move.
    pub spacing: Spacing,
    /// The contact law, in a scene of two or more bodies.
    pub contact: Option<&'a dyn Contact>,
    /// Each material of the scene, once.
    pub materials: Vec<&'a dyn MaterialSpec>,
    /// Each kind of field of the scene, once: those its materials bring, then those it
    /// lists.
    pub fields: Vec<Box<dyn Field>>,
}

impl<'a> StepOptions<'a> {
    /// The options `scene` sets.
    pub fn of(scene: &'a Scene) -> StepOptions<'a> {
        let mut materials: Vec<&dyn MaterialSpec> = Vec::new();
        for body in &scene.bodies {
            if !materials.iter().any(|m| m.name() == body.material.name()) {
                materials.push(&*body.material);
            }
        }
        let brought = materials.iter().flat_map(|m| m.fields());
        let listed = scene.fields.iter().map(|f| f.0.clone());
        let mut fields: Vec<Box<dyn Field>> = Vec::new();
        for field in brought.chain(listed) {
            if !fields.iter().any(|f| f.name() == field.name()) {
                fields.push(field);
            }
        }
        StepOptions {
            integration: &*scene.integration,
            update: scene.update,
            dilatation: scene.dilatation,
            affine: scene.transfer.affine(),
            spacing: scene.spacing,
            contact: (scene.bodies.len() > 1).then_some(&*scene.contact),
            materials,
            fields,
        }
    }
}

/// The material updates (`per_material`).
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
struct MaterialUpdates;

/// The fields' systems (`per_material`: the same holds of them).
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
struct FieldUpdates;

/// The timing lap after a set.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
struct Lap(StepSet);

type Systems = ScheduleConfigs<ScheduleSystem>;

/// The schedule of one step with the core systems for `options`, in the table's order.
pub fn build_schedule(options: &StepOptions) -> Schedule {
    let mut schedule = Schedule::new(StepSchedule);
    schedule.set_executor(SingleThreadedExecutor::new());
    schedule.set_build_settings(ScheduleBuildSettings {
        ambiguity_detection: LogLevel::Error,
        ..Default::default()
    });
    configure_sets(&mut schedule);
    let weighted = options.integration.weighted_systems();
    let mut core = |set: StepSet, systems: Systems| {
        schedule.add_systems(systems.in_set(Core(set)));
    };

    core(
        StepSet::Prepare,
        (prepare::choose_time_step, prepare::clear_grids).chain(),
    );
    let scatter = (
        weighted.locate,
        cell_average::average_stress_trace,
        scatter_gather::particle_to_grid,
    );
    core(
        StepSet::ParticleToGrid,
        if options.fields.is_empty() {
            scatter.chain()
        } else {
            (scatter.chain(), keep_start_bands).chain()
        },
    );
    core(StepSet::GridUpdate, update_grid.into_configs());
    if let Some(contact) = options.contact {
        core(StepSet::Contact, contact.system());
    }
    let gather: Systems = match (options.update, options.affine) {
        (StressUpdate::Usl, false) => scatter_gather::grid_to_particle.into_configs(),
        (StressUpdate::Usl, true) => weighted.affine_gather,
        (StressUpdate::Musl, affine) => {
            let gradient = if affine {
                weighted.musl_apic_gradient
            } else {
                scatter_gather::musl_gradient.into_configs()
            };
            (
                scatter_gather::musl_velocity,
                scatter_gather::musl_remap,
                gradient,
            )
                .chain()
        }
    };
    core(
        StepSet::GridToParticle,
        match options.dilatation {
            Dilatation::PerPoint => gather,
            Dilatation::CellAveraged => (gather, cell_average::average_dilatation).chain(),
        },
    );
    let density = match options.dilatation {
        Dilatation::PerPoint => scatter_gather::point_density.into_configs(),
        Dilatation::CellAveraged => cell_average::cell_density.into_configs(),
    };
    core(
        StepSet::Move,
        match options.spacing {
            Spacing::DeltaCorrection(_) => (
                scatter_gather::advect_points,
                spacing::correct_spacing,
                density,
            )
                .chain(),
            _ => (scatter_gather::advect_points, density).chain(),
        },
    );
    for field in &options.fields {
        core(StepSet::Fields, per_material(field.system(), FieldUpdates));
    }
    for material in &options.materials {
        core(
            StepSet::ConstitutiveUpdate,
            per_material(material.update_system(), MaterialUpdates),
        );
    }
    core(StepSet::Clock, prepare::advance_clock.into_configs());
    core(
        StepSet::Diagnostics,
        (
            diagnostics::survey_bodies,
            diagnostics::check_energy.run_if(stepping),
            prepare::decide_output,
        )
            .chain(),
    );
    core(
        StepSet::Output,
        trajectory::record_trajectory
            .run_if(crate::step::output_due)
            .into_configs(),
    );
    schedule
}

/// `systems` in `set`, in no order with the other systems of `set`: each is one material's
/// and touches only the bodies carrying that material's state, so two of them never touch
/// the same data.
fn per_material(systems: Systems, set: impl SystemSet + Copy) -> Systems {
    systems.in_set(set).ambiguous_with(set)
}

/// Chains the sets with a timing lap after each, and puts each set's core first.
fn configure_sets(schedule: &mut Schedule) {
    let mut previous: Option<Lap> = None;
    for set in StepSet::ALL {
        if let Some(lap) = previous {
            schedule.configure_sets(lap.before(set));
        }
        schedule.configure_sets(set.before(Lap(set)));
        schedule.configure_sets(Core(set).in_set(set));
        if set.advances_state() {
            schedule.configure_sets(set.run_if(stepping));
        }
        schedule.add_systems((move |mut t: ResMut<Timings>| t.lap(set)).in_set(Lap(set)));
        previous = Some(Lap(set));
    }
}
