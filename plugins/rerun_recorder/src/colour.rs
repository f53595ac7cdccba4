//! The per-point fields a recording can colour by, and their colour maps.
//!
//! Rerun draws the colours it is given, so the map is chosen here: continuous fields go
//! through a perceptually ordered ramp (dark blue to yellow, close to viridis), the plastic
//! strain rate and the inertial number on a logarithmic scale over fixed decades (as the
//! paper's Fig. 2), pressure and speed linearly from 0 to the frame's 99th percentile of
//! each body (so a stiff intruder's stress ringing does not set the bed's scale); phase and
//! body are categories. The exact value of the field is recorded beside the colour.

use regolith::body::{Body, PointStates, Points};
use serde::Deserialize;

/// What the points are coloured by.
#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq, Eq)]
pub enum Field {
    /// Mean stress `p = -tr(T)/3` (Pa).
    #[default]
    Pressure,
    /// Equivalent plastic shear strain rate (1/s), log scale 1e-3..1e3.
    PlasticStrainRate,
    /// Inertial number `I` (granular bodies; 0 elsewhere), log scale 1e-4..1.
    InertialNumber,
    /// 0 solid, 1 flowing, 2 disconnected.
    Phase,
    /// Point speed (m/s).
    Speed,
    /// The body's index in the scene.
    Body,
}

impl Field {
    pub const ALL: [Field; 6] = [
        Field::Pressure,
        Field::PlasticStrainRate,
        Field::InertialNumber,
        Field::Phase,
        Field::Speed,
        Field::Body,
    ];

    /// The field called `name` on the command line: its component name, with `-` or `_`
    /// between words (`plastic-strain-rate`).
    pub fn parse(name: &str) -> Option<Field> {
        let name = name.replace('-', "_");
        Field::ALL.into_iter().find(|f| f.name() == name)
    }

    /// The component name the values are recorded under.
    pub fn name(self) -> &'static str {
        match self {
            Field::Pressure => "pressure",
            Field::PlasticStrainRate => "plastic_strain_rate",
            Field::InertialNumber => "inertial_number",
            Field::Phase => "phase",
            Field::Speed => "speed",
            Field::Body => "body",
        }
    }

    /// The field's value at every point of a body, into `out`.
    pub fn values(self, body: &Body, p: &Points, st: &PointStates, out: &mut Vec<f64>) {
        out.clear();
        let n = p.len();
        match self {
            Field::Pressure => out.extend((0..n).map(|k| p.stress[k].pressure())),
            Field::PlasticStrainRate => out.extend_from_slice(&st.plastic_strain_rate),
            Field::InertialNumber => {
                out.extend((0..n).map(|k| {
                    body.inertial_number(st.plastic_strain_rate[k], p.stress[k].pressure())
                }))
            }
            Field::Phase => out.extend(st.phase.iter().map(|ph| f64::from(ph.code()))),
            Field::Speed => out.extend(p.velocity.iter().map(|v| v.length())),
            Field::Body => out.extend(std::iter::repeat_n(body.index as f64, n)),
        }
    }

    /// Colours for `values`; `largest` is the top of the scale of the linear fields (the
    /// frame's 99th percentile over the body's points).
    pub fn colours(self, values: &[f64], largest: f64, out: &mut Vec<[u8; 4]>) {
        out.clear();
        out.extend(values.iter().map(|&v| self.colour(v, largest)));
    }

    /// The colour of `v`; `largest` is the top of the linear fields' scale (the other
    /// fields ignore it).
    pub fn colour(self, v: f64, largest: f64) -> [u8; 4] {
        match self {
            Field::Pressure | Field::Speed => linear(v, largest),
            Field::PlasticStrainRate | Field::InertialNumber => {
                let (lo, hi) = self.log_range();
                ramp(log_fraction(v, lo, hi))
            }
            Field::Phase => PHASES[(v as usize).min(PHASES.len() - 1)],
            Field::Body => BODIES[(v as usize) % BODIES.len()],
        }
    }

    /// The fixed decades of the log-scaled fields (zero for the others).
    pub fn log_range(self) -> (f64, f64) {
        match self {
            Field::PlasticStrainRate => (1e-3, 1e3),
            Field::InertialNumber => (1e-4, 1.0),
            _ => (0.0, 0.0),
        }
    }

    /// The field's unit, as the legend shows it.
    pub fn unit(self) -> &'static str {
        match self {
            Field::Pressure => "Pa",
            Field::Speed => "m/s",
            Field::PlasticStrainRate => "1/s",
            Field::InertialNumber | Field::Phase | Field::Body => "-",
        }
    }

    /// Whether the colour scale depends on the frame (its 99th percentile).
    pub fn scaled_by_frame(self) -> bool {
        matches!(self, Field::Pressure | Field::Speed)
    }
}

/// Solid (blue-grey), flowing (orange), disconnected (pale red).
const PHASES: [[u8; 4]; 3] = [
    [90, 110, 150, 255],
    [240, 150, 40, 255],
    [250, 190, 190, 255],
];

/// Distinct body colours: sand, bronze, blue, green, purple, grey.
const BODIES: [[u8; 4]; 6] = [
    [214, 190, 140, 255],
    [150, 90, 40, 255],
    [60, 110, 200, 255],
    [70, 160, 90, 255],
    [140, 80, 170, 255],
    [120, 120, 120, 255],
];

/// The ramp's colour for `v` on a linear scale from 0 to `largest`.
pub fn linear(v: f64, largest: f64) -> [u8; 4] {
    ramp(if largest > 0.0 { v / largest } else { 0.0 })
}

/// The 99th percentile of the finite values (the top of a linear colour scale: the largest
/// value alone is often one point under the intruder, which would leave the rest dark).
pub fn upper_percentile(values: impl Iterator<Item = f64>, scratch: &mut Vec<f64>) -> f64 {
    scratch.clear();
    scratch.extend(values.filter(|v| v.is_finite()));
    if scratch.is_empty() {
        return 0.0;
    }
    let k = ((scratch.len() - 1) as f64 * 0.99).round() as usize;
    *scratch.select_nth_unstable_by(k, f64::total_cmp).1
}

/// Where `v` sits between `lo` and `hi` on a log scale, clamped to [0, 1].
fn log_fraction(v: f64, lo: f64, hi: f64) -> f64 {
    if v <= lo {
        return 0.0;
    }
    ((v.ln() - lo.ln()) / (hi.ln() - lo.ln())).clamp(0.0, 1.0)
}

/// A viridis-like ramp through five anchor colours, linear between them.
pub fn ramp(f: f64) -> [u8; 4] {
    const ANCHORS: [[f64; 3]; 5] = [
        [68.0, 1.0, 84.0],
        [59.0, 82.0, 139.0],
        [33.0, 145.0, 140.0],
        [94.0, 201.0, 98.0],
        [253.0, 231.0, 37.0],
    ];
    let f = if f.is_finite() {
        f.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let x = f * (ANCHORS.len() - 1) as f64;
    let i = (x.floor() as usize).min(ANCHORS.len() - 2);
    let t = x - i as f64;
    let c = |k: usize| (ANCHORS[i][k] + t * (ANCHORS[i + 1][k] - ANCHORS[i][k])).round() as u8;
    [c(0), c(1), c(2), 255]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ramp_runs_from_dark_to_bright_and_clamps() {
        assert_eq!(ramp(0.0), [68, 1, 84, 255]);
        assert_eq!(ramp(1.0), [253, 231, 37, 255]);
        assert_eq!(ramp(-3.0), ramp(0.0));
        assert_eq!(ramp(f64::NAN), ramp(0.0));
        let brightness = |c: [u8; 4]| c[0] as u32 + c[1] as u32 + c[2] as u32;
        let mut last = 0;
        for k in 0..=20 {
            let b = brightness(ramp(k as f64 / 20.0));
            assert!(b >= last, "the ramp darkens at {k}/20");
            last = b;
        }
    }

    #[test]
    fn the_scale_top_ignores_the_last_percent_and_non_finite_values() {
        let mut v: Vec<f64> = (0..1000).map(f64::from).collect();
        v.push(f64::NAN);
        v.push(1e12);
        let top = upper_percentile(v.into_iter(), &mut Vec::new());
        assert!((985.0..=995.0).contains(&top), "{top}");
        assert_eq!(upper_percentile(std::iter::empty(), &mut Vec::new()), 0.0);
    }

    #[test]
    fn log_scale_puts_decades_evenly() {
        assert_eq!(log_fraction(1e-3, 1e-3, 1e3), 0.0);
        assert!((log_fraction(1.0, 1e-3, 1e3) - 0.5).abs() < 1e-12);
        assert_eq!(log_fraction(1e9, 1e-3, 1e3), 1.0);
        assert_eq!(log_fraction(0.0, 1e-3, 1e3), 0.0);
    }
}
