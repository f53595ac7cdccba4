//! Interaction between bodies at the grid nodes they share (the Contact set).
//!
//! Only scenes with two or more bodies get a contact system. Two laws:
//!
//! * `NoSlip`, the classic MPM default: at every node where two or more bodies have mass all
//!   of them take the nodes' common centre-of-mass velocity, and the acceleration their points
//!   see (FLIP) is the node's total force over its total mass: what one body made of all of
//!   them would see, so that a seam between bodies of one material is invisible. (Each body's
//!   own velocity change, the impulse included, would remove its points' velocity relative to
//!   the common one at every step: a damping at the seam that one body does not have, which
//!   made the authors' impact 15% shallower; docs/VALIDATION.md, "Against the authors' code".)
//! * `Frictional(friction: mu)`: Bardenhagen et al. (2001) as refined by Huang et al. (2011),
//!   run once per step before the stress update (update-stress-last form, docs/model.md §5).
//!   At a shared node each body is compared with the centre of mass of all bodies there:
//!   with `dv = v~_b - v_cm` and the unit normal `n` from body b towards the others (from the
//!   bodies' mass gradients), it acts only if `dv . n > 0` (approaching): it removes the
//!   normal part of `dv` and as much of the tangential part as Coulomb allows,
//!   `|dp_t| <= mu |dp_n|`. Separating bodies feel nothing: no glue, no tension. For two
//!   bodies the normals are opposite and the two momentum changes cancel exactly.
//!
//! Both are written as a force added to each body's nodal force; the frictional impulse also
//! enters the acceleration the FLIP update reads (no-slip's does not, above). The contact
//! switches on as soon as two bodies share a node, up to about one cell
//! before their points touch.

use bevy_ecs::prelude::*;
use bevy_ecs::schedule::ScheduleConfigs;
use bevy_ecs::system::ScheduleSystem;
use glam::DVec2;
use serde::Deserialize;

use crate::body::Body;
use crate::grid::{GridField, GridGeometry};
use crate::obstacle::Obstacles;
use crate::registry::{DynItem, Item};
use crate::resources::{Boundaries, Clock};
use crate::step::apply_walls;

/// A contact law between bodies: a kind of scene item (`contact: Frictional(friction: 0.1)`),
/// so a plugin may add one. Its system sits in the core of the Contact set, which only
/// scenes of two or more bodies run.
pub trait Contact: DynItem {
    /// Whether the law needs the mass gradient (surface normal) of the body called `body`
    /// in a scene of `bodies` bodies; the scatter accumulates it only then.
    fn needs_normal_of(&self, body: &str, bodies: usize) -> bool;
    /// The body whose normal the law uses for every contact, if it names one (the scene
    /// check makes sure it exists).
    fn normal_body(&self) -> Option<&str> {
        None
    }
    /// The law's system, which the step runs in the core of its Contact set.
    fn system(&self) -> ScheduleConfigs<ScheduleSystem>;
    /// Inserts what the law's system reads (its parameters) into a new simulation's world;
    /// nothing by default.
    fn insert_resources(&self, _world: &mut World) {}
}

item_kind!(Contact, "contact law");

/// One shared velocity at shared nodes (bodies stick together once they share a node).
#[derive(Clone, Copy, Debug, Deserialize)]
pub struct NoSlip;

impl Item for NoSlip {
    const NAME: &'static str = "NoSlip";
    const UNIT: bool = true;
}

impl Contact for NoSlip {
    fn needs_normal_of(&self, _body: &str, _bodies: usize) -> bool {
        false
    }
    fn system(&self) -> ScheduleConfigs<ScheduleSystem> {
        no_slip.into_configs()
    }
}

/// Coulomb friction with coefficient `friction` between surfaces; no force on separating
/// bodies.
#[derive(Clone, Debug, Deserialize, Resource)]
#[serde(deny_unknown_fields)]
pub struct Frictional {
    /// The surface friction coefficient `mu_surf` (the paper uses 0.1).
    pub friction: f64,
    /// Where the contact normal comes from; default `Common`.
    #[serde(default)]
    pub normal: NormalRule,
}

/// How the contact normal at a node is made.
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
pub enum NormalRule {
    /// From the difference of the bodies' mass gradients (Huang et al.): symmetric, but
    /// diagonal at a body's corners, where it reads a flat surface as an obstacle.
    #[default]
    Common,
    /// From the named body's mass gradient alone, for every body in contact with it: exact
    /// for a flat or smooth body (a slab, an intruder) whatever the other's corners.
    Body(String),
}

impl Item for Frictional {
    const NAME: &'static str = "Frictional";
    fn validate(&self) -> Result<(), String> {
        if self.friction.is_finite() && self.friction >= 0.0 {
            Ok(())
        } else {
            Err(format!(
                "the contact friction must be a non-negative number, got {}",
                self.friction
            ))
        }
    }
}

impl Contact for Frictional {
    /// The common normal needs every body's gradient. A named normal needs only the named
    /// body's when there are two bodies: wherever it is absent from a shared node only one
    /// body is present, which gets no impulse whatever its normal. With three or more, a
    /// node without the named body falls back to the common normal of the others, so every
    /// body keeps its gradient. Leaving the unused gradients out saves one of the bed's four
    /// accumulations per node in the scatter, and its clear, in the paper's scenes (all name
    /// their intruder).
    fn needs_normal_of(&self, body: &str, bodies: usize) -> bool {
        match &self.normal {
            NormalRule::Common => bodies > 1,
            NormalRule::Body(named) => bodies > 2 || (bodies == 2 && named == body),
        }
    }
    fn normal_body(&self) -> Option<&str> {
        match &self.normal {
            NormalRule::Common => None,
            NormalRule::Body(name) => Some(name),
        }
    }
    fn system(&self) -> ScheduleConfigs<ScheduleSystem> {
        frictional.into_configs()
    }
    fn insert_resources(&self, world: &mut World) {
        world.insert_resource(self.clone());
    }
}

/// One body's trial state at one node.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NodeBody {
    pub mass: f64,
    /// Trial momentum `p~ = p + dt f`.
    pub momentum: DVec2,
    /// Mass gradient `sum_p m_p grad S_i(x_p)`: at a surface node it points out of the body.
    pub mass_gradient: DVec2,
}

/// The momentum changes frictional contact makes at one node, one per body (zero for bodies
/// that are separating or have no defined normal). With `reference`, every normal comes from
/// that body's mass gradient alone; otherwise from the difference of gradients. Normals
/// closer to zero than `normal_tolerance` are treated as undefined.
pub fn frictional_impulses(
    bodies: &[NodeBody],
    friction: f64,
    reference: Option<usize>,
    normal_tolerance: f64,
    out: &mut [DVec2],
) {
    let mass: f64 = bodies.iter().map(|b| b.mass).sum();
    let momentum: DVec2 = bodies.iter().map(|b| b.momentum).sum();
    let gradient: DVec2 = bodies.iter().map(|b| b.mass_gradient).sum();
    let v_cm = momentum / mass;
    for ((k, b), out) in bodies.iter().enumerate().zip(out.iter_mut()) {
        *out = {
            // `sum m grad S_i(x_p)` points out of a body (from its points towards the node):
            // b's points towards the others, theirs towards b, so the difference is the
            // common normal from b into the others.
            let towards = match reference {
                Some(r) if r == k => b.mass_gradient,
                Some(r) => -bodies[r].mass_gradient,
                None => b.mass_gradient - (gradient - b.mass_gradient),
            };
            let len = towards.length();
            if len <= normal_tolerance {
                *out = DVec2::ZERO;
                continue;
            }
            let n = towards / len;
            let dv = b.momentum / b.mass - v_cm;
            let approach = dv.dot(n);
            if approach <= 0.0 {
                *out = DVec2::ZERO;
                continue;
            }
            let tangential = dv - approach * n;
            let slip = tangential.length();
            let limit = friction * approach;
            let kept = if slip > limit { limit / slip } else { 1.0 };
            -b.mass * (approach * n + kept * tangential)
        };
    }
}

/// Per-node sums and per-body copies the contact systems keep from step to step, so that a
/// step allocates nothing once they have grown.
#[derive(Default)]
pub struct ContactScratch {
    /// Per node: bodies above their mass tolerance there.
    sharing: Vec<u8>,
    /// The nodes two or more bodies share: the only ones either law acts on.
    shared: Vec<usize>,
    /// Per shared node: total mass, momentum and force (no-slip law).
    mass: Vec<f64>,
    momentum: Vec<DVec2>,
    force: Vec<DVec2>,
    /// Per body and shared node (`body * shared + k`): the state read and the impulse to
    /// apply.
    state: Vec<NodeBody>,
    present: Vec<bool>,
    impulse: Vec<DVec2>,
    named: Vec<bool>,
    /// Per node, the bodies there (reused).
    at_node: Vec<NodeBody>,
    which: Vec<usize>,
    out: Vec<DVec2>,
}

impl ContactScratch {
    /// Finds the nodes two or more bodies share (a few hundred against the whole grid) into
    /// `shared`. Capacity for the worst case (every node shared) is reserved up front: the
    /// count changes from step to step, and growing mid-run would allocate in a step.
    fn find_shared<'a>(&mut self, fields: impl Iterator<Item = &'a GridField>, nodes: usize) {
        self.sharing.clear();
        self.sharing.resize(nodes, 0);
        for f in fields {
            for (sharing, &m) in self.sharing.iter_mut().zip(&f.mass) {
                if m > f.mass_tolerance {
                    *sharing = sharing.saturating_add(1);
                }
            }
        }
        self.shared.clear();
        self.shared.reserve(nodes);
        let sharing = &self.sharing;
        self.shared.extend((0..nodes).filter(|&n| sharing[n] >= 2));
    }
}

/// Adds the contact force that gives every body at a shared node the common velocity.
pub fn no_slip(
    clock: Res<Clock>,
    mut scratch: Local<ContactScratch>,
    mut fields: Query<&mut GridField>,
) {
    let dt = clock.dt;
    let s = &mut *scratch;
    let nodes = fields.iter().next().map_or(0, |f| f.mass.len());
    s.find_shared(fields.iter(), nodes);
    s.mass.clear();
    s.mass.reserve(nodes);
    s.mass.resize(s.shared.len(), 0.0);
    s.momentum.clear();
    s.momentum.reserve(nodes);
    s.momentum.resize(s.shared.len(), DVec2::ZERO);
    s.force.clear();
    s.force.reserve(nodes);
    s.force.resize(s.shared.len(), DVec2::ZERO);
    for f in fields.iter() {
        for (k, &n) in s.shared.iter().enumerate() {
            if f.mass[n] > f.mass_tolerance {
                s.mass[k] += f.mass[n];
                s.momentum[k] += f.momentum[n];
                s.force[k] += f.force[n];
            }
        }
    }
    for mut f in fields.iter_mut() {
        for (k, &n) in s.shared.iter().enumerate() {
            if f.mass[n] > f.mass_tolerance {
                let v_cm = s.momentum[k] / s.mass[k];
                let impulse = f.mass[n] * v_cm - f.momentum[n];
                apply_impulse(&mut f, n, impulse, dt);
                f.acceleration[n] = s.force[k] / s.mass[k];
            }
        }
    }
}

/// Adds `impulse` to a body's momentum at node `n` as a force over the step.
fn apply_impulse(f: &mut GridField, n: usize, impulse: DVec2, dt: f64) {
    let m = f.mass[n];
    f.contact_force += impulse / dt;
    f.force[n] += impulse / dt;
    f.momentum[n] += impulse;
    f.velocity[n] = f.momentum[n] / m;
    f.acceleration[n] = f.force[n] / m;
}

/// The frictional contact law, with walls applied again afterwards (a contact normal that
/// is not parallel to a wall could otherwise push a wall node through it). Bodies are read
/// into the scratch, impulses computed node by node, then applied body by body (the query
/// visits bodies in the same order both times).
pub fn frictional(
    clock: Res<Clock>,
    contact: Res<Frictional>,
    grid: Res<GridGeometry>,
    walls: Res<Boundaries>,
    obstacles: Res<Obstacles>,
    mut scratch: Local<ContactScratch>,
    mut bodies: Query<(&Body, &mut GridField)>,
) {
    let Frictional { friction, normal } = &*contact;
    let (friction, dt) = (*friction, clock.dt);
    let s = &mut *scratch;
    let nodes = bodies.iter().next().map_or(0, |(_, f)| f.mass.len());
    let count = bodies.iter().count();
    // Only the shared nodes are read into the scratch (capacity for all, as in
    // `find_shared`).
    s.find_shared(bodies.iter().map(|(_, f)| f), nodes);
    let shared = s.shared.len();
    s.state.clear();
    s.state.reserve(count * nodes);
    s.present.clear();
    s.present.reserve(count * nodes);
    s.named.clear();
    for (body, f) in bodies.iter() {
        s.named
            .push(matches!(normal, NormalRule::Body(n) if *n == body.name));
        for &n in &s.shared {
            s.present.push(f.mass[n] > f.mass_tolerance);
            s.state.push(NodeBody {
                mass: f.mass[n],
                momentum: f.momentum[n],
                // Empty for a body whose gradient the rule never uses (`needs_normal_of`).
                mass_gradient: f.mass_gradient.get(n).copied().unwrap_or(DVec2::ZERO),
            });
        }
    }
    // Per body and shared node (`body * shared + k`).
    s.impulse.clear();
    s.impulse.reserve(count * nodes);
    s.impulse.resize(count * shared, DVec2::ZERO);
    for k in 0..shared {
        s.at_node.clear();
        s.which.clear();
        for b in 0..count {
            if s.present[b * shared + k] {
                s.at_node.push(s.state[b * shared + k]);
                s.which.push(b);
            }
        }
        // A normal is undefined when the mass gradients nearly cancel: below a millionth
        // of the typical gradient magnitude m / h at this node.
        let scale: f64 = s.at_node.iter().map(|b| b.mass).sum::<f64>() / grid.cell_size;
        let reference = s.which.iter().position(|&b| s.named[b]);
        s.out.clear();
        s.out.resize(s.at_node.len(), DVec2::ZERO);
        frictional_impulses(&s.at_node, friction, reference, 1e-6 * scale, &mut s.out);
        for (&b, &impulse) in s.which.iter().zip(s.out.iter()) {
            s.impulse[b * shared + k] = impulse;
        }
    }
    for (b, (_, mut f)) in bodies.iter_mut().enumerate() {
        for (k, &n) in s.shared.iter().enumerate() {
            let impulse = s.impulse[b * shared + k];
            if impulse != DVec2::ZERO {
                apply_impulse(&mut f, n, impulse, dt);
            }
        }
        apply_walls(&grid, &walls.0, &obstacles, &mut f, Some(dt));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn body(m: f64, v: DVec2, g: DVec2) -> NodeBody {
        NodeBody {
            mass: m,
            momentum: m * v,
            mass_gradient: g,
        }
    }

    #[test]
    fn separating_bodies_feel_nothing() {
        // A above (its outward normal at the node points down), moving up; B below, at rest.
        let a = body(1.0, DVec2::new(0.3, 1.0), DVec2::new(0.0, -2.0));
        let b = body(2.0, DVec2::ZERO, DVec2::new(0.0, 3.0));
        let mut dp = [DVec2::ONE; 2];
        frictional_impulses(&[a, b], 0.5, None, 1e-12, &mut dp);
        assert_eq!(dp, [DVec2::ZERO; 2]);
    }

    #[test]
    fn frictionless_contact_removes_only_the_normal_approach() {
        let a = body(1.0, DVec2::new(0.7, -1.0), DVec2::new(0.0, -2.0));
        let b = body(3.0, DVec2::ZERO, DVec2::new(0.0, 3.0));
        let mut dp = [DVec2::ZERO; 2];
        frictional_impulses(&[a, b], 0.0, None, 1e-12, &mut dp);
        assert!(dp[0].x.abs() < 1e-15 && dp[1].x.abs() < 1e-15);
        // A's normal velocity becomes the common one: v_cm,y = -1/4.
        assert!(((a.momentum.y + dp[0].y) / a.mass + 0.25).abs() < 1e-15);
        assert!((dp[0] + dp[1]).length() < 1e-15);
    }
}
