//! The built-in shapes: rectangle, disc and simple polygon.

use glam::DVec2;
use serde::Deserialize;

use super::{Shape, finite, positive};
use crate::registry::Item;

/// `Rectangle(min: (x, y), max: (x, y))`: an axis-aligned rectangle.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Rectangle {
    pub min: DVec2,
    pub max: DVec2,
}

impl Item for Rectangle {
    const NAME: &'static str = "Rectangle";
    fn validate(&self) -> Result<(), String> {
        for (n, v) in [("min.x", self.min.x), ("min.y", self.min.y)] {
            finite(n, v)?;
        }
        let size = self.max - self.min;
        positive("width (max.x - min.x)", size.x)?;
        positive("height (max.y - min.y)", size.y)
    }
}

impl Shape for Rectangle {
    fn contains(&self, p: DVec2) -> bool {
        p.x >= self.min.x && p.x < self.max.x && p.y >= self.min.y && p.y < self.max.y
    }
    fn bounds(&self) -> (DVec2, DVec2) {
        (self.min, self.max)
    }
    fn area(&self) -> Option<f64> {
        let s = self.max - self.min;
        Some(s.x * s.y)
    }
    fn outward_normal(&self, p: DVec2, _reach: f64) -> DVec2 {
        let (a, b) = (self.min, self.max);
        let corners = [a, DVec2::new(b.x, a.y), b, DVec2::new(a.x, b.y)];
        edge_normal((0..4).map(|i| (corners[i], corners[(i + 1) % 4])), p, |q| {
            self.contains(q)
        })
    }
}

/// The outward normal of a polygonal boundary (given by its edges) nearest to `p`: the unit
/// vector from `p` to its nearest boundary point when `p` is inside, from that point to `p`
/// when outside. Where several edges are nearest within round-off (a node on a corner's
/// bisector), the directions to each are averaged, which gives the bisector; a point on an
/// edge itself takes the edge's normal turned to the side `contains` says is outside.
pub fn edge_normal(
    edges: impl Iterator<Item = (DVec2, DVec2)> + Clone,
    p: DVec2,
    contains: impl Fn(DVec2) -> bool,
) -> DVec2 {
    let nearest = |a: DVec2, b: DVec2| {
        let ab = b - a;
        let t = ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0);
        a + t * ab
    };
    let scale = edges
        .clone()
        .map(|(a, b)| a.distance(b))
        .fold(0.0, f64::max);
    let d_min = edges
        .clone()
        .map(|(a, b)| nearest(a, b).distance(p))
        .fold(f64::INFINITY, f64::min);
    let tie = d_min + 1e-9 * scale;
    let sign = if contains(p) { -1.0 } else { 1.0 };
    let mut sum = DVec2::ZERO;
    for (a, b) in edges {
        let q = nearest(a, b);
        if q.distance(p) > tie {
            continue;
        }
        let away = p - q;
        sum += if away.length() > 1e-9 * scale {
            sign * away.normalize()
        } else {
            let n = (b - a).perp().normalize();
            if contains(p + 1e-6 * scale * n) {
                -n
            } else {
                n
            }
        };
    }
    sum.normalize_or_zero()
}

/// `Disc(centre: (x, y), radius: r)`.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Disc {
    pub centre: DVec2,
    pub radius: f64,
}

impl Item for Disc {
    const NAME: &'static str = "Disc";
    fn validate(&self) -> Result<(), String> {
        finite("centre.x", self.centre.x)?;
        finite("centre.y", self.centre.y)?;
        positive("radius", self.radius)
    }
}

impl Shape for Disc {
    fn contains(&self, p: DVec2) -> bool {
        (p - self.centre).length_squared() < self.radius * self.radius
    }
    fn bounds(&self) -> (DVec2, DVec2) {
        (
            self.centre - DVec2::splat(self.radius),
            self.centre + DVec2::splat(self.radius),
        )
    }
    fn area(&self) -> Option<f64> {
        Some(std::f64::consts::PI * self.radius * self.radius)
    }
    fn outward_normal(&self, p: DVec2, _reach: f64) -> DVec2 {
        (p - self.centre).normalize_or_zero()
    }
}

/// `Polygon(vertices: [(x, y), ...])`: a simple (non self-intersecting) polygon, either winding.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Polygon {
    pub vertices: Vec<DVec2>,
}

impl Polygon {
    fn edges(&self) -> impl Iterator<Item = (DVec2, DVec2)> + Clone + '_ {
        let n = self.vertices.len();
        (0..n).map(move |i| (self.vertices[i], self.vertices[(i + 1) % n]))
    }

    /// Signed area (positive when anticlockwise).
    pub fn signed_area(&self) -> f64 {
        0.5 * self.edges().map(|(a, b)| a.perp_dot(b)).sum::<f64>()
    }
}

fn segments_cross(a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> bool {
    let o1 = (b - a).perp_dot(c - a);
    let o2 = (b - a).perp_dot(d - a);
    let o3 = (d - c).perp_dot(a - c);
    let o4 = (d - c).perp_dot(b - c);
    o1 * o2 < 0.0 && o3 * o4 < 0.0
}

impl Item for Polygon {
    const NAME: &'static str = "Polygon";
    fn validate(&self) -> Result<(), String> {
        if self.vertices.len() < 3 {
            return Err(format!(
                "a polygon needs at least 3 vertices, got {}",
                self.vertices.len()
            ));
        }
        for (i, v) in self.vertices.iter().enumerate() {
            finite(&format!("vertices[{i}].x"), v.x)?;
            finite(&format!("vertices[{i}].y"), v.y)?;
        }
        if self.signed_area().abs() <= 0.0 {
            return Err("the polygon has zero area".into());
        }
        let e: Vec<_> = self.edges().collect();
        for i in 0..e.len() {
            for j in i + 2..e.len() {
                if i == 0 && j == e.len() - 1 {
                    continue;
                }
                if segments_cross(e[i].0, e[i].1, e[j].0, e[j].1) {
                    return Err(format!("the polygon's edges {i} and {j} cross each other"));
                }
            }
        }
        Ok(())
    }
}

impl Shape for Polygon {
    fn contains(&self, p: DVec2) -> bool {
        // Even-odd rule with a horizontal ray.
        let mut inside = false;
        for (a, b) in self.edges() {
            if (a.y > p.y) != (b.y > p.y) {
                let x = a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x);
                if p.x < x {
                    inside = !inside;
                }
            }
        }
        inside
    }
    fn bounds(&self) -> (DVec2, DVec2) {
        let min = self.vertices.iter().fold(DVec2::INFINITY, |m, v| m.min(*v));
        let max = self
            .vertices
            .iter()
            .fold(DVec2::NEG_INFINITY, |m, v| m.max(*v));
        (min, max)
    }
    fn area(&self) -> Option<f64> {
        Some(self.signed_area().abs())
    }
    fn outward_normal(&self, p: DVec2, _reach: f64) -> DVec2 {
        edge_normal(self.edges(), p, |q| self.contains(q))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn polygon_contains_matches_a_rectangle() {
        let poly = Polygon {
            vertices: vec![
                DVec2::new(0.0, 0.0),
                DVec2::new(2.0, 0.0),
                DVec2::new(2.0, 1.0),
                DVec2::new(0.0, 1.0),
            ],
        };
        let rect = Rectangle {
            min: DVec2::ZERO,
            max: DVec2::new(2.0, 1.0),
        };
        assert!((poly.signed_area() - 2.0).abs() < 1e-12);
        for i in 0..50 {
            for j in 0..30 {
                let p = DVec2::new(-0.5 + i as f64 * 0.061, -0.5 + j as f64 * 0.067);
                assert_eq!(poly.contains(p), rect.contains(p), "at {p}");
            }
        }
    }

    #[test]
    fn bow_tie_is_rejected() {
        let poly = Polygon {
            vertices: vec![
                DVec2::new(0.0, 0.0),
                DVec2::new(2.0, 2.0),
                DVec2::new(2.0, 0.0),
                DVec2::new(0.0, 1.0),
            ],
        };
        assert!(Item::validate(&poly).unwrap_err().contains("cross"));
    }
}
