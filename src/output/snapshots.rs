//! `Snapshots(every: 0.01)`: every material point's state as CSV at a fixed interval.
//!
//! Files go to `<out>/snapshots/snapshot_NNNNN.csv` with columns
//! `t,body,x,y,vx,vy,mass,volume,pressure,shear_stress,plastic_strain_rate,plastic_strain,phase`
//! (phase: 0 solid, 1 flowing, 2 disconnected); they feed figures and external
//! analysis. The built-in output registers through [`super::OutputPlugin`] like a user's.

use std::fmt::Write as _;

use bevy_ecs::prelude::*;
use serde::Deserialize;

use super::{Output, RunDir, write_atomic};
use crate::body::{Body, PointStates, Points};
use crate::sim::Clock;
use crate::step::StepSet;

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Snapshots {
    /// Interval between snapshots (s).
    pub every: f64,
}

#[derive(Resource, Debug)]
struct SnapshotClock {
    every: f64,
    next: f64,
    count: usize,
}

impl Output for Snapshots {
    const NAME: &'static str = "Snapshots";

    fn validate(&self) -> Result<(), String> {
        if self.every.is_finite() && self.every > 0.0 {
            Ok(())
        } else {
            Err(format!(
                "every must be a positive number of seconds, got {}",
                self.every
            ))
        }
    }

    fn install(&self, world: &mut World, schedule: &mut Schedule) {
        world.insert_resource(SnapshotClock {
            every: self.every,
            next: 0.0,
            count: 0,
        });
        schedule.add_systems(write_snapshot.in_set(StepSet::Output));
    }

    /// Snapshots were written at 0, every, 2 every, ... up to `time`.
    fn resume(&self, world: &mut World, time: f64) {
        let done = (time / self.every + 1e-9).floor() as usize + 1;
        let mut clock = world.resource_mut::<SnapshotClock>();
        clock.count = done;
        clock.next = done as f64 * self.every;
    }
}

fn write_snapshot(
    clock: Res<Clock>,
    dir: Res<RunDir>,
    mut snap: ResMut<SnapshotClock>,
    mut health: ResMut<crate::diagnostics::Health>,
    bodies: Query<(&Body, &Points, &PointStates)>,
) {
    let eps = 1e-9 * snap.every;
    if !(clock.observing || clock.last_step || clock.time >= snap.next - eps) {
        return;
    }
    while snap.next <= clock.time + eps {
        snap.next += snap.every;
    }
    let Some(dir) = &dir.0 else { return };
    let mut sorted: Vec<_> = bodies.iter().collect();
    sorted.sort_by_key(|(b, _, _)| b.index);
    let mut csv = String::from(
        "t,body,x,y,vx,vy,mass,volume,pressure,shear_stress,plastic_strain_rate,plastic_strain,phase\n",
    );
    for (body, p, st) in sorted {
        for k in 0..p.len() {
            let (x, v, s) = (p.position[k], p.velocity[k], p.stress[k]);
            let _ = writeln!(
                csv,
                "{:e},{},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{}",
                clock.time,
                body.name,
                x.x,
                x.y,
                v.x,
                v.y,
                p.mass[k],
                p.volume[k],
                s.pressure(),
                s.equivalent_shear(),
                st.plastic_strain_rate[k],
                st.plastic_strain[k],
                st.phase[k].code()
            );
        }
    }
    let folder = dir.join("snapshots");
    let path = folder.join(format!("snapshot_{:05}.csv", snap.count));
    snap.count += 1;
    let result = std::fs::create_dir_all(&folder).and_then(|_| write_atomic(&path, csv.as_bytes()));
    if let Err(e) = result {
        health.fault.get_or_insert(crate::error::Fault {
            step: clock.step,
            time: clock.time,
            message: format!("cannot write {}: {e}", path.display()),
        });
    }
}
