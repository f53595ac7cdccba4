//! The paper's tipped intruder (section 4.2; docs/model.md §7.1): a plate of width `w` with a
//! flat top and a nose `y = s |x|` below, every corner rounded with radius `r`, its tail
//! lengthened so that the rounded shape keeps the area the paper's mass implies.
//!
//! A convex polygon with rounded corners is the set of points within `r` of the polygon
//! shrunk inwards by `r`; its area is, by Steiner's formula, `A_in + P_in r + pi r^2` with
//! `A_in` and `P_in` the area and perimeter of the shrunk polygon. The tail height is solved
//! so that this equals the requested area ("mass lost to rounding added to the tail"). The
//! shape is placed by its lowest point, the tip, which the paper puts at the free surface.
//!
//! The 2D area comes from the paper's numbers: mass 0.219 kg, bronze 8910 kg/m^3 of
//! thickness 2.2 mm in a bed 3 mm thick, i.e. an areal density 6500 kg/m^3 over 3 mm:
//! `A = 0.219 / (6500 * 0.003) = 0.011231 m^2` (73.0 kg per metre of thickness). The body's
//! material then uses `density: 6500.0`.

use glam::DVec2;
use serde::Deserialize;

use super::{Shape, finite, positive};
use crate::registry::Item;

/// `TippedIntruder(tip: (x, y), width: 0.0965, slope: 1.0, corner_radius: 0.01, area: 0.011231)`.
#[derive(Clone, Debug, Deserialize)]
#[serde(try_from = "TippedParams")]
pub struct TippedIntruder {
    params: TippedParams,
    /// The shrunk (inner) polygon, anticlockwise, in scene coordinates.
    inner: Vec<DVec2>,
    /// Height of the straight tail (sides) of the unrounded plate.
    pub tail: f64,
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct TippedParams {
    tip: DVec2,
    width: f64,
    slope: f64,
    corner_radius: f64,
    area: f64,
}

/// The unrounded plate with its tip at the origin: nose corners at `(+-w/2, s w/2)`, top at
/// `s w/2 + tail`; anticlockwise.
fn plate(width: f64, slope: f64, tail: f64) -> Vec<DVec2> {
    let (hw, nose) = (0.5 * width, 0.5 * slope * width);
    let mut v = vec![
        DVec2::ZERO,
        DVec2::new(hw, nose),
        DVec2::new(hw, nose + tail),
    ];
    v.push(DVec2::new(-hw, nose + tail));
    v.push(DVec2::new(-hw, nose));
    if slope == 0.0 {
        // A flat bottom: the tip vertex lies on the bottom edge, drop it.
        v.remove(0);
    }
    v
}

/// The convex polygon `poly` (anticlockwise) shrunk inwards by `r`: each edge moved inwards
/// along its normal, consecutive edges intersected.
fn shrink(poly: &[DVec2], r: f64) -> Vec<DVec2> {
    let n = poly.len();
    let lines: Vec<(DVec2, DVec2)> = (0..n)
        .map(|i| {
            let (a, b) = (poly[i], poly[(i + 1) % n]);
            let d = (b - a).normalize();
            let inward = DVec2::new(-d.y, d.x);
            (a + r * inward, d)
        })
        .collect();
    (0..n)
        .map(|i| {
            let (p1, d1) = lines[(i + n - 1) % n];
            let (p2, d2) = lines[i];
            // p1 + t d1 = p2 + u d2
            let t = (p2 - p1).perp_dot(d2) / d1.perp_dot(d2);
            p1 + t * d1
        })
        .collect()
}

fn area_perimeter(poly: &[DVec2]) -> (f64, f64) {
    let n = poly.len();
    let mut area = 0.0;
    let mut perimeter = 0.0;
    for i in 0..n {
        let (a, b) = (poly[i], poly[(i + 1) % n]);
        area += 0.5 * a.perp_dot(b);
        perimeter += (b - a).length();
    }
    (area, perimeter)
}

/// Area of the plate with tail `tail` after rounding every corner with radius `r`.
fn rounded_area(width: f64, slope: f64, tail: f64, r: f64) -> f64 {
    let (a, p) = area_perimeter(&shrink(&plate(width, slope, tail), r));
    a + p * r + std::f64::consts::PI * r * r
}

impl TryFrom<TippedParams> for TippedIntruder {
    type Error = String;
    fn try_from(p: TippedParams) -> Result<Self, String> {
        finite("tip.x", p.tip.x)?;
        finite("tip.y", p.tip.y)?;
        positive("width", p.width)?;
        positive("area", p.area)?;
        if !(p.slope.is_finite() && p.slope >= 0.0) {
            return Err(format!(
                "slope must be a non-negative number, got {}",
                p.slope
            ));
        }
        if !(p.corner_radius.is_finite()
            && p.corner_radius > 0.0
            && p.corner_radius < 0.25 * p.width)
        {
            return Err(format!(
                "corner_radius must lie in (0, width/4 = {}), got {}",
                0.25 * p.width,
                p.corner_radius
            ));
        }
        // The rounded area grows linearly with the tail (the sides lengthen): bisect.
        let r = p.corner_radius;
        let too_short = |tail: f64| rounded_area(p.width, p.slope, tail, r) < p.area;
        let (mut lo, mut hi) = (2.0 * r, 2.0 * r);
        if !too_short(lo) {
            return Err(format!(
                "area {} m^2 is too small for a width of {} m with slope {} and corner radius {}",
                p.area, p.width, p.slope, r
            ));
        }
        while too_short(hi) {
            hi *= 2.0;
            if hi > 1e3 {
                return Err("area too large for the width".into());
            }
        }
        for _ in 0..100 {
            let mid = 0.5 * (lo + hi);
            if too_short(mid) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let tail = 0.5 * (lo + hi);
        let inner_at_origin = shrink(&plate(p.width, p.slope, tail), r);
        // The lowest point of the rounded shape is r below the lowest inner vertex.
        let bottom = inner_at_origin
            .iter()
            .map(|v| v.y)
            .fold(f64::INFINITY, f64::min)
            - r;
        let shift = p.tip - DVec2::new(0.0, bottom);
        let inner = inner_at_origin.iter().map(|v| *v + shift).collect();
        Ok(TippedIntruder {
            params: p,
            inner,
            tail,
        })
    }
}

impl TippedIntruder {
    /// The area of the rounded shape (equals the requested area).
    pub fn area(&self) -> f64 {
        let (a, p) = area_perimeter(&self.inner);
        let r = self.params.corner_radius;
        a + p * r + std::f64::consts::PI * r * r
    }
}

/// Distance from `p` to the segment `a`-`b`.
fn segment_distance(p: DVec2, a: DVec2, b: DVec2) -> f64 {
    let ab = b - a;
    let t = ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0);
    (p - (a + t * ab)).length()
}

impl Item for TippedIntruder {
    const NAME: &'static str = "TippedIntruder";
    fn validate(&self) -> Result<(), String> {
        Ok(())
    }
}

impl Shape for TippedIntruder {
    fn contains(&self, p: DVec2) -> bool {
        let n = self.inner.len();
        let inside = (0..n)
            .all(|i| (self.inner[(i + 1) % n] - self.inner[i]).perp_dot(p - self.inner[i]) >= 0.0);
        inside
            || (0..n).any(|i| {
                segment_distance(p, self.inner[i], self.inner[(i + 1) % n])
                    < self.params.corner_radius
            })
    }

    fn area(&self) -> Option<f64> {
        Some(TippedIntruder::area(self))
    }

    fn bounds(&self) -> (DVec2, DVec2) {
        let r = DVec2::splat(self.params.corner_radius);
        let min = self.inner.iter().fold(DVec2::INFINITY, |m, v| m.min(*v));
        let max = self
            .inner
            .iter()
            .fold(DVec2::NEG_INFINITY, |m, v| m.max(*v));
        (min - r, max + r)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn intruder(slope: f64) -> TippedIntruder {
        TippedIntruder::try_from(TippedParams {
            tip: DVec2::new(0.455, 0.6825),
            width: 0.0965,
            slope,
            corner_radius: 0.01,
            area: 0.011231,
        })
        .unwrap()
    }

    #[test]
    fn every_slope_keeps_the_paper_area_and_sits_on_its_tip() {
        for s in [0.0, 0.5, 1.0, 1.5, 2.0, 2.5, 3.0] {
            let t = intruder(s);
            assert!(
                (t.area() / 0.011231 - 1.0).abs() < 1e-9,
                "s = {s}: area {}",
                t.area()
            );
            let (lo, hi) = Shape::bounds(&t);
            assert!((lo.y - 0.6825).abs() < 1e-12, "s = {s}: tip at {}", lo.y);
            assert!(
                (hi.x - lo.x - 0.0965).abs() < 1e-12,
                "s = {s}: width {}",
                hi.x - lo.x
            );
            // A Monte Carlo-free check of the area: a fine lattice count.
            let h = 2e-4;
            let mut count = 0usize;
            let (mut y, x0) = (lo.y + 0.5 * h, lo.x + 0.5 * h);
            while y < hi.y {
                let mut x = x0;
                while x < hi.x {
                    if Shape::contains(&t, DVec2::new(x, y)) {
                        count += 1;
                    }
                    x += h;
                }
                y += h;
            }
            let counted = count as f64 * h * h;
            assert!(
                (counted / 0.011231 - 1.0).abs() < 5e-3,
                "s = {s}: lattice area {counted}"
            );
        }
    }

    #[test]
    fn sharper_tips_have_shorter_tails() {
        assert!(intruder(3.0).tail < intruder(1.0).tail && intruder(1.0).tail < intruder(0.0).tail);
    }
}
