//! The step's order is the table at the top of `src/schedule.rs`: for every combination of
//! the options that choose core systems (shape functions, stress update, dilatation,
//! transfer, spacing, contact, materials, a listed field) the step is built, and the systems
//! it runs, set by set, are held against the table read from that file. ARCHITECTURE.md
//! names the same sets in the same order.

use bevy_ecs::prelude::*;
use bevy_ecs::schedule::ScheduleConfigs;
use bevy_ecs::system::ScheduleSystem;
use bevy_ecs::world::EntityWorldMut;
use regolith::contact::{Contact, Frictional, NoSlip};
use regolith::field::Field;
use regolith::grid_field::FieldColumns;
use regolith::integration::ShapeFunctions;
use regolith::material::MaterialSpec;
use regolith::registry::Item;
use regolith::resources::{Dilatation, StressUpdate};
use regolith::schedule::{StepOptions, build_schedule};
use regolith::shape_functions::{CpdiFixed, Linear, QuadraticBspline};
use regolith::step::StepSet;
use regolith::step::spacing::{DeltaCorrection, Spacing};

const TABLE_SOURCE: &str = include_str!("../../src/schedule.rs");
const ARCHITECTURE: &str = include_str!("../../ARCHITECTURE.md");

/// A field a scene could list, as a plugin's would be: its system writes field columns, as
/// the fluidity's does, so the two must be declared free of each other's order.
#[derive(Clone, Debug, serde::Deserialize)]
struct Dye;

impl Item for Dye {
    const NAME: &'static str = "Dye";
    const UNIT: bool = true;
}

fn spread_dye(_: Query<&mut FieldColumns>) {}

impl Field for Dye {
    fn columns(&self) -> &'static [&'static str] {
        &["dye"]
    }
    fn attach(&self, _: &mut EntityWorldMut) {}
    fn system(&self) -> ScheduleConfigs<ScheduleSystem> {
        spread_dye.into_configs()
    }
}

/// One entry of the table: a system and the conditions under which the step has it.
struct Entry {
    set: String,
    system: String,
    when: Vec<String>,
}

/// The table's rows, in order.
fn table() -> Vec<Entry> {
    let doc: Vec<&str> = TABLE_SOURCE
        .lines()
        .take_while(|l| l.starts_with("//!"))
        .map(|l| l.trim_start_matches("//!"))
        .map(|l| l.strip_prefix(' ').unwrap_or(l))
        .collect();
    let start = doc
        .iter()
        .position(|l| *l == "```text")
        .expect("a text block")
        + 2;
    let end = start
        + doc[start..]
            .iter()
            .position(|l| *l == "```")
            .expect("its end");
    let mut set = String::new();
    let mut entries = Vec::new();
    for line in &doc[start..end] {
        let mut words = line.split_whitespace();
        if !line.starts_with(' ') {
            set = words.next().expect("a set").to_string();
        }
        for word in words {
            let (system, when) = match word.split_once('{') {
                Some((s, w)) => (
                    s,
                    w.trim_end_matches('}')
                        .split(',')
                        .map(String::from)
                        .collect(),
                ),
                None => (word, Vec::new()),
            };
            entries.push(Entry {
                set: set.clone(),
                system: system.to_string(),
                when,
            });
        }
    }
    entries
}

/// `regolith::step::locate::locate_points<regolith::shape_functions::CpdiFixed>` as the
/// table writes it, with the scheme and material named: `locate_points<CpdiFixed>`.
fn short(name: &str) -> String {
    let mut out = String::new();
    let mut word = String::new();
    for c in name.chars() {
        if c.is_alphanumeric() || c == '_' {
            word.push(c);
        } else if c == ':' {
            word.clear();
        } else {
            out.push_str(&word);
            word.clear();
            out.push(c);
        }
    }
    out + &word
}

struct Case<'a> {
    options: StepOptions<'a>,
    /// The conditions that hold, as the table writes them.
    holds: Vec<String>,
    scheme: &'static str,
    /// The systems of the fields the scene lists (`<F>`).
    listed: Vec<String>,
}

/// The systems each set runs, in order (the timing laps separate the sets).
fn executed(options: &StepOptions) -> Vec<Vec<String>> {
    let mut schedule = build_schedule(options);
    let mut world = World::new();
    schedule.initialize(&mut world).expect("the step builds");
    let mut sets = vec![Vec::new()];
    for (_, system) in schedule.systems().expect("initialised") {
        let name = system.name().to_string();
        if name.contains("{{closure}}") {
            sets.push(Vec::new());
        } else if !name.starts_with("bevy_ecs") {
            sets.last_mut().unwrap().push(short(&name));
        }
    }
    sets.pop();
    sets
}

/// What the table says the step of `case` runs, set by set.
fn expected(table: &[Entry], case: &Case, materials: &[&str]) -> Vec<Vec<String>> {
    StepSet::ALL
        .iter()
        .map(|set| {
            let label = format!("{set:?}");
            let mut systems = Vec::new();
            for entry in table.iter().filter(|e| e.set == label) {
                if !entry.when.iter().all(|w| case.holds.contains(w)) {
                    continue;
                }
                if entry.system == "<F>" {
                    systems.extend(case.listed.iter().cloned());
                } else if entry.system.ends_with("<M>") {
                    let base = entry.system.trim_end_matches("<M>");
                    systems.extend(materials.iter().map(|m| format!("{base}<{m}>")));
                } else {
                    systems.push(entry.system.replace("<S>", &format!("<{}>", case.scheme)));
                }
            }
            systems
        })
        .collect()
}

/// Material updates, and fields, run in no fixed order among themselves: their sets are
/// compared sorted.
fn sort_unordered(sets: &mut [Vec<String>]) {
    for set in [StepSet::Fields, StepSet::ConstitutiveUpdate] {
        sets[set as usize].sort();
    }
}

#[test]
fn the_step_runs_the_table_for_every_combination_of_options() {
    let table = table();
    assert!(
        table.len() > 20,
        "the table was read: {} entries",
        table.len()
    );
    let registries = regolith::Regolith::default().registries();
    let material = |text: &str| -> Box<dyn MaterialSpec> {
        let scene = format!(
            "Scene(name: \"m\", domain: (size: (0.1, 0.1), cells: (10, 10)), \
             time: (end: 0.1, step: Cfl(0.5), output_every: 0.1), \
             walls: (left: Slip, right: Slip, bottom: NoSlip, top: Free), \
             bodies: [(name: \"b\", shape: Rectangle(min: (0.0, 0.0), max: (0.1, 0.05)), \
             material: {text})])"
        );
        let scene = regolith::Scene::parse(&scene, "<m>", &registries).unwrap();
        scene.bodies.into_iter().next().unwrap().material.0
    };
    let mui = material(
        "MuI(youngs_modulus: 2.0e7, poisson_ratio: 0.45, grain_density: 1280.0, \
         packing_fraction: 0.79, grain_diameter: 5.0e-3, mu_s: 0.320, mu_2: 0.598, i_0: 0.278)",
    );
    let nonlocal = material(
        "Nonlocal(youngs_modulus: 2.0e7, poisson_ratio: 0.45, grain_density: 1280.0, \
         packing_fraction: 0.79, grain_diameter: 5.0e-3, mu_s: 0.320, mu_2: 0.598, i_0: 0.278)",
    );
    let elastic =
        material("LinearElastic(density: 7800.0, youngs_modulus: 2.0e11, poisson_ratio: 0.3)");
    let frictional = Frictional {
        friction: 0.1,
        normal: Default::default(),
    };
    let schemes: [(&dyn ShapeFunctions, &str); 3] = [
        (&Linear, "Linear"),
        (&CpdiFixed, "CpdiFixed"),
        (&QuadraticBspline, "QuadraticBspline"),
    ];
    let contacts: [(Option<&dyn Contact>, &str); 3] = [
        (None, "one body"),
        (Some(&NoSlip), "NoSlip"),
        (Some(&frictional), "Frictional"),
    ];
    let material_sets: [Vec<(&dyn MaterialSpec, &str)>; 4] = [
        vec![(&*mui, "MuI")],
        vec![(&*nonlocal, "Nonlocal")],
        vec![(&*elastic, "LinearElastic"), (&*mui, "MuI")],
        vec![(&*elastic, "LinearElastic"), (&*nonlocal, "Nonlocal")],
    ];
    // With and without a field the scene lists.
    let listed_sets: [Vec<Box<dyn Field>>; 2] = [Vec::new(), vec![Box::new(Dye)]];
    let mut cases = 0;
    for (integration, scheme) in schemes {
        for update in [StressUpdate::Usl, StressUpdate::Musl] {
            for dilatation in [Dilatation::PerPoint, Dilatation::CellAveraged] {
                for affine in [false, true] {
                    for spacing in [
                        Spacing::Off,
                        Spacing::DeltaCorrection(DeltaCorrection::default()),
                    ] {
                        for (contact, contact_name) in contacts {
                            for (materials, listed) in material_sets
                                .iter()
                                .flat_map(|m| listed_sets.iter().map(move |l| (m, l)))
                            {
                                let mut holds = vec![
                                    format!("{update:?}"),
                                    format!("{dilatation:?}"),
                                    if affine { "affine" } else { "!affine" }.to_string(),
                                    contact_name.to_string(),
                                ];
                                if let Spacing::DeltaCorrection(_) = spacing {
                                    holds.push("DeltaCorrection".into());
                                }
                                holds.extend(materials.iter().map(|(_, n)| n.to_string()));
                                let materials_of: Vec<&dyn MaterialSpec> =
                                    materials.iter().map(|(m, _)| *m).collect();
                                let fields: Vec<Box<dyn Field>> = materials_of
                                    .iter()
                                    .flat_map(|m| m.fields())
                                    .chain(listed.iter().cloned())
                                    .collect();
                                if !fields.is_empty() {
                                    holds.push("Fields".into());
                                }
                                let case = Case {
                                    options: StepOptions {
                                        integration,
                                        update,
                                        dilatation,
                                        affine,
                                        spacing,
                                        contact,
                                        materials: materials_of,
                                        fields,
                                    },
                                    holds,
                                    scheme,
                                    listed: listed.iter().map(|_| "spread_dye".into()).collect(),
                                };
                                let names: Vec<&str> = materials.iter().map(|(_, n)| *n).collect();
                                let mut ran = executed(&case.options);
                                let mut want = expected(&table, &case, &names);
                                sort_unordered(&mut ran);
                                sort_unordered(&mut want);
                                assert_eq!(ran, want, "options {:?}", case.holds);
                                cases += 1;
                            }
                        }
                    }
                }
            }
        }
    }
    assert_eq!(cases, 3 * 2 * 2 * 2 * 2 * 3 * 4 * 2);
}

#[test]
fn the_table_names_every_set_in_order() {
    let table = table();
    let mut sets: Vec<String> = table.iter().map(|e| e.set.clone()).collect();
    sets.dedup();
    let all: Vec<String> = StepSet::ALL.iter().map(|s| format!("{s:?}")).collect();
    assert_eq!(sets, all);
}

/// ARCHITECTURE.md's "One step" lists the sets on one line, as the code runs them.
#[test]
fn the_architecture_names_the_same_sets() {
    let all: Vec<String> = StepSet::ALL.iter().map(|s| format!("{s:?}")).collect();
    let line = ARCHITECTURE
        .lines()
        .find(|l| l.starts_with("Prepare "))
        .expect("ARCHITECTURE.md has a line of the step's sets, starting with Prepare");
    let listed: Vec<String> = line.split_whitespace().map(String::from).collect();
    assert_eq!(listed, all, "ARCHITECTURE.md's sets against StepSet::ALL");
}
