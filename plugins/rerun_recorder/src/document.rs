//! What a recording says about itself: the scene text and resolved setup as a Markdown
//! document, the domain outline, and the default viewer layout.

use std::fmt::Write as _;
use std::path::Path;

use regolith::body::{Body, BodyState, PointStates, Points};
use regolith::grid::{GridField, GridGeometry};
use rerun::blueprint::components::PlayState;
use rerun::blueprint::{
    Blueprint, ContainerLike, Horizontal, Spatial2DView, Tabs, TextDocumentView, TimePanel,
    TimeSeriesView, Vertical,
};
use rerun::{LineStrips2D, RecordingStream};

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
/// step and scene document in tabs. The viewer opens on the `sim_time` timeline, paused.
///
/// The plots list their entities by body: the viewer's entity filters take `/**` only at the
/// end of a path, so `/plots/*/depth` would match nothing.
pub fn layout(bodies: &[(&str, bool)]) -> Blueprint {
    let mut right: Vec<ContainerLike> = plot_contents(bodies)
        .into_iter()
        .map(|(name, contents)| TimeSeriesView::new(name).with_contents(contents).into())
        .collect();
    // Depth and velocity stay in view; the other plots and the scene go into tabs.
    let tabs = right.split_off(2);
    let scene = TextDocumentView::new("scene").with_origin("/scene").into();
    right.push(Tabs::new(tabs.into_iter().chain([scene])).into());
    Blueprint::new(
        Horizontal::new([
            Spatial2DView::new("material points")
                .with_origin("/")
                .with_contents(["/world/**", "/grid/**"])
                .into(),
            Vertical::new(right).into(),
        ])
        .with_column_shares([2.0, 1.0]),
    )
    // Simulated seconds, paused: a viewer left to follow the newest data keeps the plots on
    // the last few hundred frames, where the descent is never seen.
    .with_time_panel(
        TimePanel::new()
            .with_timeline("sim_time")
            .with_play_state(PlayState::Paused),
    )
}

/// The time-series views of [`layout`], in order, with their entity filters.
fn plot_contents(bodies: &[(&str, bool)]) -> Vec<(&'static str, Vec<String>)> {
    let each = |tracked_only: bool, tail: &str| -> Vec<String> {
        bodies
            .iter()
            .filter(|b| b.1 || !tracked_only)
            .map(|b| format!("/plots/{}/{tail}", b.0))
            .collect()
    };
    vec![
        ("depth", each(true, "depth")),
        ("velocity", each(true, "velocity/**")),
        ("kinetic energy", each(false, "kinetic_energy")),
        ("contact force", each(true, "contact_force/**")),
        ("acceleration", each(true, "acceleration/**")),
        ("time step", vec!["/plots/time_step".into()]),
    ]
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

/// The domain's outline, logged once.
fn domain_outline(grid: &GridGeometry) -> LineStrips2D {
    let (lo, hi) = (grid.origin, grid.max());
    let corners = [
        [lo.x as f32, lo.y as f32],
        [hi.x as f32, lo.y as f32],
        [hi.x as f32, hi.y as f32],
        [lo.x as f32, hi.y as f32],
        [lo.x as f32, lo.y as f32],
    ];
    LineStrips2D::new([corners]).with_colors([[0u8, 0, 0, 255]])
}

#[cfg(test)]
mod tests {
    use super::plot_contents;

    /// Rerun's entity filters take a wildcard only as a final `/**`: a filter such as
    /// `/plots/*/depth` matches nothing and leaves its plot empty.
    #[test]
    fn every_plot_filter_names_a_path_or_a_subtree() {
        let views = plot_contents(&[("bed", false), ("intruder", true)]);
        assert_eq!(views.len(), 6);
        for (name, filters) in &views {
            assert!(!filters.is_empty(), "{name}: no entities");
            for f in filters {
                let stem = f.strip_suffix("/**").unwrap_or(f);
                assert!(!stem.contains('*'), "{name}: {f}");
                assert!(f.starts_with("/plots/"), "{name}: {f}");
            }
        }
        assert_eq!(views[0].1, ["/plots/intruder/depth"]);
        assert_eq!(
            views[2].1,
            [
                "/plots/bed/kinetic_energy",
                "/plots/intruder/kinetic_energy"
            ]
        );
    }
}
