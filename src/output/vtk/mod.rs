//! `Vtk(every: 0.01)`: the run as VTK XML files for ParaView (or any VTK reader).
//!
//! Each frame writes one `.vtu` per body (its points as vertex cells with the chosen
//! `fields`) into `<out>/vtk/`, and, with `grid: true`, one `.vti` per body with its nodal
//! field. `vtk/points.pvd` (and `vtk/grid.pvd`) list the frames with their simulated times,
//! so ParaView's time slider steps through the run; they are rewritten (atomically) after
//! every frame, so a run that fails or is interrupted leaves a collection of the frames it
//! wrote. Checkpoints carry the frame count and the collections' entries, so a resumed run
//! lists every frame, the earlier ones included.

mod xml;

use bevy_ecs::prelude::*;
use serde::Deserialize;

use super::{Output, OutputFaults, RunDir, Timing, write_or_fault};
use crate::body::{Body, PointStates, Points};
use crate::carry::{Carried, carried, restored};
use crate::grid::{GridField, GridGeometry};
use crate::grid_field::FieldColumns;
use crate::plugin::Install;
use crate::registry::Item;
use crate::resources::Clock;
use crate::step::StepSet;
pub use xml::{Entry, read_collection};

/// A per-point quantity a `.vtu` can carry (the position always).
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
pub enum VtkField {
    /// (vx, vy, 0), m/s.
    Velocity,
    /// -trace/3 of the 3D stress, Pa (positive in compression).
    Pressure,
    /// Equivalent shear stress, Pa.
    ShearStress,
    /// The full Cauchy stress as a 3 x 3 tensor (plane strain: xz = yz = 0), Pa, tension
    /// positive.
    Stress,
    /// Equivalent plastic shear strain rate of the last step, 1/s.
    PlasticStrainRate,
    /// Accumulated equivalent plastic shear strain.
    PlasticStrain,
    /// 0 solid, 1 flowing, 2 disconnected.
    Phase,
    /// kg per metre of depth.
    Mass,
    /// m^2 per metre of depth.
    Volume,
    /// The body's position in the scene's list (to colour bodies apart in one view).
    Body,
}

impl VtkField {
    const ALL: [VtkField; 10] = [
        VtkField::Velocity,
        VtkField::Pressure,
        VtkField::ShearStress,
        VtkField::Stress,
        VtkField::PlasticStrainRate,
        VtkField::PlasticStrain,
        VtkField::Phase,
        VtkField::Mass,
        VtkField::Volume,
        VtkField::Body,
    ];

    /// The array's name in the files.
    fn name(self) -> &'static str {
        match self {
            VtkField::Velocity => "velocity",
            VtkField::Pressure => "pressure",
            VtkField::ShearStress => "shear_stress",
            VtkField::Stress => "stress",
            VtkField::PlasticStrainRate => "plastic_strain_rate",
            VtkField::PlasticStrain => "plastic_strain",
            VtkField::Phase => "phase",
            VtkField::Mass => "mass",
            VtkField::Volume => "volume",
            VtkField::Body => "body",
        }
    }

    /// This field of every point of one body.
    fn array(self, body: &Body, p: &Points, st: &PointStates) -> xml::Array {
        let name = self.name();
        let scalar = |v: &[f64]| xml::Array::f64(name, 1, v.iter().copied());
        match self {
            VtkField::Velocity => xml::Array::vectors(name, &p.velocity),
            VtkField::Pressure => xml::Array::f64(name, 1, p.stress.iter().map(|s| s.pressure())),
            VtkField::ShearStress => {
                xml::Array::f64(name, 1, p.stress.iter().map(|s| s.equivalent_shear()))
            }
            VtkField::Stress => xml::Array::f64(
                name,
                9,
                p.stress
                    .iter()
                    .flat_map(|s| [s.xx, s.xy, 0.0, s.xy, s.yy, 0.0, 0.0, 0.0, s.zz]),
            ),
            VtkField::PlasticStrainRate => scalar(&st.plastic_strain_rate),
            VtkField::PlasticStrain => scalar(&st.plastic_strain),
            VtkField::Phase => xml::Array::u8(name, st.phase.iter().map(|f| f.code())),
            VtkField::Mass => scalar(&p.mass),
            VtkField::Volume => scalar(&p.volume),
            VtkField::Body => {
                xml::Array::i32(name, std::iter::repeat_n(body.index as i32, p.len()))
            }
        }
    }
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Vtk {
    /// Interval between frames (s).
    #[serde(default)]
    pub every: Option<f64>,
    /// Or the times to write them at (s), increasing.
    #[serde(default)]
    pub at: Option<Vec<f64>>,
    /// The point fields to write (default: all of them). The columns of the body's fields
    /// (module `field`: `fluidity`, a plugin's `tracer`) are written after them, always.
    #[serde(default)]
    pub fields: Option<Vec<VtkField>>,
    /// Also write each body's nodal field (`.vti`).
    #[serde(default)]
    pub grid: bool,
}

/// The folder under the run directory, and the collections in it.
pub const FOLDER: &str = "vtk";
pub const POINTS_COLLECTION: &str = "points.pvd";
pub const GRID_COLLECTION: &str = "grid.pvd";

#[derive(Resource, Debug)]
struct VtkState {
    when: Timing,
    fields: Vec<VtkField>,
    grid: bool,
    frame: usize,
    points: Vec<Entry>,
    nodes: Vec<Entry>,
}

impl Item for Vtk {
    const NAME: &'static str = "Vtk";
    fn validate(&self) -> Result<(), String> {
        Timing::check(self.every, self.at.as_deref())?;
        if let Some(fields) = &self.fields
            && let Some(twice) = fields
                .iter()
                .enumerate()
                .find(|(k, f)| fields[..*k].contains(f))
        {
            return Err(format!("fields lists {:?} twice", twice.1));
        }
        Ok(())
    }
}

impl Output for Vtk {
    fn install(&self, sim: &mut Install) {
        sim.insert_resource(VtkState {
            when: Timing::new(self.every, self.at.as_deref()),
            fields: self.fields.clone().unwrap_or(VtkField::ALL.to_vec()),
            grid: self.grid,
            frame: 0,
            points: Vec::new(),
            nodes: Vec::new(),
        });
        sim.add_systems(StepSet::Output, write_frame);
    }

    /// The schedule, the next frame's number and the collections' entries so far.
    fn save(&self, world: &World) -> Carried {
        let v = world.resource::<VtkState>();
        carried(&(&v.when, v.frame, &v.points, &v.nodes))
    }

    fn restore(&self, world: &mut World, state: &[u8]) -> Result<(), String> {
        let mut v = world.resource_mut::<VtkState>();
        (v.when, v.frame, v.points, v.nodes) = restored(state)?;
        Ok(())
    }
}

/// File stems for the bodies: their names with anything but letters, digits, `-` and `_`
/// replaced, and the body's index added where two names would meet.
fn stems(names: &[&str]) -> Vec<String> {
    let clean: Vec<String> = names
        .iter()
        .map(|n| {
            n.chars()
                .map(|c| {
                    if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                        c
                    } else {
                        '_'
                    }
                })
                .collect()
        })
        .collect();
    clean
        .iter()
        .enumerate()
        .map(|(k, s)| {
            if clean.iter().filter(|t| *t == s).count() > 1 {
                format!("{s}_{k}")
            } else {
                s.clone()
            }
        })
        .collect()
}

fn write_frame(
    clock: Res<Clock>,
    dir: Res<RunDir>,
    geometry: Res<GridGeometry>,
    mut state: ResMut<VtkState>,
    faults: Res<OutputFaults>,
    bodies: Query<(
        &Body,
        &Points,
        &PointStates,
        &GridField,
        Option<&FieldColumns>,
    )>,
) {
    if !state.when.due(&clock) {
        return;
    }
    let Some(dir) = &dir.0 else { return };
    let folder = dir.join(FOLDER);
    if let Err(e) = std::fs::create_dir_all(&folder) {
        faults.report(&clock, format!("cannot create {}: {e}", folder.display()));
        return;
    }
    let mut sorted: Vec<_> = bodies.iter().collect();
    sorted.sort_by_key(|(b, ..)| b.index);
    let names: Vec<&str> = sorted.iter().map(|(b, ..)| b.name.as_str()).collect();
    let stems = stems(&names);
    let frame = state.frame;
    state.frame += 1;
    let lattice = xml::Lattice {
        origin: geometry.origin.to_array(),
        spacing: geometry.cell_size,
        nodes: [geometry.nodes_along(0), geometry.nodes_along(1)],
    };
    for ((body, p, st, field, columns), stem) in sorted.into_iter().zip(&stems) {
        let mut arrays: Vec<_> = state.fields.iter().map(|f| f.array(body, p, st)).collect();
        let columns = columns.map_or(&[][..], |c| c.columns());
        arrays.extend(
            columns
                .iter()
                .map(|c| xml::Array::f64(&c.name, 1, c.values.iter().copied())),
        );
        let file = format!("{stem}_{frame:05}.vtu");
        let bytes = xml::unstructured_points(clock.time, &p.position, &arrays);
        write_or_fault(&folder.join(&file), &bytes, &clock, &faults);
        state.points.push(Entry {
            time: clock.time,
            part: body.index,
            file,
        });
        if state.grid {
            let file = format!("{stem}_grid_{frame:05}.vti");
            let bytes = grid_file(clock.time, &lattice, field);
            write_or_fault(&folder.join(&file), &bytes, &clock, &faults);
            state.nodes.push(Entry {
                time: clock.time,
                part: body.index,
                file,
            });
        }
    }
    let collections = [
        (POINTS_COLLECTION, &state.points, true),
        (GRID_COLLECTION, &state.nodes, state.grid),
    ];
    for (name, entries, written) in collections {
        if written {
            let text = xml::collection(entries);
            write_or_fault(&folder.join(name), text.as_bytes(), &clock, &faults);
        }
    }
}

/// One body's nodal field: mass, velocity, momentum and the nodal force of the step, and
/// the total contact force on the body as field data.
fn grid_file(time: f64, lattice: &xml::Lattice, field: &GridField) -> Vec<u8> {
    let arrays = [
        xml::Array::f64("mass", 1, field.mass.iter().copied()),
        xml::Array::vectors("velocity", &field.velocity),
        xml::Array::vectors("momentum", &field.momentum),
        xml::Array::vectors("force", &field.force),
    ];
    let contact = [field.contact_force.x, field.contact_force.y, 0.0];
    xml::image_data(time, lattice, &arrays, &[("contact_force", &contact)])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stems_are_file_safe_and_distinct() {
        assert_eq!(
            stems(&["bed", "disc 1", "disc/1", "intruder"]),
            ["bed", "disc_1_1", "disc_1_2", "intruder"]
        );
    }
}
