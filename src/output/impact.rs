//! Impact diagnostics as the paper defines them (section 4.2), from an intruder's
//! centre-of-mass trajectory, and whether the run measured them at all.
//!
//! * first contact: the start of the first step in which the bed pushed on the intruder
//!   through the grid (its contact force was not zero), the same interaction the physics
//!   sees. It is about a cell before the outlines touch, because bodies interact wherever
//!   they share nodes; `contact_gap` says how far above `surface` the intruder's lowest
//!   point was then. The speed and energy are the intruder's at that instant, before the
//!   bed acted on it;
//! * final depth: the vertical displacement of the centre of mass from first contact to the
//!   end of the run;
//! * stopping time: the last time the position differs from its final value by more than
//!   0.2% of the final depth (measured from first contact);
//! * peak deceleration: the largest upward acceleration after contact, from the
//!   centre-of-mass velocity differenced between output rows (so it is the mean over one
//!   output interval; a finer `output_every` resolves sharper peaks).
//!
//! The final depth and the stopping time mean something only if the intruder stopped
//! before the run ended. It is **at rest** when both hold: its speed at the end is below
//! [`REST_SPEED_FRACTION`] of its speed at first contact, and it stayed inside the 0.2% band
//! for the last [`REST_WINDOW_FRACTION`] of the time since first contact. Otherwise
//! `final_depth` and `stopping_time` are null, `not_at_rest` says why, and `depth_at_end`
//! is the displacement so far (provisional).
//!
//! A scene asks for them with the output `Impact(body: "intruder", surface: 0.6825)`; the
//! body must exist and be tracked (`check` refuses otherwise). They appear in
//! `summary.json` under `impact`, with their units under `units`.

use bevy_ecs::prelude::*;
use glam::DVec2;
use serde::{Deserialize, Serialize};

use crate::body::{BodyState, Points};
use crate::carry::{Carried, carried, restored};
use crate::grid::GridField;
use crate::output::Output;
use crate::output::summary::Section;
use crate::output::trajectory::Trajectory;
use crate::plugin::Install;
use crate::registry::Item;
use crate::resources::Clock;
use crate::scene_view::SceneView;

/// At rest: the final speed is below this fraction of the speed at first contact.
pub const REST_SPEED_FRACTION: f64 = 0.01;
/// At rest: the position stayed in the 0.2% band for this last fraction of the time since
/// first contact. The speed alone cannot tell a stop from the turning point of a bounce;
/// a turning point under a deceleration `a` leaves the band (`a dt^2 / 2` against 0.2% of
/// the depth, under a millimetre) within milliseconds, a tenth of a 0.3 s run.
pub const REST_WINDOW_FRACTION: f64 = 0.1;
/// The paper's band around the final position that defines the stopping time.
const BAND: f64 = 0.002;

/// The paper's impact measures, and whether they hold.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ImpactMetrics {
    pub contact_time: f64,
    /// Speed of the centre of mass at first contact.
    pub contact_speed: f64,
    /// Height of the intruder's lowest point above `surface` at first contact.
    pub contact_gap: f64,
    /// Kinetic energy at first contact, per metre of thickness.
    pub impact_energy: f64,
    pub at_rest: bool,
    /// Why the intruder is not at rest (then `final_depth` and `stopping_time` are null).
    pub not_at_rest: Option<String>,
    pub final_depth: Option<f64>,
    pub stopping_time: Option<f64>,
    /// The displacement from first contact to the end of the run, at rest or not.
    pub depth_at_end: f64,
    pub speed_at_end: f64,
    pub peak_deceleration: f64,
}

/// The units of the fields of `summary.json`'s `impact` (written beside it as `units`).
pub const UNITS: [(&str, &str); 9] = [
    ("contact_time", "s"),
    ("contact_speed", "m/s"),
    ("contact_gap", "m"),
    ("impact_energy", "J/m (per metre of thickness)"),
    ("final_depth", "m"),
    ("stopping_time", "s (from first contact)"),
    ("depth_at_end", "m"),
    ("speed_at_end", "m/s"),
    ("peak_deceleration", "m/s^2"),
];

/// The intruder's state at an instant: at first contact, the start of the first step in
/// contact.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ContactInstant {
    pub time: f64,
    pub centre_of_mass: [f64; 2],
    pub velocity: [f64; 2],
    /// Height of the lowest point (the bottom of its domain) at that instant.
    pub lowest: f64,
}

/// Computes the measures from output rows `(t, y, vx, vy)` of the centre of mass, the
/// instant of first contact, the height of `surface` and the intruder's mass per unit
/// thickness. `None` with fewer than two rows after contact.
pub fn analyse(
    rows: (&[f64], &[f64], &[f64], &[f64]),
    contact: &ContactInstant,
    surface: f64,
    mass: f64,
) -> Option<ImpactMetrics> {
    let (t, y, vx, vy) = rows;
    let n = t.len();
    let first = t.iter().position(|&t| t >= contact.time - 1e-12)?;
    if first + 1 >= n {
        return None;
    }
    let y0 = contact.centre_of_mass[1];
    let final_y = y[n - 1];
    let depth = y0 - final_y;
    let tolerance = BAND * depth.abs();
    let last_away = (first..n)
        .rev()
        .find(|&k| (y[k] - final_y).abs() > tolerance);
    let stopping = last_away.map_or(0.0, |k| t[k] - contact.time);
    let peak = (first + 1..n)
        .map(|k| (vy[k] - vy[k - 1]) / (t[k] - t[k - 1]))
        .fold(0.0, f64::max);
    let v0 = DVec2::from(contact.velocity).length();
    let speed_at_end = DVec2::new(vx[n - 1], vy[n - 1]).length();
    let since = t[n - 1] - contact.time;
    let mut why = Vec::new();
    if speed_at_end > REST_SPEED_FRACTION * v0 {
        why.push(format!(
            "its speed at the end is {speed_at_end:.3} m/s, above {}% of its {v0:.3} m/s at first contact",
            100.0 * REST_SPEED_FRACTION
        ));
    }
    if stopping > (1.0 - REST_WINDOW_FRACTION) * since {
        why.push(format!(
            "it left the {}% band around its final position {stopping:.4} s after first contact, within the last {}% of the {since:.4} s the run followed it",
            100.0 * BAND,
            100.0 * REST_WINDOW_FRACTION
        ));
    }
    let at_rest = why.is_empty();
    Some(ImpactMetrics {
        contact_time: contact.time,
        contact_speed: v0,
        contact_gap: contact.lowest - surface,
        impact_energy: 0.5 * mass * v0 * v0,
        at_rest,
        not_at_rest: (!at_rest).then(|| why.join("; ")),
        final_depth: at_rest.then_some(depth),
        stopping_time: at_rest.then_some(stopping),
        depth_at_end: depth,
        speed_at_end,
        peak_deceleration: peak,
    })
}

/// `Impact(body: "intruder", surface: 0.6825)`: records the measures for `summary.json`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Impact {
    /// The impacting body (it must be `tracked`).
    pub body: String,
    /// Height of the free surface the body hits (m).
    pub surface: f64,
}

/// What the `Impact` output watches, and the instant of first contact once it happened
/// (carried over checkpoints).
#[derive(Resource, Clone, Debug)]
pub struct ImpactWatch {
    pub body: String,
    /// The body's entity, found at install.
    pub entity: Option<Entity>,
    pub surface: f64,
    pub contact: Option<ContactInstant>,
    /// Before contact, the body's state at the end of the last step (the start of the
    /// next).
    pub before: Option<ContactInstant>,
}

impl ContactInstant {
    /// The state of `points` (whole-body `state`) at `time`.
    fn of(time: f64, state: &BodyState, points: &Points) -> ContactInstant {
        let lowest = (0..points.len())
            .map(|k| points.position[k].y - points.half_width[k])
            .fold(f64::INFINITY, f64::min);
        ContactInstant {
            time,
            centre_of_mass: state.centre_of_mass.to_array(),
            velocity: state.velocity.to_array(),
            lowest,
        }
    }
}

/// Records the start of the first step at whose end the watched body feels a contact
/// force, and until then the state each step ends with.
pub fn record_first_contact(
    clock: Res<Clock>,
    mut watch: ResMut<ImpactWatch>,
    bodies: Query<(&BodyState, &Points, &GridField)>,
) {
    if watch.contact.is_some() {
        return;
    }
    let Some((state, points, field)) = watch.entity.and_then(|e| bodies.get(e).ok()) else {
        return;
    };
    if field.contact_force == DVec2::ZERO {
        watch.before = Some(ContactInstant::of(clock.time, state, points));
    } else {
        watch.contact = watch.before;
    }
}

impl Item for Impact {
    const NAME: &'static str = "Impact";
    fn validate(&self) -> Result<(), String> {
        if self.body.is_empty() {
            return Err("body must name the impacting body".into());
        }
        if !self.surface.is_finite() {
            return Err(format!(
                "surface must be a finite height (m), got {}",
                self.surface
            ));
        }
        Ok(())
    }
}

impl Output for Impact {
    /// `impact`: the measures of [`analyse`], or `null` with `impact_not_measured` saying
    /// why (the body never touched, too few rows after contact).
    fn summary(&self, world: &World) -> Section {
        let (impact, why) = match measure(world) {
            Some(Ok(m)) => (Some(m), None),
            Some(Err(why)) => (None, Some(why)),
            None => (None, None),
        };
        let mut section = Section::entry("impact", serde_json::json!(impact));
        section
            .entries
            .insert("impact_not_measured".into(), serde_json::json!(why));
        section.units = UNITS
            .iter()
            .map(|&(k, u)| (format!("impact.{k}"), u.to_string()))
            .collect();
        section.headline = Some(match (&impact, &why) {
            (Some(m), _) => headline(m),
            (None, Some(why)) => format!("impact: not measured: {why}"),
            (None, None) => "impact: not measured".to_string(),
        });
        section
    }

    fn check_scene(&self, scene: &SceneView) -> Result<(), String> {
        if !scene.body(&self.body)?.tracked {
            return Err(format!(
                "body \"{}\" must be tracked (tracked: true) so that its trajectory is recorded",
                self.body
            ));
        }
        Ok(())
    }

    fn install(&self, sim: &mut Install) {
        let entity = sim.body(&self.body);
        let world = sim.world();
        let time = world.get_resource::<Clock>().map_or(0.0, |c| c.time);
        let start = entity
            .and_then(|e| world.get::<Points>(e))
            .map(|p| ContactInstant::of(time, &BodyState::measure(p), p));
        sim.insert_resource(ImpactWatch {
            body: self.body.clone(),
            entity,
            surface: self.surface,
            contact: None,
            before: start,
        });
        sim.add_systems(crate::step::StepSet::Output, record_first_contact);
    }

    /// The first contact, once seen, and the state the body ended the last step with.
    fn save(&self, world: &World) -> Carried {
        let watch = world.resource::<ImpactWatch>();
        carried(&(watch.contact, watch.before))
    }

    fn restore(&self, world: &mut World, state: &[u8]) -> Result<(), String> {
        let mut watch = world.resource_mut::<ImpactWatch>();
        (watch.contact, watch.before) = restored(state)?;
        Ok(())
    }
}
/// The impact measures from the trajectory rows and the recorded first contact: `None`
/// without an `Impact` output's watch, `Some(Err(why))` when they could not be measured.
fn measure(world: &World) -> Option<Result<ImpactMetrics, String>> {
    let watch = world.get_resource::<ImpactWatch>()?;
    let table = world.get_resource::<Trajectory>()?;
    let now = world.get_resource::<Clock>().map_or(0.0, |c| c.time);
    let mass = watch
        .entity
        .and_then(|e| world.get::<BodyState>(e))
        .map(|s| s.mass);
    let series = |q: &str| {
        table
            .column(&watch.body, q)
            .map(|c| table.series(c))
            .ok_or_else(|| format!("the trajectory has no column {}_{q}", watch.body))
    };
    let measured = || {
        let (y, vx, vy) = (series("y")?, series("vx")?, series("vy")?);
        let contact = watch.contact.ok_or_else(|| {
            format!(
                "body \"{}\" felt no contact force before the run ended at t = {} s",
                watch.body,
                crate::format::Seconds(now)
            )
        })?;
        let mass = mass.ok_or_else(|| format!("no body \"{}\"", watch.body))?;
        analyse(
            (&table.series(0), &y, &vx, &vy),
            &contact,
            watch.surface,
            mass,
        )
        .ok_or_else(|| {
            format!(
                "fewer than two trajectory rows after first contact at t = {} s",
                crate::format::Seconds(contact.time)
            )
        })
    };
    Some(measured())
}

/// The impact result in one line.
fn headline(m: &ImpactMetrics) -> String {
    let contact = format!(
        "first contact at {:.4} s, {:.3} m/s, {:.2} J/m",
        m.contact_time, m.contact_speed, m.impact_energy
    );
    match (m.final_depth, m.stopping_time) {
        (Some(depth), Some(stop)) => format!(
            "impact: at rest; final depth {depth:.4} m, stopping time {stop:.4} s ({contact})"
        ),
        _ => format!(
            "impact: NOT at rest, no final depth or stopping time: {} (depth so far {:.4} m; {contact})",
            m.not_at_rest.as_deref().unwrap_or_default(),
            m.depth_at_end
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_constant_deceleration_is_measured_exactly() {
        // y = y0 - v0 t + a t^2 / 2 until it stops at t = v0 / a, then rest.
        let (y0, v0, a) = (1.0, 3.0, 20.0);
        let stop = v0 / a;
        let t: Vec<f64> = (0..=400).map(|k| k as f64 * 1e-3).collect();
        let y: Vec<f64> = t
            .iter()
            .map(|&t| {
                let s = t.min(stop);
                y0 - v0 * s + 0.5 * a * s * s
            })
            .collect();
        let vy: Vec<f64> = t
            .iter()
            .map(|&t| if t < stop { -v0 + a * t } else { 0.0 })
            .collect();
        let vx = vec![0.0; t.len()];
        let contact = ContactInstant {
            time: 0.0,
            centre_of_mass: [0.0, y0],
            velocity: [0.0, -v0],
            lowest: y0 - 0.1,
        };
        let m = analyse((&t, &y, &vx, &vy), &contact, y0 - 0.1, 2.0).unwrap();
        assert!(m.at_rest, "{:?}", m.not_at_rest);
        assert_eq!(m.contact_gap, 0.0);
        assert!((m.final_depth.unwrap() - v0 * v0 / (2.0 * a)).abs() < 1e-12);
        assert!((m.impact_energy - 9.0).abs() < 1e-12);
        assert!((m.peak_deceleration - a).abs() < 1e-9);
        // the last row further than 0.2% of the depth from rest: (v0 - a t)^2 / 2a > 0.002 d
        let expected = stop - (2.0 * a * 0.002 * m.depth_at_end).sqrt() / a;
        let stopping = m.stopping_time.unwrap();
        assert!(
            (stopping - expected).abs() < 2e-3,
            "{stopping} vs {expected}"
        );
    }

    #[test]
    fn a_run_that_ends_while_the_intruder_moves_has_no_final_depth() {
        // Constant deceleration cut off at half the stopping time.
        let (v0, a) = (3.0, 20.0);
        let t: Vec<f64> = (0..=75).map(|k| k as f64 * 1e-3).collect();
        let y: Vec<f64> = t.iter().map(|&t| 1.0 - v0 * t + 0.5 * a * t * t).collect();
        let vy: Vec<f64> = t.iter().map(|&t| -v0 + a * t).collect();
        let vx = vec![0.0; t.len()];
        let contact = ContactInstant {
            time: 0.0,
            centre_of_mass: [0.0, 1.0],
            velocity: [0.0, -v0],
            lowest: 0.9,
        };
        let m = analyse((&t, &y, &vx, &vy), &contact, 0.9, 2.0).unwrap();
        assert!(!m.at_rest);
        assert_eq!((m.final_depth, m.stopping_time), (None, None));
        let why = m.not_at_rest.unwrap();
        assert!(why.contains("1.500 m/s") && why.contains("band"), "{why}");
        assert!((m.depth_at_end - (v0 * 0.075 - 0.5 * a * 0.075 * 0.075)).abs() < 1e-12);
    }
}
