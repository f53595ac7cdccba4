//! An example plugin: a passive tracer that a body's points carry and the grid diffuses, a
//! field (`regolith::field`) added without touching the engine.
//!
//! A scene lists it under `fields`, naming its body:
//! `fields: [Tracer(body: "layer", diffusivity: 1e-4, marked: Rectangle(min: (0.0, 0.0), max: (0.1, 0.02)))]`.
//! Each point starts with the tracer at 1 inside `marked` and 0 elsewhere, carries it as it
//! moves, and the tracer diffuses through the material at `diffusivity` `D` (m^2/s):
//! `dc/dt = D lap(c)` following the points, with no flux through the walls or the free
//! surface. It is the smallest useful field: a dye to watch how a flow mixes (`D = 0` is a
//! pure marker), or a stand-in for heat conduction at a fixed conductivity.
//!
//! What it shows of the facility: the field's column (`tracer`) is added to the body's
//! `FieldColumns`, so checkpoints carry it and VTK frames show it with nothing written here
//! for either; its system runs in the step's `Fields` set, beside the nonlocal fluidity if
//! the body has one, and writes only its own column; its explicit step is checked before a
//! run (`check_step`).
//!
//! A step of the tracer, per body: the points' tracer scattered to the nodes as a
//! volume-weighted mean (`grid_field::scatter`, with the bands of the step's start), the
//! nodal 5-point Laplacian with zero flux at every wall and at the material's edge
//! (`grid_field::laplacian`), and each point's tracer raised by `dt D` times the Laplacian
//! interpolated back over the active nodes (`grid_field::gather_active`). On a uniform
//! periodic block a Fourier mode of the tracer then decays at `D k^2` (to the grid's
//! second-order error), and the volume-weighted total is kept to round-off.

use rayon::prelude::*;
use regolith::bevy_ecs::prelude::*;
use regolith::bevy_ecs::schedule::ScheduleConfigs;
use regolith::bevy_ecs::system::ScheduleSystem;
use regolith::bevy_ecs::world::EntityWorldMut;
use regolith::body::Points;
use regolith::field::Field;
use regolith::geometry::{Shape, finite};
use regolith::grid::GridGeometry;
use regolith::grid_field::{
    FieldColumns, FieldWalls, GridFields, NodeCondition, StartBands, gather_active, laplacian,
    scatter,
};
use regolith::registry::{Item, Named};
use regolith::resources::Clock;
use regolith::step::Location;
use regolith::{Plugin, Regolith};
use serde::Deserialize;

/// The tracer's column in the body's `FieldColumns`.
pub const COLUMN: &str = "tracer";

/// `Tracer(body: "name", diffusivity: D, marked: shape)`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Tracer {
    /// The body carrying it.
    pub body: String,
    /// `D` (m^2/s), zero or more.
    pub diffusivity: f64,
    /// Where the tracer starts at 1 (0 elsewhere): any registered shape.
    pub marked: Named<dyn Shape>,
}

impl Item for Tracer {
    const NAME: &'static str = "Tracer";
    fn validate(&self) -> Result<(), String> {
        finite("diffusivity", self.diffusivity)?;
        if self.diffusivity < 0.0 {
            return Err(format!(
                "diffusivity must be zero or more (m^2/s), got {}",
                self.diffusivity
            ));
        }
        Ok(())
    }
}

/// A body's tracer diffusivity (component): how `diffuse_tracer` finds the bodies carrying
/// a tracer.
#[derive(Component, Clone, Copy, Debug)]
pub struct TracerDiffusivity(pub f64);

/// The explicit step's limit: `D dt / h^2` at most this (the 5-point Laplacian's).
pub const MAX_DIFFUSION_NUMBER: f64 = 0.25;

/// Zero flux through every wall (a periodic side wraps whatever is set).
const INSULATED: FieldWalls<'static> = FieldWalls {
    left: NodeCondition::ZeroFlux,
    right: NodeCondition::ZeroFlux,
    bottom: NodeCondition::ZeroFlux,
    top: NodeCondition::ZeroFlux,
    segments: &[],
    obstacles: &[],
};

impl Field for Tracer {
    fn body(&self) -> Option<&str> {
        Some(&self.body)
    }
    fn columns(&self) -> &'static [&'static str] {
        &[COLUMN]
    }
    fn check_step(&self, cell_size: f64, max_dt: f64) -> Result<(), String> {
        let number = self.diffusivity * max_dt / (cell_size * cell_size);
        if number <= MAX_DIFFUSION_NUMBER {
            return Ok(());
        }
        Err(format!(
            "the diffusion number D dt / h^2 would reach {number:.3} (D = {} m^2/s, dt = \
             {max_dt:.3e} s, h = {cell_size} m), above the {MAX_DIFFUSION_NUMBER} its explicit \
             step allows: take a smaller diffusivity or step, or larger cells",
            self.diffusivity
        ))
    }
    fn attach(&self, body: &mut EntityWorldMut) {
        let marks: Vec<f64> = body
            .get::<Points>()
            .map(|p| {
                let inside = |x| if self.marked.contains(x) { 1.0 } else { 0.0 };
                p.position.iter().map(|&x| inside(x)).collect()
            })
            .unwrap_or_default();
        body.insert(TracerDiffusivity(self.diffusivity));
        body.get_mut::<FieldColumns>()
            .expect("the builder gives a body with fields its columns")
            .add(COLUMN, marks)
            .expect("the scene check allows one tracer per body");
    }
    fn system(&self) -> ScheduleConfigs<ScheduleSystem> {
        diffuse_tracer.into_configs()
    }
}

/// What the tracer reads and writes of a body.
type TracerBody<'a> = (
    &'a TracerDiffusivity,
    &'a Points,
    &'a Location,
    &'a StartBands,
    &'a mut GridFields,
    &'a mut FieldColumns,
);

/// One explicit diffusion step of every body's tracer (module docs).
pub fn diffuse_tracer(
    grid: Res<GridGeometry>,
    clock: Res<Clock>,
    mut bodies: Query<TracerBody>,
    mut curvature: Local<Vec<f64>>,
) {
    for (diffusivity, points, location, bands, mut nodal, mut columns) in &mut bodies {
        if diffusivity.0 == 0.0 {
            continue;
        }
        let tracer = columns
            .get_mut(COLUMN)
            .expect("a body with a tracer carries its column");
        let nodes = nodal.field_mut(COLUMN);
        let carried = &*tracer;
        scatter(&grid, location, &bands.0, nodes, |k| {
            (points.mass[k] > 0.0).then(|| (points.volume[k], carried[k]))
        });
        laplacian(&grid, nodes, &INSULATED, &mut curvature);
        let (nodes, curvature) = (&*nodes, &*curvature);
        let rate = clock.dt * diffusivity.0;
        tracer.par_iter_mut().enumerate().for_each(|(k, c)| {
            if let Some([l]) = gather_active(location, nodes, [curvature], k) {
                *c += rate * l;
            }
        });
    }
}

/// Adds the `Tracer` field.
pub struct TracerPlugin;

impl Plugin for TracerPlugin {
    fn build(&self, app: &mut Regolith) {
        app.register::<dyn Field, Tracer>();
    }
}
