//! How honest a granular body still is at the end of a run: the `health` of each granular
//! body in `summary.json`, and the run's `warnings` when a bound is passed.
//!
//! A run can reach its end time with a flow that has gone wrong without any fault: a dense
//! layer that compacts at constant point volume (docs/numerics.md) sinks while every point
//! keeps its volume (the shipped chute: to half its thickness, its points' volume twice the
//! area they fill, at 20 s). That is no divergence, so the fault checks (`diagnostics`)
//! never stop it; these measures say it in the summary and the run's last lines instead.
//!
//! The dense bulk is the body's interior cells: cells holding points of the body whose
//! eight neighbours hold some too (across a periodic side the neighbour wraps; beyond any
//! other side it counts as held, so a bed resting on the floor is dense down to it). There
//! an honest body's points fill the cells: their summed volume equals the cells' area
//! whatever the density, because a point's volume follows its deformation. Compaction at
//! constant point volume crowds more point volume into fewer cells (ratio above 1); holes
//! the points do not see give a ratio below 1.

use glam::DVec2;
use serde::Serialize;

use crate::body::{Phase, PointStates, Points};
use crate::grid::GridGeometry;

/// The bound on `|bulk_volume_ratio - 1|` past which a run warns. The elastic compression
/// of a dense bed is `p / K`, about 1e-5 in the shipped scenes; the shipped beds end within
/// 0.3% of 1 and the collapsed columns within 1.7% (docs/VALIDATION.md, "Health"), and the
/// compacting chute reaches 2.04.
pub const VOLUME_BOUND: f64 = 0.02;

/// The bound on a layer's thickness drift past which a run warns: a layer of constant mass
/// keeps its thickness to `p / K` whatever it does, so 2% is a compaction (or a dilation)
/// the model does not have.
pub const HEIGHT_BOUND: f64 = 0.02;

/// One granular body's health (summary.json `bodies[].health`).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct BodyHealth {
    /// Mass fraction of the body's points that are disconnected (below the critical
    /// density, carrying no stress).
    pub disconnected_fraction: f64,
    /// Mass fraction of the points in the dense bulk (interior cells) that are disconnected.
    pub bulk_disconnected_fraction: f64,
    /// Summed point volume in the interior cells over their area: 1 for an honest body.
    pub bulk_volume_ratio: f64,
    /// Interior cells counted.
    pub bulk_cells: usize,
    /// For a layer (a body that spans a periodic domain's width): its thickness now over
    /// its thickness at the start, minus 1. The thickness is from the 1st to the 99th
    /// percentile of the points' heights, plus their spacing; the start's is the body's
    /// shape's height.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub height_drift: Option<f64>,
}

impl BodyHealth {
    /// Measures `points` on `grid`; `layer` is the bottom and top at the start when the
    /// body is a layer ([`layer_bounds`]).
    pub fn measure(
        points: &Points,
        states: &PointStates,
        grid: &GridGeometry,
        layer: Option<(f64, f64)>,
    ) -> BodyHealth {
        let n = points.len();
        let mass: f64 = points.mass.iter().sum();
        if n == 0 || mass <= 0.0 {
            return BodyHealth::default();
        }
        let gas = |k: usize| states.phase[k] == Phase::Disconnected;
        let inv_h = 1.0 / grid.cell_size;
        let [nx, ny] = grid.cells;
        let cell: Vec<[usize; 2]> = points
            .position
            .iter()
            .map(|&x| grid.cell_at(x, inv_h))
            .collect();
        let mut held = vec![false; nx * ny];
        for &[i, j] in &cell {
            held[j * nx + i] = true;
        }
        let neighbour = |i: usize, d: i64, cells: usize, periodic: bool| -> Option<usize> {
            let k = i as i64 + d;
            match (k, periodic) {
                (k, _) if (0..cells as i64).contains(&k) => Some(k as usize),
                (k, true) => Some(k.rem_euclid(cells as i64) as usize),
                _ => None,
            }
        };
        let interior = |i: usize, j: usize| {
            held[j * nx + i]
                && (-1..=1).all(|di| {
                    (-1..=1).all(|dj| {
                        match (
                            neighbour(i, di, nx, grid.periodic[0]),
                            neighbour(j, dj, ny, grid.periodic[1]),
                        ) {
                            (Some(a), Some(b)) => held[b * nx + a],
                            _ => true,
                        }
                    })
                })
        };
        let inside: Vec<bool> = (0..nx * ny).map(|c| interior(c % nx, c / nx)).collect();
        let (mut bulk_mass, mut bulk_gas, mut bulk_volume) = (0.0, 0.0, 0.0);
        for (k, &[i, j]) in cell.iter().enumerate() {
            if inside[j * nx + i] {
                bulk_mass += points.mass[k];
                bulk_volume += points.volume[k];
                if gas(k) {
                    bulk_gas += points.mass[k];
                }
            }
        }
        let bulk_cells = inside.iter().filter(|&&c| c).count();
        let area = bulk_cells as f64 * grid.cell_size * grid.cell_size;
        // A fold from +0: an empty `sum` of floats is -0, which summary.json would print.
        let disconnected = (0..n)
            .filter(|&k| gas(k))
            .fold(0.0, |acc, k| acc + points.mass[k]);
        BodyHealth {
            disconnected_fraction: disconnected / mass,
            bulk_disconnected_fraction: if bulk_mass > 0.0 {
                bulk_gas / bulk_mass
            } else {
                0.0
            },
            bulk_volume_ratio: if area > 0.0 { bulk_volume / area } else { 1.0 },
            bulk_cells,
            height_drift: layer.map(|(bottom, top)| thickness(points) / (top - bottom) - 1.0),
        }
    }

    /// What passes a bound, one sentence each, naming `body`. A disconnected bulk is
    /// reported but not warned about: an intruder's wake separates from it physically (the
    /// coarse flow field's bed is 19% disconnected in its bulk at 0.1 s).
    pub fn warnings(&self, body: &str) -> Vec<String> {
        let mut out = Vec::new();
        if self.bulk_cells > 0 && (self.bulk_volume_ratio - 1.0).abs() > VOLUME_BOUND {
            out.push(format!(
                "{body}: the points' summed volume in its dense bulk is {:.4} of the area they fill (bound {VOLUME_BOUND}): the body {} at constant point volume, which the model does not do (docs/numerics.md, compaction)",
                self.bulk_volume_ratio,
                if self.bulk_volume_ratio > 1.0 { "compacted" } else { "opened" }
            ));
        }
        if let Some(drift) = self.height_drift
            && drift.abs() > HEIGHT_BOUND
        {
            out.push(format!(
                "{body}: the layer's thickness changed by {:+.1}% (bound {:.0}%): a layer of constant mass keeps its thickness",
                100.0 * drift,
                100.0 * HEIGHT_BOUND
            ));
        }
        out
    }
}

/// A layer's thickness: from the 1st to the 99th percentile of the points' heights, plus
/// their spacing (half of it at either end).
fn thickness(points: &Points) -> f64 {
    let mut y: Vec<f64> = points.position.iter().map(|x| x.y).collect();
    y.sort_by(f64::total_cmp);
    let spacing = 2.0 * points.half_width.first().copied().unwrap_or(0.0);
    let at = |q: f64| y[(q * (y.len() - 1) as f64).round() as usize];
    at(0.99) - at(0.01) + spacing
}

/// The bottom and top at the start of a body whose shape spans `bounds`, when it is a
/// layer: a body across the whole width of a domain periodic in x (clipped to the domain).
pub fn layer_bounds(bounds: (DVec2, DVec2), grid: &GridGeometry) -> Option<(f64, f64)> {
    let tolerance = 1e-9 * grid.size().x;
    let across = bounds.0.x <= grid.origin.x + tolerance && bounds.1.x >= grid.max().x - tolerance;
    let (bottom, top) = (bounds.0.y.max(grid.origin.y), bounds.1.y.min(grid.max().y));
    (grid.periodic[0] && across && top > bottom).then_some((bottom, top))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A periodic 1 m x 1 m box of 10 x 10 cells and a layer of 2 x 2 points per cell over
    /// the bottom `rows` rows, each point of volume `h^2 / 4`, squeezed in y by `squeeze`.
    fn layer(rows: usize, squeeze: f64) -> (Points, PointStates, GridGeometry) {
        let grid = GridGeometry {
            origin: DVec2::ZERO,
            cell_size: 0.1,
            cells: [10, 10],
            periodic: [true, false],
        };
        let mut points = Points::default();
        for j in 0..2 * rows {
            for i in 0..20 {
                let x = DVec2::new(0.025 + 0.05 * i as f64, squeeze * (0.025 + 0.05 * j as f64));
                points.position.push(x);
                points.mass.push(1.0);
                points.volume.push(0.0025);
                points.half_width.push(0.025);
            }
        }
        let states = PointStates::new(points.len());
        (points, states, grid)
    }

    #[test]
    fn an_honest_layer_is_healthy_and_a_compacted_one_is_not() {
        let bounds = (DVec2::ZERO, DVec2::new(1.0, 0.6));
        let (points, states, grid) = layer(6, 1.0);
        let start = layer_bounds(bounds, &grid);
        assert_eq!(start, Some((0.0, 0.6)));
        let health = BodyHealth::measure(&points, &states, &grid, start);
        // Rows 0-4 are interior (row 5 has nothing above it): 50 cells, exactly filled.
        assert_eq!(health.bulk_cells, 50);
        assert!((health.bulk_volume_ratio - 1.0).abs() < 1e-12, "{health:?}");
        assert!(health.height_drift.unwrap().abs() < 1e-12, "{health:?}");
        assert!(health.warnings("layer").is_empty());
        assert!(
            health.disconnected_fraction.is_sign_positive(),
            "{health:?}"
        );
        // The same points, the same volumes, 10% lower: compaction at constant volume.
        let (sunk, states, grid) = layer(6, 0.9);
        let health = BodyHealth::measure(&sunk, &states, &grid, start);
        assert!(health.bulk_volume_ratio > 1.05, "{health:?}");
        assert!(
            (health.height_drift.unwrap() + 0.1).abs() < 0.01,
            "{health:?}"
        );
        let said = health.warnings("layer");
        assert_eq!(said.len(), 2, "{said:?}");
        assert!(
            said[0].contains("compacted") && said[1].contains("thickness changed by -9.2%"),
            "{said:?}"
        );
        // Not across the whole width, or not periodic: not a layer.
        assert_eq!(
            layer_bounds((DVec2::ZERO, DVec2::new(0.5, 0.6)), &grid),
            None
        );
        let walled = GridGeometry {
            periodic: [false, false],
            ..grid
        };
        assert_eq!(layer_bounds(bounds, &walled), None);
    }

    #[test]
    fn a_disconnected_bulk_is_measured() {
        let (points, mut states, grid) = layer(6, 1.0);
        // Every point of the bottom three rows of cells (interior: rows 0-4).
        for k in 0..points.len() {
            if points.position[k].y < 0.3 {
                states.phase[k] = Phase::Disconnected;
            }
        }
        let health = BodyHealth::measure(&points, &states, &grid, None);
        assert!(
            (health.disconnected_fraction - 0.5).abs() < 1e-12,
            "{health:?}"
        );
        assert!(
            (health.bulk_disconnected_fraction - 0.6).abs() < 1e-12,
            "{health:?}"
        );
        assert_eq!(health.height_drift, None);
        // Reported, not warned about: a wake separates physically.
        assert!(health.warnings("bed").is_empty());
    }
}
