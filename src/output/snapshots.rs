//! `Snapshots(every: 0.01)` or `Snapshots(at: [0.0, 0.025, 0.078])`: every material point's
//! state as CSV at a fixed interval or at listed times.
//!
//! Files go to `<out>/snapshots/snapshot_NNNNN.csv` with columns
//! `t,body,x,y,vx,vy,mass,volume,pressure,shear_stress,plastic_strain_rate,plastic_strain,phase`
//! (phase: 0 solid, 1 flowing, 2 disconnected); they feed figures and external
//! analysis. The built-in output registers like a user's.

use std::fmt::Write as _;

use bevy_ecs::prelude::*;
use serde::Deserialize;

use super::{Output, OutputFaults, RunDir, Timing, write_or_fault};
use crate::body::{Body, PointStates, Points};
use crate::carry::{Carried, carried, restored};
use crate::format::Num;
use crate::plugin::Install;
use crate::registry::Item;
use crate::resources::Clock;
use crate::step::StepSet;

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Snapshots {
    /// Interval between snapshots (s).
    #[serde(default)]
    pub every: Option<f64>,
    /// Or the times to take them at (s), increasing.
    #[serde(default)]
    pub at: Option<Vec<f64>>,
}

#[derive(Resource, Debug)]
struct SnapshotClock {
    when: Timing,
    count: usize,
}

impl Item for Snapshots {
    const NAME: &'static str = "Snapshots";
    fn validate(&self) -> Result<(), String> {
        Timing::check(self.every, self.at.as_deref())
    }
}

impl Output for Snapshots {
    fn install(&self, sim: &mut Install) {
        let when = Timing::new(self.every, self.at.as_deref());
        sim.insert_resource(SnapshotClock { when, count: 0 });
        sim.add_systems(StepSet::Output, write_snapshot);
    }

    /// The schedule and the number of the next file.
    fn save(&self, world: &World) -> Carried {
        let c = world.resource::<SnapshotClock>();
        carried(&(&c.when, c.count))
    }

    fn restore(&self, world: &mut World, state: &[u8]) -> Result<(), String> {
        let mut c = world.resource_mut::<SnapshotClock>();
        (c.when, c.count) = restored(state)?;
        Ok(())
    }
}

fn write_snapshot(
    clock: Res<Clock>,
    dir: Res<RunDir>,
    mut snap: ResMut<SnapshotClock>,
    faults: Res<OutputFaults>,
    bodies: Query<(&Body, &Points, &PointStates)>,
) {
    if !snap.when.due(&clock) {
        return;
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
                "{},{},{},{},{},{},{},{},{},{},{},{},{}",
                Num(clock.time),
                body.name,
                Num(x.x),
                Num(x.y),
                Num(v.x),
                Num(v.y),
                Num(p.mass[k]),
                Num(p.volume[k]),
                Num(s.pressure()),
                Num(s.equivalent_shear()),
                Num(st.plastic_strain_rate[k]),
                Num(st.plastic_strain[k]),
                st.phase[k].code()
            );
        }
    }
    let folder = dir.join("snapshots");
    let path = folder.join(format!("snapshot_{:05}.csv", snap.count));
    snap.count += 1;
    if let Err(e) = std::fs::create_dir_all(&folder) {
        faults.report(&clock, format!("cannot create {}: {e}", folder.display()));
        return;
    }
    write_or_fault(&path, csv.as_bytes(), &clock, &faults);
}
