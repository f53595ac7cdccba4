//! Charts of fields: the space-time heat map with its colour bar, arrows of a velocity field,
//! point clouds with equal axes.

use std::path::Path;

use plotters::prelude::*;

use super::{PALETTE, Panel, Result, chart, fail};

/// The heat map's colour at fraction `f` of its top: blue through green to red.
fn heat(f: f64) -> RGBColor {
    let f = f.clamp(0.0, 1.0);
    RGBColor(
        (255.0 * f) as u8,
        (255.0 * (1.0 - (2.0 * f - 1.0).abs())) as u8,
        (255.0 * (1.0 - f)) as u8,
    )
}

/// A heat map of `values[row][col]` (Pa) over `times` (x) and `radii` (y), with the line
/// `r = speed t` drawn over it and a colour bar beside it.
pub fn space_time(
    path: &Path,
    title: &str,
    times: &[f64],
    radii: &[f64],
    values: &[Vec<f64>],
    speed: f64,
) -> Result<()> {
    let root = BitMapBackend::new(path, (1000, 620)).into_drawing_area();
    root.fill(&WHITE).map_err(fail)?;
    let (main, side) = root.split_horizontally(860);
    let dt = times
        .windows(2)
        .map(|w| w[1] - w[0])
        .fold(0.0, f64::max)
        .max(1e-12);
    let dr = if radii.len() > 1 {
        radii[1] - radii[0]
    } else {
        1.0
    };
    let (t1, r1) = (
        times.last().copied().unwrap_or(1.0) + dt,
        radii.last().copied().unwrap_or(1.0) + dr,
    );
    let ms = 1e3;
    let x_axis = format!("time (ms); black line: p-wave speed sqrt(M/rho_c) = {speed:.0} m/s");
    let axes = (x_axis.as_str(), "distance from the impact point (m)");
    let mut chart = chart(&main, title, 22, ((0.0, t1 * ms), (0.0, r1)), axes)?;
    let top = values
        .iter()
        .flatten()
        .copied()
        .fold(0.0f64, f64::max)
        .max(1e-12);
    for (k, row) in values.iter().enumerate() {
        let t = times[k];
        for (b, &v) in row.iter().enumerate() {
            let (r0, r1) = (radii[b] - 0.5 * dr, radii[b] + 0.5 * dr);
            chart
                .draw_series(std::iter::once(Rectangle::new(
                    [((t - 0.5 * dt) * ms, r0), ((t + 0.5 * dt) * ms, r1)],
                    heat(v / top).filled(),
                )))
                .map_err(fail)?;
        }
    }
    chart
        .draw_series(LineSeries::new(
            [(0.0, 0.0), (t1 * ms, speed * t1)],
            BLACK.stroke_width(2),
        ))
        .map_err(fail)?;
    colour_bar(&side, "pressure rise (kPa)", top)
}

/// A vertical colour bar of [`heat`] from 0 to `top` (Pa), its axis labelled in kPa.
fn colour_bar<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    label: &str,
    top: f64,
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let mut bar = ChartBuilder::on(area)
        .caption(label, ("sans-serif", 17))
        .margin_top(40)
        .margin_bottom(57)
        .margin_right(8)
        .y_label_area_size(70)
        .build_cartesian_2d(0.0..1.0, 0.0..top)
        .map_err(fail)?;
    bar.configure_mesh()
        .disable_x_mesh()
        .disable_x_axis()
        .disable_y_mesh()
        .y_label_formatter(&|v| format!("{:.0}", v / 1e3))
        .label_style(("sans-serif", 16))
        .draw()
        .map_err(fail)?;
    const STEPS: usize = 64;
    bar.draw_series((0..STEPS).map(|k| {
        let (f0, f1) = (k as f64 / STEPS as f64, (k + 1) as f64 / STEPS as f64);
        Rectangle::new(
            [(0.0, f0 * top), (1.0, f1 * top)],
            heat(0.5 * (f0 + f1)).filled(),
        )
    }))
    .map_err(fail)?;
    Ok(())
}

/// What an arrow chart draws beside the arrows: a circle (the intruder, centre and radius
/// in axis units) and a reference arrow of `length` axis units with its meaning.
pub struct ArrowKey {
    pub disc: ((f64, f64), f64),
    pub length: f64,
    pub meaning: String,
}

/// Arrows from `origins` along `vectors` (same units as the axes), on equal axes, with the
/// intruder outlined and a reference arrow in the lower left corner.
pub fn arrows(
    path: &Path,
    title: &str,
    axes: (&str, &str),
    origins: &[(f64, f64)],
    vectors: &[(f64, f64)],
    window: ((f64, f64), (f64, f64)),
    key: &ArrowKey,
) -> Result<()> {
    let size = equal_aspect(window, 760);
    let root = BitMapBackend::new(path, size).into_drawing_area();
    root.fill(&WHITE).map_err(fail)?;
    let mut chart = chart(&root, title, 22, window, axes)?;
    let colour = PALETTE[0];
    chart
        .draw_series(origins.iter().zip(vectors).map(|(&o, &v)| {
            PathElement::new(vec![o, (o.0 + v.0, o.1 + v.1)], colour.stroke_width(1))
        }))
        .map_err(fail)?;
    chart
        .draw_series(origins.iter().map(|&o| Circle::new(o, 1, colour.filled())))
        .map_err(fail)?;
    let ((cx, cy), r) = key.disc;
    let outline: Vec<(f64, f64)> = (0..=72)
        .map(|k| {
            let a = k as f64 * std::f64::consts::TAU / 72.0;
            (cx + r * a.cos(), cy + r * a.sin())
        })
        .collect();
    chart
        .draw_series(std::iter::once(PathElement::new(
            outline,
            BLACK.stroke_width(2),
        )))
        .map_err(fail)?;
    let ((x0, x1), (y0, y1)) = window;
    let at = (x0 + 0.05 * (x1 - x0), y0 + 0.05 * (y1 - y0));
    let tip = (at.0 + key.length, at.1);
    let head = 0.25 * key.length;
    chart
        .draw_series([
            PathElement::new(vec![at, tip], BLACK.stroke_width(2)),
            PathElement::new(
                vec![
                    (tip.0 - head, tip.1 + 0.5 * head),
                    tip,
                    (tip.0 - head, tip.1 - 0.5 * head),
                ],
                BLACK.stroke_width(2),
            ),
        ])
        .map_err(fail)?;
    chart
        .draw_series(std::iter::once(Text::new(
            key.meaning.clone(),
            (tip.0 + 0.3 * head, at.1 + 0.4 * head),
            ("sans-serif", 18),
        )))
        .map_err(fail)?;
    root.present().map_err(fail)
}

/// Label areas and margins of [`chart`] in pixels, for sizing equal-aspect figures.
const CHART_FRAME: (u32, u32) = (65 + 24, 45 + 24 + 40);

/// The image size for `window` at `width` pixels so that a unit is as long along y as x.
fn equal_aspect(window: ((f64, f64), (f64, f64)), width: u32) -> (u32, u32) {
    let ((x0, x1), (y0, y1)) = window;
    let plot = f64::from(width - CHART_FRAME.0);
    let height = plot * (y1 - y0) / (x1 - x0);
    (width, height.round() as u32 + CHART_FRAME.1)
}

/// Point clouds side by side on equal axes, one panel per `(caption, clouds)`; each cloud
/// is one colour.
pub fn clouds(
    path: &Path,
    title: &str,
    panels: &[Panel],
    window: ((f64, f64), (f64, f64)),
) -> Result<()> {
    let (w, h) = equal_aspect(window, 600);
    let root = BitMapBackend::new(path, (w * panels.len() as u32, h + 30)).into_drawing_area();
    root.fill(&WHITE).map_err(fail)?;
    let root = root.titled(title, ("sans-serif", 24)).map_err(fail)?;
    let areas = root.split_evenly((1, panels.len().max(1)));
    for (area, (caption, clouds)) in areas.iter().zip(panels) {
        let mut chart = chart(area, caption, 20, window, ("x (m)", "y (m)"))?;
        for (k, cloud) in clouds.iter().enumerate() {
            let colour = PALETTE[k % PALETTE.len()];
            chart
                .draw_series(cloud.iter().map(|&p| Circle::new(p, 1, colour.filled())))
                .map_err(fail)?;
        }
    }
    root.present().map_err(fail)
}
