//! What a recording says about itself: the scene text and resolved setup as a Markdown
//! document, the domain outline, and the default viewer layout.

use std::fmt::Write as _;
use std::path::Path;

use regolith::body::{Body, BodyState, PointStates, Points};
use regolith::grid::{GridField, GridGeometry};
use rerun::RecordingStream;
use rerun::blueprint::{
    Blueprint, Horizontal, Spatial2DView, Tabs, TextDocumentView, TimeSeriesView, Vertical,
};

use crate::record::domain_outline;

type BodyRow<'a> = (
    &'a Body,
    &'a Points,
    &'a PointStates,
    &'a BodyState,
    &'a GridField,
);

/// Points (with the domain, the grid and the colour legend) on the left, taking two thirds
/// of the width; on the right the depth and velocity plots (both components in one plot, so
/// a component that is zero by symmetry shows as a flat line beside the other rather than
/// as round-off noise on its own axis), with the energy, contact force, acceleration, time
/// step and scene document in tabs.
pub fn layout() -> Blueprint {
    Blueprint::new(
        Horizontal::new([
            Spatial2DView::new("material points")
                .with_origin("/")
                .with_contents(["/world/**", "/grid/**"])
                .into(),
            Vertical::new([
                TimeSeriesView::new("depth")
                    .with_contents(["/plots/*/depth"])
                    .into(),
                TimeSeriesView::new("velocity")
                    .with_contents(["/plots/*/velocity/**"])
                    .into(),
                Tabs::new([
                    TimeSeriesView::new("kinetic energy")
                        .with_contents(["/plots/*/kinetic_energy"])
                        .into(),
                    TimeSeriesView::new("contact force")
                        .with_contents(["/plots/*/contact_force/**"])
                        .into(),
                    TimeSeriesView::new("acceleration")
                        .with_contents(["/plots/*/acceleration/**"])
                        .into(),
                    TimeSeriesView::new("time step")
                        .with_contents(["/plots/time_step"])
                        .into(),
                    TextDocumentView::new("scene").with_origin("/scene").into(),
                ])
                .into(),
            ])
            .into(),
        ])
        .with_column_shares([2.0, 1.0]),
    )
}

/// Rerun's 2D views draw y downward; the simulation's y points up (against gravity). A
/// mirror in y at the roots of the spatial entities makes the view show the bed at the
/// bottom while every logged position keeps its simulation value.
pub fn y_up() -> rerun::Transform3D {
    rerun::Transform3D::from_scale([1.0, -1.0, 1.0])
}

/// Logs the static entities: the y mirror of the spatial roots (`grid` only when the grid
/// is recorded), the domain outline and the `scene` document (the scene file
/// the run wrote into its output directory, if any, and the setup as the World holds it).
pub fn log_setup(
    stream: &RecordingStream,
    dir: Option<&Path>,
    grid: &GridGeometry,
    bodies: &[BodyRow],
    with_grid: bool,
) {
    let _ = stream.log_static("world", &y_up());
    if with_grid {
        let _ = stream.log_static("grid", &y_up());
    }
    let _ = stream.log_static("world/domain", &domain_outline(grid));
    let mut md = String::from("# Resolved setup\n\n");
    let _ = writeln!(
        md,
        "- grid: {} x {} cells of {} m from ({}, {})",
        grid.cells[0], grid.cells[1], grid.cell_size, grid.origin.x, grid.origin.y
    );
    for (body, p, _, state, _) in bodies {
        let _ = writeln!(
            md,
            "- body `{}`: {} material, {} points, mass {:.4} kg/m, p-wave speed {:.1} m/s{}",
            body.name,
            body.material,
            p.len(),
            state.mass,
            body.wave_speed,
            if body.tracked { ", tracked" } else { "" }
        );
    }
    if let Some(text) = dir.and_then(|d| std::fs::read_to_string(d.join("scene.ron")).ok()) {
        let _ = write!(md, "\n# Scene\n\n```ron\n{text}\n```\n");
    }
    let _ = stream.log_static("scene", &rerun::TextDocument::from_markdown(md));
}
