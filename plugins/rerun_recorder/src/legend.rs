//! The colour legend drawn beside the domain in the world view.
//!
//! Rerun draws the colours it is given and has no colour bar for them, so the recording
//! carries its own: to the right of the domain, in world coordinates (it scales and pans
//! with the points), one bar per body for the fields scaled by the frame (pressure, speed:
//! each body on its own scale, so the intruder's stress ringing never sets the bed's),
//! one shared bar for the fixed log scales, and labelled swatches for the categories
//! (phase, body). Each bar carries the top of its scale as the component `scale_top`.

use regolith::grid::GridGeometry;
use rerun::{LineStrips2D, Points2D, RecordingStream};

use crate::colour::{self, Field};

/// Segments of a colour bar.
const SEGMENTS: usize = 16;

/// The x-extent of the `slot`-th legend column to the right of the domain.
fn column(grid: &GridGeometry, slot: usize) -> (f32, f32) {
    let (lo, hi) = (grid.origin, grid.max());
    let w = (hi.x - lo.x) as f32;
    let x0 = hi.x as f32 + w * (0.05 + 0.3 * slot as f32);
    (x0, 0.05 * w)
}

/// A vertical bar as tall as the domain in legend column `slot`, `colours(f)` giving the
/// colour at fraction `f` of its height; `labels` are its title (the body, or the field of
/// a shared bar, and the unit), the bottom value and the top value.
fn bar(
    stream: &RecordingStream,
    path: &str,
    grid: &GridGeometry,
    slot: usize,
    labels: [String; 3],
    scale_top: f64,
    colours: impl Fn(f64) -> [u8; 4],
) {
    let (x0, width) = column(grid, slot);
    let (y0, y1) = (grid.origin.y as f32, grid.max().y as f32);
    let dy = (y1 - y0) / SEGMENTS as f32;
    // Rerun draws 2D boxes as outlines; strips as wide as the bar draw it filled.
    let xc = x0 + 0.5 * width;
    let segments = LineStrips2D::new(
        (0..SEGMENTS).map(|k| [[xc, y0 + k as f32 * dy], [xc, y0 + (k + 1) as f32 * dy]]),
    )
    .with_radii([0.5 * width])
    .with_colors((0..SEGMENTS).map(|k| colours((k as f64 + 0.5) / SEGMENTS as f64)));
    let _ = stream.log(format!("{path}/bar"), &segments);
    let top = rerun::external::arrow::array::Float64Array::from(vec![scale_top]);
    let _ = stream.log(
        format!("{path}/bar"),
        &rerun::AnyValues::default()
            .with_component_from_data("scale_top", std::sync::Arc::new(top)),
    );
    let [title, bottom, top] = labels;
    let marks = Points2D::new([
        [x0, y1 + 1.2 * dy],
        [x0 + 1.2 * width, y0],
        [x0 + 1.2 * width, y1],
    ])
    .with_radii([0.0f32])
    .with_labels([title, bottom, top])
    .with_show_labels(true);
    let _ = stream.log(format!("{path}/labels"), &marks);
}

/// Labelled colour swatches, one per category.
fn swatches(
    stream: &RecordingStream,
    path: &str,
    grid: &GridGeometry,
    items: &[(String, [u8; 4])],
) {
    let (x0, width) = column(grid, 0);
    let y1 = grid.max().y as f32;
    let y = |k: usize| y1 - (k as f32 + 0.5) * 2.0 * width;
    let swatches = LineStrips2D::new((0..items.len()).map(|k| [[x0, y(k)], [x0 + width, y(k)]]))
        .with_radii([0.5 * width])
        .with_colors(items.iter().map(|i| i.1))
        .with_labels(items.iter().map(|i| i.0.clone()))
        .with_show_labels(true);
    let _ = stream.log_static(format!("{path}/swatches"), &swatches);
}

/// Logs the legend of this frame. `scales` holds each body's name and the top of its
/// linear scale (unused by the other fields). The fixed legends are logged once (static).
pub fn log(
    stream: &RecordingStream,
    grid: &GridGeometry,
    field: Field,
    scales: &[(&str, f64)],
    first: bool,
) {
    let unit = field.unit();
    match field {
        Field::Pressure | Field::Speed => {
            for (slot, &(name, top)) in scales.iter().enumerate() {
                let labels = [format!("{name} ({unit})"), "0".into(), format!("{top:.3e}")];
                bar(
                    stream,
                    &format!("world/legend/{name}"),
                    grid,
                    slot,
                    labels,
                    top,
                    |f| field.colour(f * top, top),
                );
            }
        }
        Field::PlasticStrainRate | Field::InertialNumber if first => {
            let (lo, hi) = field.log_range();
            let labels = [
                format!("{} ({unit}, log)", field.name()),
                format!("{lo:e}"),
                format!("{hi:e}"),
            ];
            bar(
                stream,
                "world/legend/all",
                grid,
                0,
                labels,
                hi,
                colour::ramp,
            );
        }
        Field::Phase if first => {
            let items: Vec<_> = ["solid", "flowing", "disconnected"]
                .iter()
                .enumerate()
                .map(|(k, n)| (n.to_string(), field.colour(k as f64, 0.0)))
                .collect();
            swatches(stream, "world/legend/all", grid, &items);
        }
        Field::Body if first => {
            let items: Vec<_> = scales
                .iter()
                .enumerate()
                .map(|(k, &(n, _))| (n.to_string(), field.colour(k as f64, 0.0)))
                .collect();
            swatches(stream, "world/legend/all", grid, &items);
        }
        _ => {}
    }
}
