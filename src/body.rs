//! A body is an entity; its material points are one struct-of-arrays component on it.
//!
//! One entity per point would cost random access and make sorting by cell impossible
//! (ARCHITECTURE.md), so the columns live together here and the hot loops see plain slices.

use bevy_ecs::prelude::*;
use glam::{DMat2, DVec2};
use serde::{Deserialize, Serialize};

use crate::stress::Stress;

/// The material points of one body (docs/model.md §1).
#[derive(Component, Clone, Debug, Default, Serialize, Deserialize)]
pub struct Points {
    pub position: Vec<DVec2>,
    pub velocity: Vec<DVec2>,
    /// Mass per unit thickness (kg/m), constant.
    pub mass: Vec<f64>,
    /// Physical volume per unit thickness (m^2), updated from `tr L` each step.
    pub volume: Vec<f64>,
    /// Fixed integration half-width (m): half the initial point spacing, never updated.
    pub half_width: Vec<f64>,
    pub stress: Vec<Stress>,
    /// Velocity gradient of the last step, `L_ab = d v_a / d x_b`.
    pub velocity_gradient: Vec<DMat2>,
    /// Grid velocity interpolated at the point in the last step (its advection velocity);
    /// MUSL carries it from the velocity pass to the position update.
    pub advection: Vec<DVec2>,
    /// The affine part of the point's velocity field, `C_p` (1/s), carried from step to
    /// step by the APIC transfer (`transfer: Apic`); empty with FLIP.
    pub affine: Vec<DMat2>,
    /// The density the constitutive update sees (kg/m^3): `m/V`, or with cell-averaged
    /// dilatation the mean density of the points in the point's cell.
    pub density: Vec<f64>,
}

impl Points {
    pub fn len(&self) -> usize {
        self.position.len()
    }

    pub fn is_empty(&self) -> bool {
        self.position.is_empty()
    }

    /// Bytes held per point (for memory estimates), not counting material history or the
    /// APIC affine matrix ([`Points::AFFINE_BYTES`]).
    pub const BYTES_PER_POINT: usize = 16 + 16 + 8 + 8 + 8 + 32 + 32 + 16 + 8;
    /// Bytes of the affine matrix an APIC point carries besides.
    pub const AFFINE_BYTES: usize = 32;

    /// A 64-bit fingerprint of the state that carries into the next step (positions,
    /// velocities, masses, volumes and stresses, bit for bit): equal fingerprints mean the
    /// same state to the last bit, so runs on two thread counts, builds or machines can be
    /// compared. FNV-1a over the values' bits, written out so that it never changes with
    /// the standard library's hasher.
    pub fn fingerprint(&self) -> u64 {
        const PRIME: u64 = 0x0000_0100_0000_01b3;
        let mut h: u64 = 0xcbf2_9ce4_8422_2325;
        let mut eat = |v: f64| {
            for byte in v.to_bits().to_le_bytes() {
                h = (h ^ u64::from(byte)).wrapping_mul(PRIME);
            }
        };
        for k in 0..self.len() {
            let (x, v, t) = (self.position[k], self.velocity[k], self.stress[k]);
            for value in [x.x, x.y, v.x, v.y, self.mass[k], self.volume[k]] {
                eat(value);
            }
            for value in [t.xx, t.yy, t.xy, t.zz] {
                eat(value);
            }
            if let Some(c) = self.affine.get(k) {
                for value in c.to_cols_array() {
                    eat(value);
                }
            }
        }
        h
    }
}

/// The inertial number below which a granular point on the yield surface is labelled at rest
/// ([`Phase::Solid`]) rather than [`Phase::Flowing`]: the lower end of the dense-flow regime,
/// `I ~ 1e-3` (GDR MiDi 2004, Eur. Phys. J. E 14, 341; Jop, Forterre & Pouliquen 2006,
/// Nature 441, 727), below which a granular material creeps quasi-statically and `mu(I)`
/// differs from `mu_s` by under `(mu_2 - mu_s) I / I_0`, 0.1% of PS-1's friction. A pile at
/// its angle of repose sits on the yield surface, and elastic jitter there gives its points
/// small plastic increments step after step; they are labelled at rest, not flowing
/// (docs/GRANULAR.md, "Phases at rest"). A label only: the stress update is the same.
pub const QUASI_STATIC_INERTIAL_NUMBER: f64 = 1e-3;

/// `I = gdp d sqrt(rho_s / p)` from the material's `scale = d sqrt(rho_s)`, the plastic rate
/// `gdp` (1/s) and the pressure `p` (Pa); 0 when `p <= 0` (no contact pressure, no `I`).
pub fn inertial_number(scale: f64, gdp: f64, p: f64) -> f64 {
    if p > 0.0 { gdp * scale / p.sqrt() } else { 0.0 }
}

/// The state of the material at a point, as the constitutive update classifies it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Phase {
    /// Dense and at rest: below the yield surface (elastic), or, for a granular material, on
    /// it at an inertial number below [`QUASI_STATIC_INERTIAL_NUMBER`] (creeping).
    #[default]
    Solid,
    /// Dense and flowing plastically: on the yield surface, for a granular material at an
    /// inertial number of at least [`QUASI_STATIC_INERTIAL_NUMBER`]; for a material without
    /// grains (`DruckerPrager`, `Bingham`, no grain scale) at any plastic rate.
    Flowing,
    /// Below the critical density or in tension: stress free (granular "gas").
    Disconnected,
}

impl Phase {
    /// 0 solid, 1 flowing, 2 disconnected (for CSV and colour maps).
    pub fn code(self) -> u8 {
        match self {
            Phase::Solid => 0,
            Phase::Flowing => 1,
            Phase::Disconnected => 2,
        }
    }

    /// The label of a point the update classified as `self`, given its inertial number
    /// (`None` for a material without a grain scale): a `Flowing` point below
    /// [`QUASI_STATIC_INERTIAL_NUMBER`] is at rest (`Solid`); other labels are kept.
    pub fn at_inertial_number(self, inertial_number: Option<f64>) -> Phase {
        match (self, inertial_number) {
            (Phase::Flowing, Some(i)) if i < QUASI_STATIC_INERTIAL_NUMBER => Phase::Solid,
            (phase, _) => phase,
        }
    }
}

/// Public per-point results of the constitutive update, for diagnostics and outputs.
#[derive(Component, Clone, Debug, Default, Serialize, Deserialize)]
pub struct PointStates {
    /// Equivalent plastic shear strain rate of the last step (1/s).
    pub plastic_strain_rate: Vec<f64>,
    /// Accumulated equivalent plastic shear strain.
    pub plastic_strain: Vec<f64>,
    pub phase: Vec<Phase>,
}

impl PointStates {
    /// Bytes held per point (for memory estimates).
    pub const BYTES_PER_POINT: usize = 8 + 8 + std::mem::size_of::<Phase>();

    pub fn new(points: usize) -> Self {
        PointStates {
            plastic_strain_rate: vec![0.0; points],
            plastic_strain: vec![0.0; points],
            phase: vec![Phase::Solid; points],
        }
    }
}

/// What a body is: its name and the facts the step needs about it.
#[derive(Component, Clone, Debug)]
pub struct Body {
    pub name: String,
    /// Position in the scene's body list.
    pub index: usize,
    /// Written to `trajectory.csv`.
    pub tracked: bool,
    /// Name of the body's material.
    pub material: &'static str,
    /// Elastic p-wave speed used by the CFL condition (m/s).
    pub wave_speed: f64,
    /// `d sqrt(rho_s)` of a granular material, so that the inertial number is
    /// `I = gdp d sqrt(rho_s / p)`; `None` for materials without grains.
    pub inertial_scale: Option<f64>,
    /// Whether the material is granular, so that the delta-correction (the scene's
    /// `spacing`) may move the body's points (`step::spacing`).
    pub granular: bool,
}

impl Body {
    /// Inertial number of a point with plastic rate `gdp` at pressure `p` (0 when `p <= 0`
    /// or the material has no grain scale).
    pub fn inertial_number(&self, gdp: f64, p: f64) -> f64 {
        self.inertial_scale
            .map_or(0.0, |s| inertial_number(s, gdp, p))
    }
}

/// Whole-body quantities, refreshed in the Diagnostics set.
#[derive(Component, Clone, Copy, Debug, Default, Serialize)]
pub struct BodyState {
    pub mass: f64,
    pub centre_of_mass: DVec2,
    pub velocity: DVec2,
    pub kinetic_energy: f64,
    /// Largest point speed.
    pub max_speed: f64,
    /// Points retired through an `Open` side (no mass left).
    pub retired: usize,
}

/// Points per chunk of the whole-body sums. Sums run chunk by chunk and the chunks are
/// combined in order, so the parallel survey of the Diagnostics set and a serial
/// `BodyState::measure` give bitwise the same state whatever the thread count.
pub const SURVEY_CHUNK: usize = 4096;

/// Sums over one chunk of a body's points, and what the health check screens them for.
#[derive(Clone, Copy, Debug)]
pub struct ChunkSurvey {
    mass: f64,
    moment: DVec2,
    momentum: DVec2,
    kinetic_energy: f64,
    max_speed: f64,
    retired: usize,
    /// Zero unless some position, velocity, stress or volume is NaN or infinite (or the
    /// values are so large that their sum overflows).
    pub non_finite: f64,
    pub min_volume: f64,
    /// Corners of the box around the chunk's points.
    pub lowest: DVec2,
    pub highest: DVec2,
}

impl Default for ChunkSurvey {
    fn default() -> Self {
        ChunkSurvey {
            mass: 0.0,
            moment: DVec2::ZERO,
            momentum: DVec2::ZERO,
            kinetic_energy: 0.0,
            max_speed: 0.0,
            retired: 0,
            non_finite: 0.0,
            min_volume: f64::INFINITY,
            lowest: DVec2::INFINITY,
            highest: DVec2::NEG_INFINITY,
        }
    }
}

impl ChunkSurvey {
    /// How many chunks `points` points make.
    pub fn count(points: usize) -> usize {
        points.div_ceil(SURVEY_CHUNK)
    }

    /// The point indices of chunk `c` of `points` points.
    pub fn range(c: usize, points: usize) -> std::ops::Range<usize> {
        c * SURVEY_CHUNK..((c + 1) * SURVEY_CHUNK).min(points)
    }

    /// The survey of chunk `c` of the body's points.
    pub fn over(points: &Points, c: usize) -> ChunkSurvey {
        let mut s = ChunkSurvey::default();
        for k in ChunkSurvey::range(c, points.len()) {
            let (x, v, t) = (points.position[k], points.velocity[k], points.stress[k]);
            let vol = points.volume[k];
            s.non_finite += (x.x + x.y + v.x + v.y + t.xx + t.yy + t.xy + t.zz + vol) * 0.0;
            s.min_volume = s.min_volume.min(vol);
            s.lowest = s.lowest.min(x);
            s.highest = s.highest.max(x);
            let m = points.mass[k];
            if m == 0.0 {
                s.retired += 1;
                continue;
            }
            s.mass += m;
            s.moment += m * x;
            s.momentum += m * v;
            s.kinetic_energy += 0.5 * m * v.length_squared();
            s.max_speed = s.max_speed.max(v.length());
        }
        s
    }
}

impl BodyState {
    /// Mass-weighted sums over the body's points (chunk by chunk, see `SURVEY_CHUNK`).
    pub fn measure(points: &Points) -> BodyState {
        BodyState::from_chunks(
            (0..ChunkSurvey::count(points.len())).map(|c| ChunkSurvey::over(points, c)),
        )
    }

    /// Combines chunk surveys, in order.
    pub fn from_chunks(chunks: impl IntoIterator<Item = ChunkSurvey>) -> BodyState {
        let mut s = BodyState::default();
        let mut moment = DVec2::ZERO;
        let mut momentum = DVec2::ZERO;
        for c in chunks {
            s.mass += c.mass;
            moment += c.moment;
            momentum += c.momentum;
            s.kinetic_energy += c.kinetic_energy;
            s.max_speed = s.max_speed.max(c.max_speed);
            s.retired += c.retired;
        }
        if s.mass > 0.0 {
            s.centre_of_mass = moment / s.mass;
            s.velocity = momentum / s.mass;
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use glam::DVec2;

    use super::Points;
    use crate::stress::Stress;

    fn two_points() -> Points {
        let stress = Stress {
            xx: -1.0e3,
            yy: -2.0e3,
            xy: 5.0,
            zz: -1.5e3,
        };
        Points {
            position: vec![DVec2::new(0.1, 0.2), DVec2::new(0.3, 0.2)],
            velocity: vec![DVec2::new(0.0, -1.0); 2],
            mass: vec![0.5; 2],
            volume: vec![1e-4; 2],
            half_width: vec![0.005; 2],
            stress: vec![stress; 2],
            ..Points::default()
        }
    }

    #[test]
    fn the_fingerprint_sees_one_bit_and_the_order() {
        let a = two_points();
        assert_eq!(a.fingerprint(), two_points().fingerprint());
        let mut b = two_points();
        b.stress[1].xy = f64::from_bits(b.stress[1].xy.to_bits() + 1);
        assert_ne!(a.fingerprint(), b.fingerprint(), "one ulp of one stress");
        let mut c = two_points();
        c.position.swap(0, 1);
        assert_ne!(a.fingerprint(), c.fingerprint(), "two points swapped");
        // What does not carry into the next step is not part of it.
        let mut d = two_points();
        d.density = vec![1.0; 2];
        assert_eq!(a.fingerprint(), d.fingerprint());
    }
}
