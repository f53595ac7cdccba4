//! A plugin's own system may move points, and the step stays exact and sound.
//!
//! The scatter runs bands of points in parallel without locks, trusting that each point's
//! footprint lies in its band's node rows. The bands are found after the points move and
//! reused by the next step, so a system that moves points in between (a driven intruder, a
//! prescribed displacement) leaves them stale unless the step notices. It notices through
//! bevy's change detection, and the scatter checks every point against its band before it
//! writes (a stale band is a panic, never a data race). Before change detection, this test
//! hit that check: cells found before the plugin's move were reused.

use regolith::bevy_ecs::prelude::*;
use regolith::body::Points;
use regolith::grid::GridGeometry;
use regolith::resources::Clock;
use regolith::step::StepSet;
use regolith::{Plugin, Regolith, Scene, Simulation};

/// Every point moves 0.4 cells up on even steps and down on odd ones: enough to change the
/// cell, and the band, of many points at every step.
fn shift(step: u64, h: f64) -> f64 {
    if step.is_multiple_of(2) {
        0.4 * h
    } else {
        -0.4 * h
    }
}

fn shake(clock: Res<Clock>, grid: Res<GridGeometry>, mut bodies: Query<&mut Points>) {
    let dy = shift(clock.step, grid.cell_size);
    for mut points in &mut bodies {
        for x in &mut points.position {
            x.y += dy;
        }
    }
}

/// Adds `shake` at the start of every step, through the plugin API.
struct Shake;

impl Plugin for Shake {
    fn build(&self, app: &mut Regolith) {
        app.add_systems(StepSet::Prepare, shake);
    }
}

fn scene(app: Regolith) -> Scene {
    let sets: Vec<String> = [
        "domain.cells=(40, 40)",
        "time=(end: 1.0, step: Cfl(0.5), output_every: 1.0)",
    ]
    .map(String::from)
    .to_vec();
    Scene::load(
        &crate::common::scene_path("bench_contact"),
        &sets,
        &app.registries(),
    )
    .unwrap()
    .0
}

#[test]
fn points_moved_by_a_plugin_system_are_located_again() {
    const STEPS: usize = 40;
    let mut driven = Simulation::new(&scene(Regolith::default().add_plugin(Shake)));
    // The reference moves the same points from outside the schedule, where the cells are
    // found again for certain (`points_mut` discards them).
    let mut reference = Simulation::new(&scene(Regolith::default()));
    let h = reference.grid().cell_size;
    for _ in 0..STEPS {
        driven.step().unwrap();
        let dy = shift(reference.clock().step, h);
        for name in ["bed", "disc"] {
            for x in &mut reference.points_mut(name).unwrap().position {
                x.y += dy;
            }
        }
        reference.step().unwrap();
    }
    assert!(driven.clock().step as usize == STEPS);
    for name in ["bed", "disc"] {
        assert_eq!(
            driven.points(name).unwrap().fingerprint(),
            reference.points(name).unwrap().fingerprint(),
            "{name}: the plugin's move gave another state than the same move made outside"
        );
    }
}

/// Moves every point three cells up without telling change detection, which safe code may
/// do (`bypass_change_detection`): the scatter must refuse the stale bands, not race.
fn hide_a_move(grid: Res<GridGeometry>, mut bodies: Query<&mut Points>) {
    for mut points in &mut bodies {
        for x in &mut points.bypass_change_detection().position {
            x.y += 3.0 * grid.cell_size;
        }
    }
}

struct HiddenMove;

impl Plugin for HiddenMove {
    fn build(&self, app: &mut Regolith) {
        app.add_systems(StepSet::Diagnostics, hide_a_move);
    }
}

#[test]
#[should_panic(expected = "reaches outside the nodes of its band")]
fn a_move_hidden_from_change_detection_stops_the_scatter() {
    let mut sim = Simulation::new(&scene(Regolith::default().add_plugin(HiddenMove)));
    for _ in 0..3 {
        sim.step().unwrap();
    }
}
