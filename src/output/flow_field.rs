//! `FlowField(..)`: the granular velocity field normalised by the intruder's velocity, as in
//! the paper's section 4.3.2 (Fig. 6, after Clark, Kondic & Behringer 2016).
//!
//! The paper shows "the nodal velocity field as projected into the material point
//! positions": each point's grid-interpolated velocity `sum_i S_ip v_i`, which regolith keeps
//! as the point's advection velocity. At each requested time the output writes, for every
//! point of the bed, its position relative to the intruder's centre of mass in intruder
//! widths (the paper's axes) and its velocity divided by the intruder's speed, so fields at
//! different speeds can be compared: the paper finds the field ahead of the intruder keeps
//! its normalised shape from 3.07 m/s down to 0.1 m/s (a "dynamic steady state").
//! Files: `flow_field_<k>.csv`, columns `t,x,y,dx,dy,ux,uy` with `dx, dy` the offset from
//! the intruder's centre over `scale` and `ux, uy` the velocity over the intruder's speed.

use bevy_ecs::prelude::*;
use glam::DVec2;
use serde::Deserialize;

use crate::body::{BodyState, Points};
use crate::carry::{Carried, carried, restored};
use crate::format::Num;
use crate::output::{Instants, Output, OutputFaults, RunDir, check_instants, write_or_fault};
use crate::plugin::Install;
use crate::registry::Item;
use crate::resources::Clock;
use crate::step::StepSet;

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FlowField {
    /// The granular body.
    pub body: String,
    /// The intruder (its centre of mass and speed normalise the field).
    pub intruder: String,
    /// Length that normalises the offsets (m), e.g. the intruder's diameter.
    pub scale: f64,
    /// Times to write the field at (s), increasing.
    pub at: Vec<f64>,
}

/// One normalised field.
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct NormalisedField {
    pub time: f64,
    /// The intruder's speed used (m/s).
    pub speed: f64,
    /// Offsets from the intruder's centre, in `scale` units.
    pub offset: Vec<DVec2>,
    /// Velocities over the intruder's speed.
    pub velocity: Vec<DVec2>,
}

/// The fields written so far (kept for tests and figures).
#[derive(Resource, Clone, Debug)]
pub struct FlowFields {
    spec: FlowField,
    /// The bed and the intruder, found at install.
    bodies: [Option<Entity>; 2],
    when: Instants,
    pub fields: Vec<NormalisedField>,
}

impl Item for FlowField {
    const NAME: &'static str = "FlowField";
    fn validate(&self) -> Result<(), String> {
        if !(self.scale.is_finite() && self.scale > 0.0) {
            return Err(format!(
                "scale must be a positive length, got {}",
                self.scale
            ));
        }
        check_instants(&self.at)?;
        if self.body == self.intruder {
            return Err("body and intruder must be different bodies".into());
        }
        Ok(())
    }
}

impl Output for FlowField {
    fn bodies(&self) -> Vec<&str> {
        vec![&self.body, &self.intruder]
    }

    fn install(&self, sim: &mut Install) {
        let bodies = [sim.body(&self.body), sim.body(&self.intruder)];
        sim.insert_resource(FlowFields {
            spec: self.clone(),
            bodies,
            when: Instants::new(self.at.clone()),
            fields: Vec::new(),
        });
        sim.add_systems(StepSet::Output, record_flow_field);
    }

    /// The times still to come and the fields written so far.
    fn save(&self, world: &World) -> Carried {
        let f = world.resource::<FlowFields>();
        carried(&(&f.when, &f.fields))
    }

    fn restore(&self, world: &mut World, state: &[u8]) -> Result<(), String> {
        let mut f = world.resource_mut::<FlowFields>();
        (f.when, f.fields) = restored(state)?;
        Ok(())
    }
}

fn record_flow_field(
    clock: Res<Clock>,
    dir: Res<RunDir>,
    mut fields: ResMut<FlowFields>,
    faults: Res<OutputFaults>,
    bodies: Query<(&Points, &BodyState)>,
) {
    let index = fields.when.done();
    if !fields.when.due(&clock) {
        return;
    }
    let spec = &fields.spec;
    let find = |body: Option<Entity>| body.and_then(|e| bodies.get(e).ok());
    let (Some((points, _)), Some((_, intruder))) = (find(fields.bodies[0]), find(fields.bodies[1]))
    else {
        return;
    };
    let speed = intruder.velocity.length();
    let inverse = if speed > 0.0 { 1.0 / speed } else { 0.0 };
    let live: Vec<usize> = (0..points.len())
        .filter(|&k| points.mass[k] > 0.0)
        .collect();
    let field = NormalisedField {
        time: clock.time,
        speed,
        offset: live
            .iter()
            .map(|&k| (points.position[k] - intruder.centre_of_mass) / spec.scale)
            .collect(),
        velocity: live
            .iter()
            .map(|&k| points.advection[k] * inverse)
            .collect(),
    };
    if let Some(dir) = &dir.0 {
        let mut csv = String::from("t,x,y,dx,dy,ux,uy\n");
        for ((&k, d), u) in live.iter().zip(&field.offset).zip(&field.velocity) {
            let x = points.position[k];
            csv.push_str(&format!(
                "{},{},{},{},{},{},{}\n",
                Num(clock.time),
                Num(x.x),
                Num(x.y),
                Num(d.x),
                Num(d.y),
                Num(u.x),
                Num(u.y)
            ));
        }
        let path = dir.join(format!("flow_field_{index}.csv"));
        write_or_fault(&path, csv.as_bytes(), &clock, &faults);
    }
    fields.fields.push(field);
}
