//! Whole-scene checks: the values no single field can judge on its own.

use std::collections::HashSet;

use super::{BodySpec, InitialStress, Scene, StressUpdate, TimeStep, Wall};
use crate::error::SceneError;
use crate::fill::fill;
use crate::geometry::Shape;
use crate::grid::GridGeometry;
use crate::obstacle::Obstacles;
use crate::registry::Item;
use crate::shape_functions::Linear;
use glam::DVec2;

/// Largest grid (cells) and body (points) a scene may ask for: beyond these the state
/// alone needs several GiB per body, more than the machines this runs on are sized for.
const MAX_CELLS: usize = 20_000_000;
const MAX_POINTS: usize = 50_000_000;

/// Fewer material points than this in a body draw a resolution warning.
pub const MIN_POINTS: usize = 100;
/// Fewer cells than this across a body's smallest extent draw a resolution warning.
pub const MIN_CELLS_ACROSS: f64 = 4.0;

/// The line of the `n`-th (from 0) appearance of `needle`.
fn line_of(text: &str, needle: &str, n: usize) -> Option<usize> {
    let (at, _) = text.match_indices(needle).nth(n)?;
    Some(text[..at].matches('\n').count() + 1)
}

/// An error pointing at the line where `needle` first appears (the file alone otherwise).
pub(super) fn near(text: &str, origin: &str, needle: &str, message: String) -> SceneError {
    near_nth(text, origin, needle, 0, message)
}

/// An error pointing at the line where `needle` appears for the `n`-th time (from 0).
fn near_nth(text: &str, origin: &str, needle: &str, n: usize, message: String) -> SceneError {
    match line_of(text, needle, n) {
        Some(line) => SceneError {
            file: origin.to_string(),
            line: Some(line),
            column: None,
            message,
        },
        None => SceneError::file(origin, message),
    }
}

fn positive_finite(v: f64) -> bool {
    v.is_finite() && v > 0.0
}

impl Scene {
    /// The grid this scene's domain and walls describe (assumes a checked scene).
    pub fn grid(&self) -> GridGeometry {
        let (nx, ny) = self.domain.cells;
        GridGeometry {
            origin: self.domain.origin,
            cell_size: self.domain.size.x / nx as f64,
            cells: [nx, ny],
            periodic: [
                self.walls.left == Wall::Periodic,
                self.walls.bottom == Wall::Periodic,
            ],
        }
    }

    /// Choices that are allowed but known to misbehave, one sentence each.
    pub fn warnings(&self) -> Vec<String> {
        let mut w = Vec::new();
        if let Some(cfl) = self.fixed_step_cfl()
            && cfl > 1.0
        {
            w.push(format!(
                "the fixed time step is above the CFL limit (c dt / h = {cfl:.3} > 1) and the run may diverge; allowed by time.allow_unstable"
            ));
        }
        if self.integration.name() == Linear::NAME && self.update == StressUpdate::Usl {
            w.push(
                "Linear integration with update Usl amplifies round-off at nodes of tiny mass and can blow up (docs/numerics.md); CpdiFixed or update: Musl avoid it"
                    .to_string(),
            );
        }
        w.extend(self.resolution_warnings());
        w
    }

    /// A body resolved by fewer than [`MIN_POINTS`] points or [`MIN_CELLS_ACROSS`] cells
    /// across its smallest extent: its motion and stresses are then mostly the grid's.
    fn resolution_warnings(&self) -> Vec<String> {
        let grid = self.grid();
        let preset = self.preset.map_or(String::new(), |p| {
            format!(" (the preset {p:?} sets the resolution)")
        });
        self.bodies
            .iter()
            .filter_map(|b| {
                let points = fill(&*b.shape, &grid, b.points_per_cell).positions.len();
                let (lo, hi) = b.shape.bounds();
                let extent = hi.min(grid.max()) - lo.max(grid.origin);
                // A body exactly 4 cells across can come out as 3.999999999999998 of them
                // (x from 0.46 to 0.5 on cells of 0.01): it meets the bound, and must not be
                // told otherwise.
                let across = extent.x.min(extent.y) / grid.cell_size * (1.0 + 1e-9);
                let mut short = Vec::new();
                if points < MIN_POINTS {
                    short.push(format!(
                        "{points} material points (at least {MIN_POINTS} are advised)"
                    ));
                }
                if across < MIN_CELLS_ACROSS {
                    short.push(format!(
                        "{across:.2} cells across its smallest extent (at least \
                         {MIN_CELLS_ACROSS} are advised)"
                    ));
                }
                (!short.is_empty()).then(|| {
                    format!(
                        "body \"{}\" is coarsely resolved: {}{preset}",
                        b.name,
                        short.join(" and ")
                    )
                })
            })
            .collect()
    }

    /// The CFL number `dt (c + |v|) / h` of a `Fixed` step at the start, from each body's
    /// p-wave speed and initial speed; `None` for a `Cfl` rule.
    pub fn fixed_step_cfl(&self) -> Option<f64> {
        let TimeStep::Fixed(dt) = self.time.step else {
            return None;
        };
        let signal = self
            .bodies
            .iter()
            .map(|b| b.material.wave_speed() + b.velocity.length())
            .fold(0.0, f64::max);
        Some(dt * signal / self.grid().cell_size)
    }

    /// The largest step body `b` can take: the fixed one, or its CFL limit at rest.
    fn largest_step(&self, b: &BodySpec) -> f64 {
        match self.time.step {
            TimeStep::Fixed(dt) => dt,
            TimeStep::Cfl(c) => c * self.grid().cell_size / b.material.wave_speed(),
        }
    }

    /// The fields the scene lists, and the columns each body's fields carry against what its
    /// material reads (module `field`).
    fn check_fields(&self, text: &str, origin: &str) -> Result<(), SceneError> {
        let h = self.grid().cell_size;
        for field in &self.fields {
            let name = field.name();
            let at = |message: String| {
                near(
                    text,
                    origin,
                    &format!("{name}("),
                    format!("{name}: {message}"),
                )
            };
            let Some(body) = field.body() else {
                return Err(at(
                    "a field the scene lists names the body it lives on (body: \"name\")".into(),
                ));
            };
            let b = self.body(body).map_err(at)?;
            field.check_step(h, self.largest_step(b)).map_err(at)?;
        }
        for b in &self.bodies {
            let fields = self.fields_of(b);
            let mut carried: Vec<(&str, &str)> = Vec::new();
            for field in &fields {
                for column in field.columns() {
                    if let Some((_, first)) = carried.iter().find(|(c, _)| c == column) {
                        return Err(near(
                            text,
                            origin,
                            &format!("{}(", field.name()),
                            format!(
                                "{}: body \"{}\" carries the column \"{column}\" already (from {first}); one field per column",
                                field.name(),
                                b.name
                            ),
                        ));
                    }
                    carried.push((column, field.name()));
                }
            }
            if let Some(missing) = b
                .material
                .point_fields()
                .iter()
                .find(|c| !carried.iter().any(|(n, _)| n == *c))
            {
                return Err(near(
                    text,
                    origin,
                    &format!("\"{}\"", b.name),
                    format!(
                        "body \"{}\": its material {} reads the field column \"{missing}\", which no field of the body carries (list one under fields)",
                        b.name,
                        b.material.name()
                    ),
                ));
            }
        }
        Ok(())
    }

    /// Everything that can be wrong with a well-typed scene. `text` (possibly empty) is the
    /// source, used to point at a line.
    pub(super) fn check(&self, text: &str, origin: &str) -> Result<(), SceneError> {
        let err = |needle: &str, message: String| Err(near(text, origin, needle, message));
        // A scene item's own check, reported at the item: `Name(`.
        let item_err =
            |name: &str, message: String| err(&format!("{name}("), format!("{name}: {message}"));
        if self.name.trim().is_empty() || self.name.contains(['/', '\\']) {
            return err(
                "name",
                format!(
                    "name must be a non-empty word without slashes, got {:?}",
                    self.name
                ),
            );
        }
        let d = &self.domain;
        if !(d.origin.is_finite() && positive_finite(d.size.x) && positive_finite(d.size.y)) {
            return err(
                "size",
                format!(
                    "domain size must be two positive numbers (m), got ({}, {})",
                    d.size.x, d.size.y
                ),
            );
        }
        if d.cells.0 == 0 || d.cells.1 == 0 || d.cells.0 > 100_000 || d.cells.1 > 100_000 {
            return err(
                "cells",
                format!(
                    "domain cells must be between 1 and 100000 along each axis, got ({}, {})",
                    d.cells.0, d.cells.1
                ),
            );
        }
        if d.cells.0 * d.cells.1 > MAX_CELLS {
            return err(
                "cells",
                format!(
                    "the grid has {} cells, more than the {MAX_CELLS} a body's nodal field may hold here",
                    d.cells.0 * d.cells.1
                ),
            );
        }
        let (hx, hy) = (d.size.x / d.cells.0 as f64, d.size.y / d.cells.1 as f64);
        if (hx - hy).abs() > 1e-9 * hx.max(hy) {
            return err(
                "cells",
                format!("cells must be square: size/cells gives {hx} m along x but {hy} m along y"),
            );
        }
        let t = &self.time;
        if !positive_finite(t.end) {
            return err(
                "end",
                format!(
                    "time.end must be a positive number of seconds, got {}",
                    t.end
                ),
            );
        }
        if !positive_finite(t.output_every) {
            return err(
                "output_every",
                format!(
                    "time.output_every must be a positive number of seconds, got {}",
                    t.output_every
                ),
            );
        }
        match t.step {
            TimeStep::Fixed(dt) if !positive_finite(dt) => {
                return err(
                    "Fixed",
                    format!("a fixed time step must be a positive number of seconds, got {dt}"),
                );
            }
            TimeStep::Cfl(c) if !(positive_finite(c) && c <= 1.0) => {
                return err("Cfl", format!("the CFL number must lie in (0, 1], got {c}"));
            }
            _ => {}
        }
        if !self.gravity.is_finite() {
            return err(
                "gravity",
                "gravity must be two finite numbers (m/s^2)".to_string(),
            );
        }
        let w = &self.walls;
        if (w.left == Wall::Periodic) != (w.right == Wall::Periodic)
            || (w.bottom == Wall::Periodic) != (w.top == Wall::Periodic)
        {
            return err(
                "walls",
                "a periodic wall needs a periodic opposite wall".to_string(),
            );
        }
        for seg in &w.segments {
            let axis = seg.side.normal_axis();
            let (lo, hi) = (d.origin[1 - axis], d.origin[1 - axis] + d.size[1 - axis]);
            let problem = if w.side(seg.side) == Wall::Periodic {
                Some("a periodic side cannot have segments".to_string())
            } else if seg.wall == Wall::Periodic {
                Some("a segment cannot be Periodic".to_string())
            } else if !(seg.from.is_finite() && seg.to.is_finite() && seg.from < seg.to) {
                Some(format!(
                    "a segment needs from < to (m), got from {} to {}",
                    seg.from, seg.to
                ))
            } else if seg.from < lo || seg.to > hi {
                Some(format!(
                    "a segment of the {:?} side must lie along it, within [{lo}, {hi}] m; got \
                     [{}, {}]",
                    seg.side, seg.from, seg.to
                ))
            } else if w.segments.iter().any(|o| {
                !std::ptr::eq(o, seg) && o.side == seg.side && o.from < seg.to && seg.from < o.to
            }) {
                Some(format!(
                    "segments of the {:?} side overlap at [{}, {}]",
                    seg.side, seg.from, seg.to
                ))
            } else {
                None
            };
            if let Some(why) = problem {
                return err("segments", why);
            }
        }
        let sides = [w.left, w.right, w.bottom, w.top];
        let segment_walls = w.segments.iter().map(|s| s.wall);
        if let Some(why) = sides
            .into_iter()
            .chain(segment_walls)
            .find_map(friction_problem)
        {
            return err("Frictional", why);
        }
        self.check_obstacles()
            .or_else(|why| err("obstacles", why))?;
        // The lock-free scatter's guarantee, checked for this grid before anything runs
        // (every grid passes: a unit test runs the check for every row count up to 1000).
        if let Err(why) = crate::grid::BandLayout::of(&self.grid()).check() {
            return err(
                "cells",
                format!("this grid cannot be scattered without a data race: {why}"),
            );
        }
        if !(self.flip.is_finite() && (0.0..=1.0).contains(&self.flip)) {
            return err(
                "flip",
                format!("flip must lie in [0, 1] (1 = pure FLIP), got {}", self.flip),
            );
        }
        if !self.transfer.blends() && self.flip != 1.0 {
            return err(
                "flip",
                format!(
                    "flip = {} blends FLIP with PIC at every step, which only `transfer: Flip` has; this scene's transfer is {:?}",
                    self.flip, self.transfer
                ),
            );
        }
        if let Some(name) = self.contact.normal_body()
            && !self.bodies.iter().any(|b| b.name == name)
        {
            return err(
                "normal",
                format!("the contact normal names body \"{name}\", which the scene does not have"),
            );
        }
        if self.bodies.is_empty() {
            return err("bodies", "the scene needs at least one body".to_string());
        }
        self.check_bodies(text, origin)?;
        let mut listed = HashSet::new();
        let view = self.view();
        for output in &self.outputs {
            let name = output.name();
            if !listed.insert(name) {
                // Point at the second listing: the first is fine on its own.
                return Err(near_nth(
                    text,
                    origin,
                    &format!("{name}("),
                    1,
                    format!(
                        "{name} is listed twice in outputs; each output can be listed once (one {name} series per run)"
                    ),
                ));
            }
            output.check_scene(&view).or_else(|e| item_err(name, e))?;
        }
        for condition in &self.conditions {
            condition
                .check_scene(&view)
                .or_else(|e| item_err(condition.name(), e))?;
        }
        self.check_fields(text, origin)?;
        if let Some(cfl) = self.fixed_step_cfl()
            && cfl > 1.0
            && !self.time.allow_unstable
        {
            let h = self.grid().cell_size;
            let signal = cfl * h / self.fixed_dt();
            return err(
                "Fixed",
                format!(
                    "the fixed time step {:e} s is above the CFL limit: c dt / h = {cfl:.3} > 1 with c + |v| = {signal:.1} m/s and h = {h} m; the largest stable fixed step is {:.3e} s (use a smaller step, Cfl(C), or time.allow_unstable: true to run anyway)",
                    self.fixed_dt(),
                    h / signal
                ),
            );
        }
        if let Some(ke) = self.limits.max_kinetic_energy
            && !(ke.is_finite() && ke > 0.0)
        {
            return err(
                "max_kinetic_energy",
                format!("limits.max_kinetic_energy must be a positive number (J/m), got {ke}"),
            );
        }
        Ok(())
    }

    /// Each obstacle: a surface an obstacle can have, and at least one grid node inside.
    fn check_obstacles(&self) -> Result<(), String> {
        let grid = self.grid();
        for (k, o) in self.obstacles.iter().enumerate() {
            let which = format!("obstacle {k} ({})", o.shape.name());
            if let Some(why) = o.check().err().or_else(|| friction_problem(o.wall)) {
                return Err(format!("{which}: {why}"));
            }
            if Obstacles::nodes_inside(&*o.shape.0, &grid).is_empty() {
                return Err(format!(
                    "{which} holds no grid node (cell size {} m): material would pass \
                     through it; make it at least a cell thick",
                    grid.cell_size
                ));
            }
        }
        Ok(())
    }

    fn fixed_dt(&self) -> f64 {
        match self.time.step {
            TimeStep::Fixed(dt) => dt,
            TimeStep::Cfl(_) => f64::NAN,
        }
    }

    fn check_bodies(&self, text: &str, origin: &str) -> Result<(), SceneError> {
        let grid = self.grid();
        let (dmin, dmax) = (grid.origin, grid.max());
        let mut names = HashSet::new();
        let mut lattices = Vec::new();
        for b in &self.bodies {
            let needle = format!("\"{}\"", b.name);
            let err = |message: String| {
                Err(near(
                    text,
                    origin,
                    &needle,
                    format!("body \"{}\": {message}", b.name),
                ))
            };
            if !names.insert(b.name.as_str()) {
                return err("another body has the same name".to_string());
            }
            if !(1..=16).contains(&b.points_per_cell) {
                return err(format!(
                    "points_per_cell must be between 1 and 16, got {}",
                    b.points_per_cell
                ));
            }
            if !b.velocity.is_finite() {
                return err("velocity must be two finite numbers (m/s)".to_string());
            }
            // Upward gravity would put the lithostatic column in tension from the bottom up.
            if b.initial_stress == InitialStress::Lithostatic
                && (self.gravity.x != 0.0 || self.gravity.y > 0.0)
            {
                return err(format!(
                    "a lithostatic initial stress needs gravity along -y (gravity.x = 0, \
                     gravity.y <= 0), got ({}, {})",
                    self.gravity.x, self.gravity.y
                ));
            }
            if let Some(k) = b.lateral_stress_ratio {
                if !(k.is_finite() && k >= 0.0) {
                    return err(format!(
                        "lateral_stress_ratio must be a non-negative number, got {k}"
                    ));
                }
                if b.initial_stress != InitialStress::Lithostatic {
                    return err(
                        "lateral_stress_ratio needs initial_stress: Lithostatic".to_string()
                    );
                }
            }
            let (lo, hi) = b.shape.bounds();
            let tol = 1e-9 * grid.cell_size;
            if lo.x < dmin.x - tol
                || lo.y < dmin.y - tol
                || hi.x > dmax.x + tol
                || hi.y > dmax.y + tol
            {
                return err(format!(
                    "its {} spans ({:.4}, {:.4})..({:.4}, {:.4}), outside the domain ({:.4}, {:.4})..({:.4}, {:.4})",
                    b.shape.name(),
                    lo.x,
                    lo.y,
                    hi.x,
                    hi.y,
                    dmin.x,
                    dmin.y,
                    dmax.x,
                    dmax.y
                ));
            }
            let max_dt = self.largest_step(b);
            if let Err(e) = b.material.check_step(grid.cell_size, max_dt) {
                return err(e);
            }
            let spacing = grid.cell_size / b.points_per_cell as f64;
            let span = (hi.min(dmax) - lo.max(dmin)).max(DVec2::ZERO) / spacing;
            if (span.x + 1.0) * (span.y + 1.0) > MAX_POINTS as f64 {
                return err(format!(
                    "it would hold about {:.2e} material points, more than the {MAX_POINTS} a body may have",
                    span.x * span.y
                ));
            }
            let lattice = fill(&*b.shape, &grid, b.points_per_cell);
            if lattice.positions.is_empty() {
                return err(format!(
                    "its shape holds no material point at {} points per cell (cell size {} m); refine the grid or enlarge the body",
                    b.points_per_cell, grid.cell_size
                ));
            }
            lattices.push(lattice);
        }
        for (a, la) in self.bodies.iter().zip(&lattices) {
            // A shape that holds one of `a`'s points: refused at `a`'s line.
            let clash = |shape: &dyn Shape, what: String, rule: &str| match la
                .positions
                .iter()
                .find(|p| shape.contains(**p))
            {
                Some(p) => Err(near(
                    text,
                    origin,
                    &format!("\"{}\"", a.name),
                    format!("{what} (e.g. at ({:.4}, {:.4})); {rule}", p.x, p.y),
                )),
                None => Ok(()),
            };
            for b in self.bodies.iter().filter(|b| !std::ptr::eq(a, *b)) {
                clash(
                    &*b.shape,
                    format!("bodies \"{}\" and \"{}\" overlap", a.name, b.name),
                    "bodies must start apart",
                )?;
            }
            for (k, o) in self.obstacles.iter().enumerate() {
                clash(
                    &*o.shape,
                    format!(
                        "body \"{}\" starts inside obstacle {k} ({})",
                        a.name,
                        o.shape.name()
                    ),
                    "bodies must start outside the obstacles",
                )?;
            }
        }
        Ok(())
    }
}

/// Why a `Frictional` wall's coefficient is not a friction coefficient, if it is not.
fn friction_problem(wall: Wall) -> Option<String> {
    match wall {
        Wall::Frictional { friction } if !(friction.is_finite() && friction >= 0.0) => Some(
            format!("a Frictional wall needs a friction coefficient >= 0, got {friction}"),
        ),
        _ => None,
    }
}
