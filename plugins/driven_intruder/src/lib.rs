//! An example plugin: a body driven at a prescribed velocity, and the force that takes.
//!
//! `conditions: [Driven(body: "intruder", velocity: (0.0, -0.5))]` keeps every grid node of
//! the body moving at `velocity` after the contact step, whatever the grains push. The
//! momentum that takes, `F = sum_i m_i (v - v_i) / dt` over the body's nodes, is the force
//! the driver applies; with the body's weight `m g` and the contact force `C` the grains
//! exert, a body at constant velocity has `F + m g + C = 0`. At a slow constant speed the
//! grains' resistance `C_y` as a function of depth is the static drag `f(z)` of the
//! paper's Poncelet law (its `h v^2` term vanishes with `v`), measured directly instead of
//! fitted from decelerating impacts.
//!
//! Written only against regolith's public API: an [`Item`] and a
//! [`Condition`] registered by [`DrivenIntruderPlugin`], a system in the `Contact` set that
//! drives the nodes, one in the `Output` set that records `driven.csv`, and a `driven`
//! section in `summary.json`.

use regolith::bevy_ecs::prelude::*;
use regolith::body::Points;
use regolith::carry::{Carried, carried, restored};
use regolith::condition::Condition;
use regolith::glam::DVec2;
use regolith::grid::GridField;
use regolith::output::summary::Section;
use regolith::output::{OutputFaults, RunDir, write_atomic};
use regolith::plugin::{Install, Plugin, Regolith};
use regolith::registry::Item;
use regolith::resources::Clock;
use regolith::scene::SceneView;
use regolith::step::{StepSet, output_due};
use serde::{Deserialize, Serialize};

/// `Driven(body: "intruder", velocity: (0.0, -0.5))`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Driven {
    /// The body to drive (by name).
    pub body: String,
    /// Its prescribed velocity (m/s); the body should start with it (`velocity` of the body).
    pub velocity: DVec2,
}

impl Item for Driven {
    const NAME: &'static str = "Driven";
    fn validate(&self) -> Result<(), String> {
        if self.velocity.is_finite() {
            Ok(())
        } else {
            Err(format!("velocity must be finite, got {}", self.velocity))
        }
    }
}

impl Condition for Driven {
    fn check_scene(&self, scene: &SceneView) -> Result<(), String> {
        let body = scene.body(&self.body)?;
        if body.velocity != self.velocity {
            return Err(format!(
                "body \"{}\" starts at {} but is driven at {}: give it the driven velocity",
                self.body, body.velocity, self.velocity
            ));
        }
        Ok(())
    }

    fn install(&self, sim: &mut Install) {
        let body = sim.body(&self.body);
        sim.insert_resource(Drive {
            spec: self.clone(),
            body,
            force: DVec2::ZERO,
            contact: DVec2::ZERO,
            rows: Vec::new(),
        });
        sim.add_systems(StepSet::Contact, drive);
        sim.add_systems(StepSet::Output, record.run_if(output_due));
    }

    /// `driven`: the body, its velocity, the rows recorded and the last forces.
    fn summary(&self, world: &World) -> Section {
        let Some(drive) = world.get_resource::<Drive>() else {
            return Section::default();
        };
        let last = drive.rows.last();
        let mut section = Section::entry(
            "driven",
            serde_json::json!({
                "body": self.body,
                "velocity": self.velocity.to_array(),
                "rows": drive.rows.len(),
                "final_bottom": last.map(|r| r.bottom),
                "final_drive_force": last.map(|r| r.force.to_array()),
                "final_contact_force": last.map(|r| r.contact.to_array()),
            }),
        );
        section.units = [
            ("driven.velocity", "m/s"),
            ("driven.final_bottom", "m"),
            ("driven.final_drive_force", "N/m (per metre of thickness)"),
            ("driven.final_contact_force", "N/m (per metre of thickness)"),
        ]
        .map(|(k, u)| (k.to_string(), u.to_string()))
        .to_vec();
        section.headline = last.map(|r| {
            format!(
                "driven: {} at {} m/s, tip at {:.4} m, resistance {:.1} N/m (driven.csv)",
                self.body, self.velocity, r.bottom, r.contact.y
            )
        });
        section
    }

    /// The last step's forces (the next record reports them) and the rows so far.
    fn save(&self, world: &World) -> Carried {
        let d = world.resource::<Drive>();
        carried(&(d.force, d.contact, &d.rows))
    }

    fn restore(&self, world: &mut World, state: &[u8]) -> Result<(), String> {
        let mut d = world.resource_mut::<Drive>();
        (d.force, d.contact, d.rows) = restored(state)?;
        Ok(())
    }
}

/// One recorded instant.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Row {
    pub time: f64,
    /// Lowest point of the body (its tip), m.
    pub bottom: f64,
    /// Force the driver applied over the last step, N per metre of thickness.
    pub force: DVec2,
    /// Force the other bodies exerted through contact over the last step.
    pub contact: DVec2,
}

/// The driver's state: the last step's forces and the recorded rows.
#[derive(Resource, Debug)]
pub struct Drive {
    pub spec: Driven,
    /// The driven body's entity, found at install.
    pub body: Option<Entity>,
    /// The driver's force over the last step.
    pub force: DVec2,
    /// The contact force on the body over the last step.
    pub contact: DVec2,
    pub rows: Vec<Row>,
}

/// Sets every node of the driven body to the prescribed velocity after contact, and keeps
/// the force that took. The acceleration is corrected with the velocity, so the FLIP update
/// of the body's points leaves them at the prescribed velocity too.
fn drive(clock: Res<Clock>, mut state: ResMut<Drive>, mut bodies: Query<&mut GridField>) {
    let dt = clock.dt;
    let target = state.spec.velocity;
    let Some(mut field) = state.body.and_then(|e| bodies.get_mut(e).ok()) else {
        return;
    };
    let field = &mut *field;
    let mut force = DVec2::ZERO;
    for n in 0..field.mass.len() {
        let m = field.mass[n];
        if m > 0.0 {
            let change = target - field.velocity[n];
            force += m * change / dt;
            field.acceleration[n] += change / dt;
            field.velocity[n] = target;
            field.momentum[n] = m * target;
        }
    }
    state.force = force;
    state.contact = field.contact_force;
}

/// Records a row at each output time and rewrites `driven.csv` in the run directory.
fn record(
    clock: Res<Clock>,
    dir: Res<RunDir>,
    faults: Res<OutputFaults>,
    mut state: ResMut<Drive>,
    bodies: Query<&Points>,
) {
    let Some(points) = regolith::output::points_of(&bodies, state.body) else {
        return;
    };
    let bottom = points
        .position
        .iter()
        .map(|x| x.y)
        .fold(f64::INFINITY, f64::min);
    let row = Row {
        time: clock.time,
        bottom,
        force: state.force,
        contact: state.contact,
    };
    let Some(dir) = &dir.0 else {
        state.rows.push(row);
        return;
    };
    let path = dir.join("driven.csv");
    state.rows.push(row);
    if let Err(e) = write_atomic(&path, to_csv(&state.rows).as_bytes()) {
        faults.report(&clock, format!("cannot write {}: {e}", path.display()));
    }
}

const HEADER: &str = "time,bottom,drive_fx,drive_fy,contact_fx,contact_fy";

fn to_csv(rows: &[Row]) -> String {
    let mut text = format!("{HEADER}\n");
    for r in rows {
        text += &format!(
            "{:?},{:?},{:?},{:?},{:?},{:?}\n",
            r.time, r.bottom, r.force.x, r.force.y, r.contact.x, r.contact.y
        );
    }
    text
}

/// Adds the `Driven` condition.
pub struct DrivenIntruderPlugin;

impl Plugin for DrivenIntruderPlugin {
    fn build(&self, app: &mut Regolith) {
        app.register::<dyn Condition, Driven>();
    }
}
