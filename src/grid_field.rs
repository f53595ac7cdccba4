//! Grid fields: scalar fields that live on a body's nodes for part of a step, for materials
//! and plugins whose law needs a spatial operator (a diffusion, a gradient) of a quantity the
//! points carry. The nonlocal granular fluidity (`material::nonlocal`) is built on it; a
//! temperature, a pore pressure or a damage field would be built the same way.
//!
//! The points carry the field's state (in named columns, [`FieldColumns`], which the
//! checkpoint saves); the grid only holds it long enough to apply an operator. A step of a
//! grid field is:
//!
//! 1. [`scatter`]: each point hands the nodes of its footprint a weight and a value; a node's
//!    value is the weighted mean `sum S w_p v_p / sum S w_p`. A node no point reaches (zero
//!    weight) is *inactive*: it is outside the material. Weighting by volume makes the nodal
//!    value a mean over the material, which does not fall off at a free surface or depend on
//!    the number of points per cell (an unnormalised sum would do both).
//! 2. An operator on the nodes: [`laplacian`] (5 points, second order), with a condition per
//!    wall ([`NodeCondition`]): a fixed value on the wall's nodes, or zero flux. Next to an
//!    inactive node, the operator reflects the field through the node (`v_{i+1} = v_{i-1}`):
//!    zero flux across the material's edge, placed at its last active node.
//! 3. [`gather_active`]: the result interpolated back to each point with its footprint (over
//!    the active nodes, renormalised), into the field's columns of the body's
//!    [`FieldColumns`], which the constitutive update hands to `Material::update` (module
//!    `material`) by name as `PointStep::fields`.
//!
//! A field (`crate::field`: the nonlocal fluidity, a plugin's tracer) runs in its own set,
//! `Fields`, after the move and before the constitutive update (the step's table,
//! `schedule.rs`): so its law may read this step's velocity gradient and density (the
//! fluidity's needs the elastic trial stress), and the material update reads its result. The
//! footprints are then still the start of the step's (the velocity gradient was gathered
//! with them), but the bands have been rebuilt for the moved points, so a field scatters
//! with the bands kept from the start of the step ([`StartBands`], copied in
//! `ParticleToGrid` by `keep_start_bands` whenever a body carries a field).

use bevy_ecs::prelude::*;
use rayon::prelude::*;

use crate::grid::GridGeometry;
use crate::obstacle::HeldNode;
use crate::resources::{Segment, Side, Wall};
use crate::step::bands::Shared;
use crate::step::{Bands, Location};

/// One scalar on every node of a body's grid: the scatter's weights and the weighted means.
#[derive(Clone, Debug, Default)]
pub struct NodalScalar {
    /// `sum S w_p`: zero at inactive nodes.
    pub weight: Vec<f64>,
    /// The weighted mean of the points' values (zero at inactive nodes).
    pub value: Vec<f64>,
}

impl NodalScalar {
    /// Whether node `n` received any weight.
    #[inline]
    pub fn active(&self, n: usize) -> bool {
        self.weight[n] > 0.0
    }

    fn reset(&mut self, nodes: usize) {
        for v in [&mut self.weight, &mut self.value] {
            v.clear();
            v.resize(nodes, 0.0);
        }
    }
}

/// A body's named nodal scalars (component), kept between steps only to reuse their storage.
#[derive(Component, Clone, Debug, Default)]
pub struct GridFields {
    fields: Vec<(&'static str, NodalScalar)>,
}

impl GridFields {
    /// Bytes of the nodal scalars held now (none before the first step).
    pub fn bytes(&self) -> usize {
        let scalar = |s: &NodalScalar| (s.weight.capacity() + s.value.capacity()) * 8;
        self.fields.iter().map(|(_, s)| scalar(s)).sum()
    }

    /// The field called `name`, created empty the first time.
    pub fn field_mut(&mut self, name: &'static str) -> &mut NodalScalar {
        let k = match self.fields.iter().position(|(n, _)| *n == name) {
            Some(k) => k,
            None => {
                self.fields.push((name, NodalScalar::default()));
                self.fields.len() - 1
            }
        };
        &mut self.fields[k].1
    }
}

/// One named per-point column of a body's fields (`FieldColumns`).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Column {
    pub name: String,
    /// One value per point, in the body's point order.
    pub values: Vec<f64>,
}

/// The per-point values a body's fields carry (component): one named column each, added by
/// the fields when the body is built (`crate::field::Field::attach`), carried from step to
/// step, saved and restored by checkpoints by name, and read by the body's material by name
/// ([`FieldValues`]). A field writes only its own columns.
#[derive(Component, Clone, Debug, Default)]
pub struct FieldColumns {
    columns: Vec<Column>,
}

impl FieldColumns {
    /// Adds column `name` with `values`; an error if the body has it already (two fields
    /// claiming one name).
    pub fn add(&mut self, name: &str, values: Vec<f64>) -> Result<(), String> {
        if self.get(name).is_some() {
            return Err(format!(
                "two fields of one body both carry a column \"{name}\""
            ));
        }
        self.columns.push(Column {
            name: name.to_string(),
            values,
        });
        Ok(())
    }

    /// Column `name`, if the body has it.
    pub fn get(&self, name: &str) -> Option<&[f64]> {
        self.columns
            .iter()
            .find(|c| c.name == name)
            .map(|c| c.values.as_slice())
    }

    /// Column `name`, mutable, if the body has it.
    pub fn get_mut(&mut self, name: &str) -> Option<&mut [f64]> {
        self.columns
            .iter_mut()
            .find(|c| c.name == name)
            .map(|c| c.values.as_mut_slice())
    }

    /// Several distinct columns at once, mutable (a field advancing its state); an error
    /// names a column the body lacks or one asked for twice.
    pub fn many_mut<const N: usize>(
        &mut self,
        names: [&str; N],
    ) -> Result<[&mut [f64]; N], String> {
        let mut at = [0; N];
        for (k, name) in names.iter().enumerate() {
            at[k] = self
                .columns
                .iter()
                .position(|c| c.name == *name)
                .ok_or_else(|| format!("the body has no field column \"{name}\""))?;
        }
        let columns = self
            .columns
            .get_disjoint_mut(at)
            .map_err(|_| format!("a column is asked for twice among {names:?}"))?;
        Ok(columns.map(|c| c.values.as_mut_slice()))
    }

    /// Bytes of the columns' values (for memory estimates).
    pub fn bytes(&self) -> usize {
        self.columns
            .iter()
            .map(|c| c.values.len() * std::mem::size_of::<f64>())
            .sum()
    }

    /// Every column, in the order the fields added them.
    pub fn columns(&self) -> &[Column] {
        &self.columns
    }

    /// Puts back the columns a checkpoint saved: the same names, each as long as now, in
    /// any order; an error names a column missing on either side.
    pub fn restore(&mut self, saved: Vec<Column>) -> Result<(), String> {
        if let Some(extra) = saved.iter().find(|s| self.get(&s.name).is_none()) {
            return Err(format!(
                "the checkpoint carries a field column \"{}\" that the scene's fields do not",
                extra.name
            ));
        }
        for column in &mut self.columns {
            let Some(s) = saved.iter().find(|s| s.name == column.name) else {
                return Err(format!(
                    "the checkpoint has no field column \"{}\" (a field added since it was written)",
                    column.name
                ));
            };
            if s.values.len() != column.values.len() {
                return Err(format!(
                    "the checkpoint's field column \"{}\" has {} values for {} points",
                    column.name,
                    s.values.len(),
                    column.values.len()
                ));
            }
            column.values.clone_from(&s.values);
        }
        Ok(())
    }
}

/// The field values one point's material update reads (`material::PointStep::fields`): the
/// columns its material declares (`Material::point_fields`), found by name.
#[derive(Clone, Copy, Debug)]
pub struct FieldValues<'a> {
    columns: &'a [(&'a str, &'a [f64])],
    point: usize,
}

impl<'a> FieldValues<'a> {
    /// No field at all (a material that reads none, or a test of one point).
    pub const NONE: FieldValues<'static> = FieldValues {
        columns: &[],
        point: 0,
    };

    /// Point `point`'s values of `columns` (name and column).
    pub fn new(columns: &'a [(&'a str, &'a [f64])], point: usize) -> Self {
        FieldValues { columns, point }
    }

    /// The value of column `name` at the point; `None` if it is not among the columns.
    #[inline]
    pub fn get(&self, name: &str) -> Option<f64> {
        self.columns
            .iter()
            .find(|(n, _)| *n == name)
            .map(|(_, c)| c[self.point])
    }
}

/// A body's bands as they were when its footprints were found (component): the scatter of a
/// field, which runs after the move, when [`Bands`] already describes the moved points.
#[derive(Component, Clone, Debug, Default)]
pub struct StartBands(pub Bands);

/// Keeps the bands of every body carrying a field as they are when its footprints are found
/// ([`StartBands`]; in `ParticleToGrid`, after the scatter).
pub fn keep_start_bands(mut bodies: Query<(&Bands, &mut StartBands)>) {
    for (bands, mut kept) in &mut bodies {
        kept.0.clone_from(bands);
    }
}

/// What a wall imposes on a grid field at its nodes.
#[derive(Clone, Copy, Debug, PartialEq, serde::Deserialize, serde::Serialize)]
pub enum NodeCondition {
    /// No flux across the wall (the default at free surfaces).
    ZeroFlux,
    /// The field takes this value on the wall's active nodes.
    Fixed(f64),
}

impl NodeCondition {
    /// What a wall imposes unless the material chooses otherwise: a `NoSlip` wall fixes the
    /// field at zero (no flow, hence no fluidity, at a wall that holds the material), any
    /// other lets it through (zero flux).
    pub fn default_for(wall: Wall) -> NodeCondition {
        if wall == Wall::NoSlip {
            NodeCondition::Fixed(0.0)
        } else {
            NodeCondition::ZeroFlux
        }
    }
}

/// A condition per side of the domain; periodic sides wrap whatever is set here. The nodes
/// a wall segment covers (`Walls::at`) take the segment's wall's default condition instead
/// ([`NodeCondition::default_for`]): an `Open` orifice in a `NoSlip` floor lets the field
/// through. The nodes an obstacle holds (`crate::obstacle`) take their obstacle's wall's
/// default too: a `NoSlip` obstacle fixes the field at zero on those of its nodes the
/// material reaches (the first row inside its surface, so the condition sits less than a
/// cell inside the surface), any other leaves them free, the nodes deeper inside being
/// inactive, which makes the surface zero flux.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FieldWalls<'a> {
    pub left: NodeCondition,
    pub right: NodeCondition,
    pub bottom: NodeCondition,
    pub top: NodeCondition,
    pub segments: &'a [Segment],
    /// The scene's obstacles' nodes (`Obstacles::held_nodes`; empty without obstacles).
    pub obstacles: &'a [HeldNode],
}

impl FieldWalls<'_> {
    /// The condition of a whole side (its segments aside).
    pub fn side(&self, side: Side) -> NodeCondition {
        match side {
            Side::Left => self.left,
            Side::Right => self.right,
            Side::Bottom => self.bottom,
            Side::Top => self.top,
        }
    }
}

/// The least weight of an active node, in units of a full node's (`h^2`, the weight of a node
/// whose whole support is material): an eighth is the weight of a node a flat free surface
/// lies halfway to (`f^2/2` for a surface a fraction `f` of a cell past the last full node).
/// So the node nearest the surface is the field's last, and its zero-flux edge lies within
/// half a cell of the surface. A node that only a sliver of material reaches (an elastic
/// displacement of `1e-12 h` past a cell boundary) would otherwise move that edge a whole
/// cell out: a layer 0.9 times its stopping height decayed five times too slowly
/// (docs/VALIDATION.md, "Nonlocal granular fluidity").
pub const FILLED: f64 = 0.125;

/// Scatters a scalar from the points to the nodes: `point(p)` is the weight and value point
/// `p` hands its footprint, or `None` for a point left out (it then makes no node active).
/// A node whose weight stays below [`FILLED`] times `h^2` is left inactive (weight and value
/// zero): it lies outside the material.
/// The bands must be those the footprints were found with (`ParticleToGrid`, after
/// `locate_points`); the scatter is parallel over bands without locks, and each node receives
/// its contributions in the same order whatever the number of threads.
pub fn scatter(
    grid: &GridGeometry,
    location: &Location,
    bands: &Bands,
    field: &mut NodalScalar,
    point: impl Fn(usize) -> Option<(f64, f64)> + Sync,
) {
    scatter_many(grid, location, bands, [field], |k| {
        point(k).map(|(w, v)| (w, [v]))
    });
}

/// [`scatter`] of `N` scalars that share their points' weights, in one pass over the
/// footprints: `point(p)` gives the weight and the `N` values. Each field gets the weights
/// and the weighted means it would get from a [`scatter`] of its own, bit for bit (the sums
/// are formed the same way, in the same order), at the cost of one.
pub fn scatter_many<const N: usize>(
    grid: &GridGeometry,
    location: &Location,
    bands: &Bands,
    mut fields: [&mut NodalScalar; N],
    point: impl Fn(usize) -> Option<(f64, [f64; N])> + Sync,
) {
    let nodes = grid.node_count();
    for field in fields.iter_mut() {
        field.reset(nodes);
    }
    let footprints = location.footprints();
    if N == 0 {
        return;
    }
    {
        // Each field's weights and sums; the weights are summed on the first field's only.
        let shared = fields.each_mut().map(|f| {
            let f = &mut **f;
            (Shared::new(&mut f.weight), Shared::new(&mut f.value))
        });
        let shared = &shared;
        bands.for_each_phase(|b| {
            let weight = shared[0].0;
            let window = bands.node_window(grid, b);
            for &p in bands.points(b) {
                let p = p as usize;
                let Some((w, v)) = point(p) else { continue };
                let f = &footprints[p];
                assert!(
                    window.holds(f),
                    "point {p} reaches outside the nodes of its band {b}: a grid field \
                     scattered with bands that do not match the footprints"
                );
                f.for_each_entry(|n, s, _| {
                    let sw = s * w;
                    // SAFETY: the footprint lies in the band's window (checked above), inside
                    // the slices of `nodes` entries (reset above), and bands of one phase
                    // have disjoint windows (`BandLayout::check`).
                    unsafe {
                        weight.add_at(n, sw);
                        for ((_, sum), v) in shared.iter().zip(v) {
                            sum.add_at(n, sw * v);
                        }
                    }
                });
            }
        });
    }
    let filled = FILLED * grid.cell_size * grid.cell_size;
    let [first, rest @ ..] = &mut fields[..] else {
        unreachable!("N > 0")
    };
    first
        .value
        .par_iter_mut()
        .zip(first.weight.par_iter_mut())
        .for_each(|(v, w)| {
            if *w >= filled {
                *v /= *w;
            } else {
                (*v, *w) = (0.0, 0.0);
            }
        });
    // The other fields take the first's weights, zero where it found a node inactive.
    for field in rest {
        field.weight.copy_from_slice(&first.weight);
        field
            .value
            .par_iter_mut()
            .zip(field.weight.par_iter())
            .for_each(|(v, &w)| *v = if w > 0.0 { *v / w } else { 0.0 });
    }
}

/// A node a wall fixes, and the next two nodes inward along the wall's normal (if the grid
/// has them).
struct FixedNode {
    node: usize,
    inward: [Option<usize>; 2],
}

/// Applies the walls' fixed values to the active nodes on them (periodic sides excepted; a
/// corner belongs to the first of left, right, bottom, top that fixes it); returns for each
/// node whether it is fixed, and the fixed nodes.
fn fix_walls(
    grid: &GridGeometry,
    field: &mut NodalScalar,
    walls: &FieldWalls,
) -> (Vec<bool>, Vec<FixedNode>) {
    let mut is_fixed = vec![false; grid.node_count()];
    let mut fixed = Vec::new();
    let nx = grid.nodes_along(0);
    for (side, axis, low) in Side::ALL {
        let condition = walls.side(side);
        let segmented = walls.segments.iter().any(|s| s.side == side);
        if grid.periodic[axis] || (!segmented && condition == NodeCondition::ZeroFlux) {
            continue;
        }
        let sign = if low { 1 } else { -1 };
        for n in grid.side_nodes(axis, low) {
            if !field.active(n) || is_fixed[n] {
                continue;
            }
            let here = grid.node_coordinate(n, 1 - axis);
            let covering = walls.segments.iter().find(|s| s.covers(side, here));
            let NodeCondition::Fixed(value) =
                covering.map_or(condition, |s| NodeCondition::default_for(s.wall))
            else {
                continue;
            };
            field.value[n] = value;
            is_fixed[n] = true;
            fixed.push(FixedNode {
                node: n,
                inward: [1, 2].map(|k| step_from(grid, axis, n % nx, n / nx, sign * k)),
            });
        }
    }
    // The obstacles' nodes the material reaches; inward is out of the obstacle, along the
    // larger component of its outward normal.
    for held in walls.obstacles {
        let n = held.node;
        if !field.active(n) || is_fixed[n] {
            continue;
        }
        let NodeCondition::Fixed(value) = NodeCondition::default_for(held.wall) else {
            continue;
        };
        field.value[n] = value;
        is_fixed[n] = true;
        let axis = usize::from(held.normal.y.abs() > held.normal.x.abs());
        let sign = if held.normal[axis] > 0.0 { 1 } else { -1 };
        fixed.push(FixedNode {
            node: n,
            inward: [1, 2].map(|k| step_from(grid, axis, n % nx, n / nx, sign * k)),
        });
    }
    (is_fixed, fixed)
}

/// The node `k` nodes from `(i, j)` along `axis`, wrapping on a periodic axis; `None` past a
/// bounded edge.
fn step_from(grid: &GridGeometry, axis: usize, i: usize, j: usize, k: isize) -> Option<usize> {
    let count = grid.nodes_along(axis) as isize;
    let here = if axis == 0 { i } else { j } as isize + k;
    let there = if grid.periodic[axis] {
        here.rem_euclid(count)
    } else if (0..count).contains(&here) {
        here
    } else {
        return None;
    } as usize;
    Some(if axis == 0 {
        grid.index(there, j)
    } else {
        grid.index(i, there)
    })
}

/// The 5-point Laplacian of `field` on its active nodes (zero on inactive ones), into `out`,
/// after fixing the walls' values on `field` (which it changes); returns for each node
/// whether a wall fixes it.
///
/// Along each axis `(v_- - 2 v + v_+)/h^2`, where a neighbour that is inactive or past a
/// bounded edge takes the value of the opposite one (zero flux through the node; both
/// missing: no curvature along that axis). On a wall's fixed nodes the Laplacian is
/// extrapolated linearly from the next two nodes inward (`2 L_1 - L_2`, second order), so a
/// point between the wall and the first inner node sees the field's curvature there.
pub fn laplacian(
    grid: &GridGeometry,
    field: &mut NodalScalar,
    walls: &FieldWalls,
    out: &mut Vec<f64>,
) -> Vec<bool> {
    let (is_fixed, fixed) = fix_walls(grid, field, walls);
    let field = &*field;
    let nx = grid.nodes_along(0);
    let inv_h2 = 1.0 / (grid.cell_size * grid.cell_size);
    out.clear();
    out.resize(grid.node_count(), 0.0);
    out.par_chunks_mut(nx).enumerate().for_each(|(j, row)| {
        for (i, l) in row.iter_mut().enumerate() {
            let n = grid.index(i, j);
            if !field.active(n) || is_fixed[n] {
                continue;
            }
            let v = field.value[n];
            let mut sum = 0.0;
            for axis in 0..2 {
                let live = |m: Option<usize>| m.filter(|&m| field.active(m));
                let [a, b] = [-1, 1].map(|k| live(step_from(grid, axis, i, j, k)));
                let (va, vb) = match (a, b) {
                    (Some(a), Some(b)) => (field.value[a], field.value[b]),
                    (Some(a), None) => (field.value[a], field.value[a]),
                    (None, Some(b)) => (field.value[b], field.value[b]),
                    (None, None) => (v, v),
                };
                sum += va - 2.0 * v + vb;
            }
            *l = sum * inv_h2;
        }
    });
    // Fixed nodes: extrapolate from the two nodes inward, along the wall's normal.
    let inner = |m: Option<usize>| m.filter(|&m| field.active(m) && !is_fixed[m]);
    for f in fixed {
        out[f.node] = match f.inward.map(inner) {
            [Some(a), Some(b)] => 2.0 * out[a] - out[b],
            [Some(a), None] => out[a],
            _ => 0.0,
        };
    }
    is_fixed
}

/// Interpolates nodal values to point `k` over the active nodes of its footprint alone, the
/// weights renormalised, `sum_active S v / sum_active S`, for each array of `nodal`: a point
/// at the material's edge then sees the field extended at zero gradient past its last active
/// node, not pulled towards the zero an inactive node holds. `None` if no node of the
/// footprint is active.
pub fn gather_active<const N: usize>(
    location: &Location,
    field: &NodalScalar,
    nodal: [&[f64]; N],
    k: usize,
) -> Option<[f64; N]> {
    let mut sum = [0.0; N];
    let mut weight = 0.0;
    location.footprints()[k].for_each_entry(|n, s, _| {
        if field.active(n) {
            weight += s;
            for (sum, values) in sum.iter_mut().zip(&nodal) {
                *sum += s * values[n];
            }
        }
    });
    (weight > 0.0).then(|| sum.map(|s| s / weight))
}

/// The value at the centre of each cell, into `out` (indexed as `GridGeometry::cell_of`
/// numbers cells): the mean of `nodal` over the cell's active corner nodes (the interpolation
/// at the centre, with linear or CPDI shape functions, renormalised like [`gather_active`]);
/// `None` if none is active. A law that pairs the field with the velocity gradient reads it
/// here, at the cell of each point: the gradient is constant over a cell, so a value that
/// varies inside one would set points of one cell against each other. Computed once per
/// cell, a loop over many points then looks its cell up.
pub fn cell_centres(
    grid: &GridGeometry,
    field: &NodalScalar,
    nodal: &[f64],
    out: &mut Vec<Option<f64>>,
) {
    let columns = grid.cells[0];
    out.clear();
    out.resize(columns * grid.cells[1], None);
    out.par_chunks_mut(columns)
        .enumerate()
        .for_each(|(j, row)| {
            for (i, centre) in row.iter_mut().enumerate() {
                *centre = centre_of(grid, field, nodal, i, j);
            }
        });
}

/// The mean of `nodal` over the active corners of cell `(i, j)` (`None` if none is active).
#[inline]
fn centre_of(
    grid: &GridGeometry,
    field: &NodalScalar,
    nodal: &[f64],
    i: usize,
    j: usize,
) -> Option<f64> {
    let next = |axis: usize, k: usize| {
        if k + 1 == grid.nodes_along(axis) {
            0
        } else {
            k + 1
        }
    };
    let corners = [
        grid.index(i, j),
        grid.index(next(0, i), j),
        grid.index(i, next(1, j)),
        grid.index(next(0, i), next(1, j)),
    ];
    let (sum, count) = corners
        .iter()
        .filter(|&&n| field.active(n))
        .fold((0.0, 0), |(s, c), &n| (s + nodal[n], c + 1));
    (count > 0).then(|| sum / count as f64)
}

#[cfg(test)]
mod tests {
    use glam::DVec2;

    use super::*;

    fn line(cells: usize, h: f64, periodic_x: bool) -> GridGeometry {
        GridGeometry {
            origin: DVec2::ZERO,
            cell_size: h,
            cells: [cells, 1],
            periodic: [periodic_x, true],
        }
    }

    fn field_of(values: Vec<f64>) -> NodalScalar {
        NodalScalar {
            weight: vec![1.0; values.len()],
            value: values,
        }
    }

    const OPEN: FieldWalls = FieldWalls {
        left: NodeCondition::ZeroFlux,
        right: NodeCondition::ZeroFlux,
        bottom: NodeCondition::ZeroFlux,
        top: NodeCondition::ZeroFlux,
        segments: &[],
        obstacles: &[],
    };

    /// The centre of a cell reads the mean of its active corners, wrapping on a periodic
    /// axis: for a linear field, its value at the centre.
    #[test]
    fn a_cell_centre_reads_the_mean_of_its_active_corners() {
        let grid = GridGeometry {
            origin: DVec2::ZERO,
            cell_size: 1.0,
            cells: [4, 3],
            periodic: [true, false],
        };
        let (nx, ny) = (grid.nodes_along(0), grid.nodes_along(1));
        let values: Vec<f64> = (0..nx * ny)
            .map(|n| (n % nx) as f64 + 2.0 * (n / nx) as f64)
            .collect();
        let mut field = field_of(values.clone());
        let mut table = Vec::new();
        let mut at = |field: &NodalScalar, x: f64, y: f64| {
            cell_centres(&grid, field, &values, &mut table);
            assert_eq!(table.len(), 12);
            table[grid.cell_of(DVec2::new(x, y))]
        };
        // Every cell reads the linear field at its centre; the last column's cells close on
        // the first column's nodes: (3 + 0) / 2 along x.
        for j in 0..3 {
            for i in 0..4 {
                let along_x = if i == 3 { 1.5 } else { i as f64 + 0.5 };
                let expected = along_x + 2.0 * (j as f64 + 0.5);
                assert_eq!(at(&field, i as f64 + 0.3, j as f64 + 0.6), Some(expected));
            }
        }
        assert_eq!(at(&field, 1.2, 2.9), Some(1.5 + 2.0 * 2.5));
        assert_eq!(at(&field, 3.7, 0.1), Some(1.5 + 2.0 * 0.5));
        // An inactive corner is left out.
        field.weight[grid.index(2, 3)] = 0.0;
        assert_eq!(at(&field, 1.2, 2.9), Some((5.0 + 6.0 + 7.0) / 3.0));
        for n in [grid.index(1, 2), grid.index(2, 2), grid.index(1, 3)] {
            field.weight[n] = 0.0;
        }
        assert_eq!(at(&field, 1.2, 2.9), None);
    }

    /// Scattering two values together gives each the weights and means, bit for bit, of a
    /// scatter of its own, for points spread irregularly over a periodic grid (footprints
    /// wrapping) with some points left out.
    #[test]
    fn a_joint_scatter_equals_separate_ones() {
        use crate::shape_functions::CpdiFixed;
        use crate::step::locate_points;
        use bevy_ecs::system::RunSystemOnce;

        let grid = GridGeometry {
            origin: DVec2::ZERO,
            cell_size: 0.1,
            cells: [6, 9],
            periodic: [true, false],
        };
        let mut points = crate::body::Points::default();
        for k in 0..150 {
            let r = |m: u64| ((k as u64 * m) % 1009) as f64 / 1009.0;
            points.position.push(DVec2::new(0.6 * r(389), 0.9 * r(577)));
            points.half_width.push(0.025);
            points.volume.push(1e-3 * (1.0 + r(97)));
        }
        let mut world = World::new();
        world.insert_resource(grid.clone());
        world.insert_resource(crate::kernels::Kernels::widest());
        let body = world
            .spawn((points, Location::default(), Bands::default()))
            .id();
        world.run_system_once(locate_points::<CpdiFixed>).unwrap();
        let entity = world.entity(body);
        let (points, location, bands) = (
            entity.get::<crate::body::Points>().unwrap(),
            entity.get::<Location>().unwrap(),
            entity.get::<Bands>().unwrap(),
        );
        let point = |k: usize| {
            let x = points.position[k];
            (k % 7 != 3).then(|| (points.volume[k], [x.x.sin() + 2.0, 3.0 * x.y - x.x]))
        };
        let mut apart = [NodalScalar::default(), NodalScalar::default()];
        for (i, field) in apart.iter_mut().enumerate() {
            scatter(&grid, location, bands, field, |k| {
                point(k).map(|(w, v)| (w, v[i]))
            });
        }
        let (mut a, mut b) = (NodalScalar::default(), NodalScalar::default());
        scatter_many(&grid, location, bands, [&mut a, &mut b], point);
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        for (joint, alone) in [(&a, &apart[0]), (&b, &apart[1])] {
            assert!(alone.weight.iter().filter(|&&w| w > 0.0).count() > 40);
            assert!(alone.weight.contains(&0.0));
            assert_eq!(bits(&joint.weight), bits(&alone.weight));
            assert_eq!(bits(&joint.value), bits(&alone.value));
        }
    }

    #[test]
    fn the_laplacian_of_a_quadratic_is_exact_inside_and_reflects_at_the_edges() {
        let grid = line(10, 0.5, false);
        let x = |i: usize| i as f64 * 0.5;
        let mut f = field_of((0..11).map(|i| 3.0 * x(i) * x(i) - x(i)).collect());
        let mut out = Vec::new();
        laplacian(&grid, &mut f, &OPEN, &mut out);
        for (i, l) in out.iter().enumerate().take(10).skip(1) {
            assert!((l - 6.0).abs() < 1e-12, "node {i}: {l}");
        }
        // Reflected through the end nodes: (2 v_1 - 2 v_0)/h^2.
        let h2 = 0.25;
        assert!((out[0] - 2.0 * (f.value[1] - f.value[0]) / h2).abs() < 1e-12);
        // An inactive node acts as the edge.
        f.weight[6] = 0.0;
        laplacian(&grid, &mut f, &OPEN, &mut out);
        assert_eq!(out[6], 0.0);
        assert!((out[5] - 2.0 * (f.value[4] - f.value[5]) / h2).abs() < 1e-12);
    }

    /// A corner node extrapolates along the normal of the wall that fixes it, not along the
    /// other (bounded) axis: with `v = y^2` fixed at the bottom, every bottom node's Laplacian
    /// is the field's 2, the corners' included.
    #[test]
    fn a_corner_extrapolates_along_its_own_wall() {
        let grid = GridGeometry {
            origin: DVec2::ZERO,
            cell_size: 1.0,
            cells: [4, 6],
            periodic: [false, false],
        };
        let (nx, ny) = (5, 7);
        let mut f = field_of((0..nx * ny).map(|n| ((n / nx) as f64).powi(2)).collect());
        let walls = FieldWalls {
            bottom: NodeCondition::Fixed(0.0),
            ..OPEN
        };
        let mut out = Vec::new();
        laplacian(&grid, &mut f, &walls, &mut out);
        for (i, l) in out.iter().take(nx).enumerate() {
            assert!((l - 2.0).abs() < 1e-12, "bottom node {i}: {l}");
        }
    }

    /// An `Open` segment of a fixed floor leaves the nodes strictly inside it free (zero
    /// flux) and fixes the rest; a `NoSlip` segment of a zero-flux side fixes its nodes.
    #[test]
    fn wall_segments_set_their_own_conditions() {
        let grid = GridGeometry {
            origin: DVec2::ZERO,
            cell_size: 1.0,
            cells: [6, 2],
            periodic: [false, false],
        };
        let nodes = 7 * 3;
        let segments = [
            Segment {
                side: Side::Bottom,
                from: 2.0,
                to: 4.0,
                wall: Wall::Open,
            },
            Segment {
                side: Side::Top,
                from: 0.5,
                to: 1.5,
                wall: Wall::NoSlip,
            },
        ];
        let walls = FieldWalls {
            bottom: NodeCondition::Fixed(0.0),
            segments: &segments,
            ..OPEN
        };
        let mut f = field_of(vec![5.0; nodes]);
        let mut out = Vec::new();
        laplacian(&grid, &mut f, &walls, &mut out);
        let bottom: Vec<f64> = f.value[..7].to_vec();
        assert_eq!(bottom, [0.0, 0.0, 0.0, 5.0, 0.0, 0.0, 0.0]);
        let top: Vec<f64> = f.value[14..].to_vec();
        assert_eq!(top, [5.0, 0.0, 5.0, 5.0, 5.0, 5.0, 5.0]);
    }

    #[test]
    fn a_fixed_wall_sets_its_nodes_and_extrapolates_the_laplacian() {
        let grid = line(8, 1.0, false);
        let mut f = field_of((0..9).map(|i| (i * i) as f64).collect());
        let walls = FieldWalls {
            left: NodeCondition::Fixed(0.0),
            ..OPEN
        };
        let mut out = Vec::new();
        laplacian(&grid, &mut f, &walls, &mut out);
        assert_eq!(f.value[0], 0.0);
        assert!((out[0] - 2.0).abs() < 1e-12 && (out[3] - 2.0).abs() < 1e-12);
        // A periodic axis ignores its walls' conditions and wraps.
        let ring = line(8, 1.0, true);
        let mut f = field_of((0..8).map(|i| (i as f64).sin()).collect());
        laplacian(&ring, &mut f, &walls, &mut out);
        let expected = (7f64.sin() - 2.0 * 0f64.sin() + 1f64.sin()) / 1.0;
        assert!((out[0] - expected).abs() < 1e-12);
    }
}
