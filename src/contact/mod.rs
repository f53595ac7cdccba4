//! Interaction between bodies at the grid nodes they share (the Contact set).
//!
//! Only scenes with two or more bodies get a contact system. `NoSlip` is the classic MPM
//! default: at every node where two or more bodies have mass, all of them move with the
//! nodes' common centre-of-mass velocity. It is written as a force added to each body's
//! nodal force, `f_c = (m_b v_cm - p~_b) / dt`, so the FLIP update sees it and the forces sum
//! to zero (momentum is conserved). Because every body is constrained by the walls before,
//! the common velocity respects them too.

use bevy_ecs::prelude::*;
use glam::DVec2;
use serde::Deserialize;

use crate::grid::GridField;
use crate::sim::Clock;

/// The contact law between bodies.
#[derive(Clone, Copy, Debug, Default, PartialEq, Deserialize)]
pub enum Contact {
    /// One shared velocity at shared nodes (bodies stick together once they share a node).
    #[default]
    NoSlip,
}

/// Adds the contact force that gives every body at a shared node the common velocity.
pub fn no_slip(clock: Res<Clock>, mut fields: Query<&mut GridField>) {
    let dt = clock.dt;
    let mut fields: Vec<Mut<GridField>> = fields.iter_mut().collect();
    let nodes = fields.first().map_or(0, |f| f.mass.len());
    for n in 0..nodes {
        let mut sharing = 0;
        let mut mass = 0.0;
        let mut momentum = DVec2::ZERO;
        for f in fields.iter() {
            if f.mass[n] > f.mass_tolerance {
                sharing += 1;
                mass += f.mass[n];
                momentum += f.momentum[n];
            }
        }
        if sharing < 2 {
            continue;
        }
        let v_cm = momentum / mass;
        for f in fields.iter_mut() {
            let m = f.mass[n];
            if m > f.mass_tolerance {
                let target = m * v_cm;
                let fc = (target - f.momentum[n]) / dt;
                f.force[n] += fc;
                f.momentum[n] = target;
                f.velocity[n] = v_cm;
                f.acceleration[n] = f.force[n] / m;
            }
        }
    }
}
