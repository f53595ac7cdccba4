//! The chart kinds the figures need, on plotters' bitmap backend: curves with markers, a
//! space-time heat map with a reference line, arrows, and point clouds.

use std::path::Path;

use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;

mod fields;

pub use fields::{ArrowKey, arrows, clouds, space_time};

/// An uncertainty band: its legend label and `(x, low, high)` at each point.
pub type Band = (String, Vec<(f64, f64, f64)>);

/// One labelled series of `(x, y)` points.
pub struct Series {
    pub label: String,
    pub points: Vec<(f64, f64)>,
    /// Drawn hollow and dashed-looking (markers only) to set a variant apart.
    pub hollow: bool,
    /// An uncertainty band drawn shaded in the series' colour behind it.
    pub band: Option<Band>,
}

type Result<T> = std::result::Result<T, String>;

/// Points `(x, y)` drawn in one colour.
pub type Cloud = Vec<(f64, f64)>;
/// A panel's caption and its clouds.
pub type Panel = (String, Vec<Cloud>);

fn fail(e: impl std::fmt::Display) -> String {
    e.to_string()
}

/// Registers the bundled font once (plotters' ab_glyph text needs one).
pub fn register_font() -> Result<()> {
    static DONE: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    let ok = *DONE.get_or_init(|| {
        plotters::style::register_font("sans-serif", FontStyle::Normal, dejavu::sans::regular())
            .is_ok()
    });
    if ok {
        Ok(())
    } else {
        Err("the bundled font could not be loaded".into())
    }
}

/// Distinct line colours; seven, so that the paper's seven tip slopes each have their own.
const PALETTE: [RGBColor; 7] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
    RGBColor(255, 127, 14),
    RGBColor(23, 190, 207),
    RGBColor(140, 86, 75),
];

fn bounds(values: impl Iterator<Item = f64>, pad_zero: bool) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    if pad_zero {
        lo = lo.min(0.0);
    }
    let pad = 0.05 * (hi - lo).max(1e-12);
    (lo - pad, hi + pad)
}

/// A titled chart over `x` and `y` ranges with labelled axes.
fn chart<'a, DB: DrawingBackend + 'a>(
    area: &'a DrawingArea<DB, plotters::coord::Shift>,
    title: &str,
    size: u32,
    ranges: ((f64, f64), (f64, f64)),
    axes: (&str, &str),
) -> Result<ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>>
where
    DB::ErrorType: 'static,
{
    let ((x0, x1), (y0, y1)) = ranges;
    let mut chart = ChartBuilder::on(area)
        .caption(title, ("sans-serif", size))
        .margin(16)
        .x_label_area_size(60)
        .y_label_area_size(85)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(fail)?;
    // Readable at a column's width: 18 px tick labels, 20 px axis names, a light major grid
    // and no minor one.
    chart
        .configure_mesh()
        .x_desc(axes.0)
        .y_desc(axes.1)
        .label_style(("sans-serif", 18))
        .axis_desc_style(("sans-serif", 20))
        .bold_line_style(BLACK.mix(0.12))
        .light_line_style(TRANSPARENT)
        .draw()
        .map_err(fail)?;
    Ok(chart)
}

/// The corner of the plot area holding the fewest of `points` (over `ranges`): where the
/// legend covers the least data.
fn emptiest_corner(points: &[(f64, f64)], ranges: ((f64, f64), (f64, f64))) -> SeriesLabelPosition {
    let ((x0, x1), (y0, y1)) = ranges;
    // A legend covers roughly the outer 40% of the width and 30% of the height.
    let count = |right: bool, top: bool| {
        points
            .iter()
            .filter(|&&(x, y)| {
                let fx = (x - x0) / (x1 - x0);
                let fy = (y - y0) / (y1 - y0);
                (if right { fx > 0.6 } else { fx < 0.4 }) && (if top { fy > 0.7 } else { fy < 0.3 })
            })
            .count()
    };
    let corners = [
        (SeriesLabelPosition::UpperRight, count(true, true)),
        (SeriesLabelPosition::UpperLeft, count(false, true)),
        (SeriesLabelPosition::LowerRight, count(true, false)),
        (SeriesLabelPosition::LowerLeft, count(false, false)),
    ];
    corners
        .into_iter()
        .min_by_key(|c| c.1)
        .map(|c| c.0)
        .unwrap_or(SeriesLabelPosition::UpperRight)
}

/// Draws the legend of the labelled series at `position`.
fn legend<'a, DB: DrawingBackend + 'a>(
    chart: &mut ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
    position: SeriesLabelPosition,
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    chart
        .configure_series_labels()
        .position(position)
        .background_style(WHITE.mix(0.9))
        .border_style(BLACK)
        .label_font(("sans-serif", 18))
        .draw()
        .map_err(fail)
}

/// Curves with markers, one colour per series, a legend; the axes start at zero.
pub fn curves(path: &Path, title: &str, x: &str, y: &str, series: &[Series]) -> Result<()> {
    curves_over(path, title, (x, None), y, series)
}

/// `curves`, with the `x` axis over `range` if given (a variable whose zero is far off, such
/// as a slope angle), else from zero.
pub fn curves_over(
    path: &Path,
    title: &str,
    (x, range): (&str, Option<(f64, f64)>),
    y: &str,
    series: &[Series],
) -> Result<()> {
    let root = BitMapBackend::new(path, (900, 620)).into_drawing_area();
    root.fill(&WHITE).map_err(fail)?;
    let xs = range.unwrap_or_else(|| {
        bounds(
            series.iter().flat_map(|s| s.points.iter().map(|p| p.0)),
            true,
        )
    });
    let band_ends = series
        .iter()
        .filter_map(|s| s.band.as_ref())
        .flat_map(|(_, b)| b.iter().flat_map(|&(_, lo, hi)| [lo, hi]));
    let ys = bounds(
        series
            .iter()
            .flat_map(|s| s.points.iter().map(|p| p.1))
            .chain(band_ends),
        true,
    );
    let mut chart = chart(&root, title, 24, (xs, ys), (x, y))?;
    let all: Vec<(f64, f64)> = series.iter().flat_map(|s| s.points.clone()).collect();
    let corner = emptiest_corner(&all, (xs, ys));
    for (k, s) in series.iter().enumerate() {
        let colour = PALETTE[k % PALETTE.len()];
        if let Some((label, band)) = &s.band {
            let mut band: Vec<_> = band
                .iter()
                .copied()
                .filter(|b| b.0.is_finite() && b.1.is_finite() && b.2.is_finite())
                .collect();
            band.sort_by(|a, b| a.0.total_cmp(&b.0));
            // The low edge forward, the high edge back: one shaded polygon.
            let outline: Vec<(f64, f64)> = band
                .iter()
                .map(|&(x, lo, _)| (x, lo))
                .chain(band.iter().rev().map(|&(x, _, hi)| (x, hi)))
                .collect();
            let shade = colour.mix(0.22);
            chart
                .draw_series(std::iter::once(Polygon::new(outline, shade.filled())))
                .map_err(fail)?
                .label(label.clone())
                .legend(move |(x, y)| {
                    Rectangle::new([(x, y - 6), (x + 20, y + 6)], shade.filled())
                });
        }
        let mut pts = s.points.clone();
        pts.retain(|p| p.0.is_finite() && p.1.is_finite());
        pts.sort_by(|a, b| a.0.total_cmp(&b.0));
        let style = if s.hollow {
            colour.stroke_width(1)
        } else {
            colour.stroke_width(2)
        };
        chart
            .draw_series(LineSeries::new(pts.clone(), style))
            .map_err(fail)?
            .label(s.label.clone())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], colour));
        let hollow = s.hollow;
        chart
            .draw_series(pts.iter().map(move |&p| {
                let marker = if hollow {
                    colour.stroke_width(2)
                } else {
                    colour.filled()
                };
                Circle::new(p, 5, marker)
            }))
            .map_err(fail)?;
    }
    legend(&mut chart, corner)?;
    root.present().map_err(fail)
}

/// A named point of a cost-error chart: name, wall time (s), relative error, on the frontier.
pub type Labelled = (String, f64, f64, bool);

/// Errors below this are drawn at it (a run equal to the reference has error zero).
const ERROR_FLOOR: f64 = 1e-4;

/// Relative error against wall time, both on log10 axes, each point named, the frontier
/// points joined in order of cost.
pub fn pareto(path: &Path, title: &str, points: &[Labelled]) -> Result<()> {
    register_font()?;
    let root = BitMapBackend::new(path, (1000, 700)).into_drawing_area();
    root.fill(&WHITE).map_err(fail)?;
    let at = |w: f64, e: f64| (w.max(1e-3).log10(), e.max(ERROR_FLOOR).log10());
    let xy: Vec<(f64, f64)> = points.iter().map(|p| at(p.1, p.2)).collect();
    let (x0, x1) = bounds(xy.iter().map(|p| p.0), false);
    let (y0, y1) = bounds(xy.iter().map(|p| p.1), false);
    let ranges = ((x0 - 0.1, x1 + 0.25), (y0 - 0.1, y1 + 0.1));
    let axes = (
        "log10 wall time (s, one thread)",
        "log10 relative error (larger of final depth and stopping time)",
    );
    let mut chart = chart(&root, title, 22, ranges, axes)?;
    let mut front: Vec<(f64, f64)> = points
        .iter()
        .zip(&xy)
        .filter(|(p, _)| p.3)
        .map(|(_, &q)| q)
        .collect();
    front.sort_by(|a, b| a.0.total_cmp(&b.0));
    chart
        .draw_series(LineSeries::new(front, PALETTE[1].stroke_width(2)))
        .map_err(fail)?
        .label("frontier")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], PALETTE[1]));
    for (p, &q) in points.iter().zip(&xy) {
        let colour = if p.3 { PALETTE[1] } else { PALETTE[0] };
        chart
            .draw_series(std::iter::once(Circle::new(q, 5, colour.filled())))
            .map_err(fail)?;
        chart
            .draw_series(std::iter::once(Text::new(
                p.0.clone(),
                (q.0 + 0.02, q.1),
                ("sans-serif", 16),
            )))
            .map_err(fail)?;
    }
    legend(&mut chart, emptiest_corner(&xy, ranges))?;
    root.present().map_err(fail)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn is_png(path: &Path) -> bool {
        std::fs::read(path).is_ok_and(|b| b.starts_with(b"\x89PNG\r\n\x1a\n") && b.len() > 1000)
    }

    #[test]
    fn the_legend_goes_to_the_corner_without_data() {
        let ranges = ((0.0, 1.0), (0.0, 1.0));
        // Data rising from lower left to upper right, as depth against energy.
        let rising: Vec<(f64, f64)> = (0..=10).map(|k| (0.1 * k as f64, 0.1 * k as f64)).collect();
        let corner = emptiest_corner(&rising, ranges);
        assert!(
            matches!(
                corner,
                SeriesLabelPosition::UpperLeft | SeriesLabelPosition::LowerRight
            ),
            "{corner:?}"
        );
        let upper_left: Vec<(f64, f64)> = vec![(0.1, 0.9), (0.2, 0.8), (0.9, 0.9), (0.1, 0.1)];
        assert!(matches!(
            emptiest_corner(&upper_left, ranges),
            SeriesLabelPosition::LowerRight
        ));
    }

    #[test]
    fn every_chart_kind_writes_a_png() {
        register_font().unwrap();
        let dir = tempfile::tempdir().unwrap();
        let series = [Series {
            label: "a".into(),
            points: vec![(0.0, 1.0), (1.0, 2.0), (2.0, f64::NAN)],
            hollow: true,
            band: Some(("band".into(), vec![(0.0, 0.5, 1.5), (1.0, 1.5, 2.5)])),
        }];
        let p = dir.path().join("curves.png");
        curves(&p, "t", "x", "y", &series).unwrap();
        assert!(is_png(&p));
        let p = dir.path().join("st.png");
        let values = vec![vec![0.0, 1.0], vec![2.0, 0.5]];
        space_time(&p, "t", &[0.0, 1e-4], &[0.005, 0.015], &values, 274.0).unwrap();
        assert!(is_png(&p));
        let p = dir.path().join("arrows.png");
        arrows(
            &p,
            "t",
            ("x", "y"),
            &[(0.0, 0.0)],
            &[(0.1, -0.2)],
            ((-1.0, 1.0), (-1.0, 1.0)),
            &ArrowKey {
                disc: ((0.0, 0.0), 0.5),
                length: 0.15,
                meaning: "unit".into(),
            },
        )
        .unwrap();
        assert!(is_png(&p));
        let p = dir.path().join("clouds.png");
        let panels = vec![(
            "t = 0".to_string(),
            vec![vec![(0.1, 0.1)], vec![(0.2, 0.2)]],
        )];
        clouds(&p, "t", &panels, ((0.0, 1.0), (0.0, 1.0))).unwrap();
        assert!(is_png(&p));
    }
}
