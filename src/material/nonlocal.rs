//! Nonlocal granular fluidity (NGF): the trans-phase model of `granular` with its mu(I) flow
//! rule replaced by the dynamic fluidity equation of Henann & Kamrin (2014) and Kamrin & Henann
//! (2015), written with the paper's saturating mu(I) as Dunatunga & Kamrin (2022) do
//! (docs/model.md §4.2). It adds a length to the model, `xi ~ A d`, so that thin layers stop
//! (`H_stop`), flow profiles depend on the layer's thickness, and short modes are damped.
//!
//! The fluidity `g` obeys
//! `t0 dg/dt = A^2 d^2 lap(g) + (mu_2 - mu_s)(mu - mu_s)/(mu_2 - mu) g - b sqrt(rho_s d^2/p) mu g^2`
//! with `b = (mu_2 - mu_s)/I_0`, and sets the plastic shear rate, `gamma_dot_p = g mu`. At a
//! known `g` the backward-Euler return is `tau = tau_tr p/(p + G dt g)`.
//!
//! How a step advances it, per body of this material:
//! 1. `fluidity_field` (a grid field, `crate::grid_field`, in `ParticleToGrid`): each dense
//!    point's `g` is scattered with its volume as weight, the nodal Laplacian is taken with the
//!    walls' conditions (`g = 0` on no-slip walls, zero flux elsewhere, settable per wall), and
//!    gathered back to the points. Disconnected points carry no fluidity and are left out.
//! 2. The update (per point): the elastic trial, then `g` from the equation above with the
//!    Laplacian explicit and everything else implicit, `mu` being the returned ratio
//!    `tau_tr/(p + G dt g)` of the unknown `g`: one scalar root, found by a safeguarded
//!    Newton iteration in a bracket (`Nonlocal::advance`). The diffusion number
//!    `A^2 d^2 dt/(t0 h^2)` must stay below 1/4 for the explicit Laplacian; the scene check
//!    refuses a scene whose largest step would break it.
//!
//! `g = 0` solves the equation, so a body at rest stays at rest unless something starts it: a
//! point whose trial stress ratio rises above `mu_s` with zero fluidity is seeded with
//! `fluidity_seed sqrt(p/rho_s)/d`, once until it falls back below `mu_s` or disconnects. A
//! reconnecting point starts from zero fluidity and is seeded the same way. Where the stress
//! exceeds `mu_2` no seed is needed: no `g` short of the one bringing `mu` below `mu_2` solves
//! the equation. A fluidity too small to change the stress in floating point
//! (`G dt g < eps p`) is set to zero, so a layer below `H_stop` comes exactly to rest.

use serde::{Deserialize, Serialize};

use bevy_ecs::prelude::*;

use super::granular::{TransPhase, check_positive, trans_phase_params};
use super::{Material, MaterialState, PointOutcome, PointStep};
use crate::body::{Phase, PointStates, Points};
use crate::grid::GridGeometry;
use crate::grid_field::{self, FieldWalls, GridFields, NodeCondition, PointFields};
use crate::registry::Item;
use crate::resources::{Boundaries, Wall, Walls};
use crate::step::{Bands, Core, Location, StepSet};
use crate::stress::Stress;

/// The nonlocal amplitude `A` unless the scene gives one: Henann & Kamrin's (2013) calibration
/// for glass beads, the value Kamrin & Henann (2015) use for flows down inclines.
pub const DEFAULT_AMPLITUDE: f64 = 0.48;
/// The fluidity's time scale `t0` (s) unless the scene gives one: the default of Haeri &
/// Skonieczny's (2022) MPM-NGF code. Steady flows and `H_stop` do not depend on it; it sets
/// how fast the fluidity relaxes to them.
pub const DEFAULT_TIME_SCALE: f64 = 1e-3;
/// The seed, in units of `sqrt(p/rho_s)/d`, unless the scene gives one.
pub const DEFAULT_SEED: f64 = 1e-2;

/// The fluidity solve stops when a step changes `g` by less than this, relatively.
const TOLERANCE: f64 = 1e-13;
/// And gives up after this many steps (bisection alone would halve the bracket this often).
const MAX_ITERATIONS: usize = 200;

/// The grid field's column: the Laplacian of the fluidity at each point.
const LAPLACIAN: &[&str] = &["fluidity_laplacian"];

/// What a wall imposes on the fluidity.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
pub enum FluidityWall {
    /// `g = 0` on the wall: a rough wall that grains do not slide along (the default on
    /// `NoSlip` walls; it is what gives a stopping height).
    Zero,
    /// No flux of fluidity through the wall (the default on every other wall).
    ZeroFlux,
}

/// Per-side choices; a side left out takes its wall's default.
#[derive(Clone, Copy, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FluidityWalls {
    pub left: Option<FluidityWall>,
    pub right: Option<FluidityWall>,
    pub bottom: Option<FluidityWall>,
    pub top: Option<FluidityWall>,
}

impl FluidityWalls {
    /// The conditions on the grid field, given the scene's walls.
    pub fn resolve(&self, walls: &Walls) -> FieldWalls {
        let side = |choice: Option<FluidityWall>, wall: Wall| {
            let choice = choice.unwrap_or(if wall == Wall::NoSlip {
                FluidityWall::Zero
            } else {
                FluidityWall::ZeroFlux
            });
            match choice {
                FluidityWall::Zero => NodeCondition::Fixed(0.0),
                FluidityWall::ZeroFlux => NodeCondition::ZeroFlux,
            }
        };
        FieldWalls {
            left: side(self.left, walls.left),
            right: side(self.right, walls.right),
            bottom: side(self.bottom, walls.bottom),
            top: side(self.top, walls.top),
        }
    }
}

/// `Nonlocal(...)`: the trans-phase model with nonlocal granular fluidity.
#[derive(Clone, Debug, Deserialize)]
#[serde(try_from = "NonlocalParams")]
pub struct Nonlocal {
    /// Elasticity, densities, grain size and the mu(I) parameters, as `MuI`'s.
    pub base: TransPhase,
    /// The nonlocal amplitude `A`.
    pub amplitude: f64,
    /// The time scale `t0` (s).
    pub time_scale: f64,
    /// The seed, in units of `sqrt(p/rho_s)/d`.
    pub seed: f64,
    pub walls: FluidityWalls,
}

trans_phase_params!(NonlocalParams {
    nonlocal_amplitude: Option<f64>,
    fluidity_time_scale: Option<f64>,
    fluidity_seed: Option<f64>,
    #[serde(default)]
    fluidity_walls: FluidityWalls,
});

impl TryFrom<NonlocalParams> for Nonlocal {
    type Error = String;
    fn try_from(p: NonlocalParams) -> Result<Self, String> {
        let base = p.trans_phase()?;
        if base.mu_2 == base.mu_s {
            return Err(format!(
                "mu_2 must be larger than mu_s = {} (the fluidity's rate law divides by \
                 mu_2 - mu_s)",
                base.mu_s
            ));
        }
        let amplitude = p.nonlocal_amplitude.unwrap_or(DEFAULT_AMPLITUDE);
        check_positive("nonlocal_amplitude", amplitude, "dimensionless")?;
        let time_scale = p.fluidity_time_scale.unwrap_or(DEFAULT_TIME_SCALE);
        check_positive("fluidity_time_scale", time_scale, "s")?;
        let seed = p.fluidity_seed.unwrap_or(DEFAULT_SEED);
        check_positive("fluidity_seed", seed, "dimensionless")?;
        Ok(Nonlocal {
            base,
            amplitude,
            time_scale,
            seed,
            walls: p.fluidity_walls,
        })
    }
}

/// A point's fluidity and what the seeding rule remembers.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct FluidityHistory {
    /// `g` (1/s); zero on a disconnected point.
    pub fluidity: f64,
    /// Seeded, or flowing, since the trial ratio last sat at or below `mu_s`.
    pub seeded: bool,
}

impl Nonlocal {
    /// `b = (mu_2 - mu_s)/I_0`.
    fn b(&self) -> f64 {
        (self.base.mu_2 - self.base.mu_s) / self.base.i_0
    }

    /// `sqrt(p/rho_s)/d` (1/s): the inverse of the grains' inertial time at pressure `p`.
    pub fn rate_scale(&self, p: f64) -> f64 {
        (p / self.base.grain_density).sqrt() / self.base.grain_diameter
    }

    /// The local (homogeneous steady) fluidity at stress ratio `mu` and pressure `p`:
    /// `sqrt(p/rho_s)/d I_0 (mu - mu_s)/((mu_2 - mu) mu)` for `mu_s < mu < mu_2`, zero below;
    /// `gamma_dot_p = g_loc mu` is the mu(I) rate.
    pub fn local_fluidity(&self, mu: f64, p: f64) -> f64 {
        let m = &self.base;
        if mu <= m.mu_s {
            return 0.0;
        }
        self.rate_scale(p) * m.i_0 * (mu - m.mu_s) / ((m.mu_2 - mu) * mu)
    }

    /// `(mu_2 - mu_s)(mu - mu_s)/(mu_2 - mu)`: the linear growth coefficient of the
    /// fluidity (times `1/t0`) at stress ratio `mu < mu_2`.
    pub fn growth(&self, mu: f64) -> f64 {
        let m = &self.base;
        (m.mu_2 - m.mu_s) * (mu - m.mu_s) / (m.mu_2 - mu)
    }

    /// The cooperativity length at stress ratio `mu` (m):
    /// `A d sqrt((mu_2 - mu)/((mu_2 - mu_s)|mu - mu_s|))`.
    pub fn cooperativity_length(&self, mu: f64) -> f64 {
        self.amplitude * self.base.grain_diameter / self.growth(mu).abs().sqrt()
    }

    /// The stopping height of a layer at `angle` (rad) on a rough incline (`g = 0` at the
    /// base, zero flux at the surface): `(pi/2) xi(tan angle)`, where the slowest mode
    /// `sin(pi y / 2H)` neither grows nor decays.
    pub fn stopping_height(&self, angle: f64) -> f64 {
        std::f64::consts::FRAC_PI_2 * self.cooperativity_length(angle.tan())
    }

    /// The fluidity after a step `dt` from `g_n`, given the diffusion `A^2 d^2 lap(g)`
    /// (explicit) and the elastic trial `tau_tr`, `p > 0`; the stress ratio is the returned
    /// one, `tau_tr/(p + gdt g)` with `gdt = G dt` (`gdt = 0`: held at `tau_tr/p`, for
    /// checking the fluidity equation alone). Solves
    /// `F(g) = t0 (g - g_n)/dt - diffusion - growth(mu) g + b sqrt(rho_s d^2/p) mu g^2 = 0`
    /// for `g >= 0`, `mu = mu(g)`.
    pub fn advance(&self, g_n: f64, diffusion: f64, tau_tr: f64, p: f64, gdt: f64, dt: f64) -> f64 {
        let (mu_s, mu_2) = (self.base.mu_s, self.base.mu_2);
        let beta = self.b() * self.base.grain_diameter * (self.base.grain_density / p).sqrt();
        let c = self.time_scale / dt;
        let k = mu_2 - mu_s;
        // F and dF/dg at g.
        let eval = |g: f64| {
            let s = p + gdt * g;
            let mu = tau_tr / s;
            let dmu = -mu * gdt / s;
            let alpha = k * (mu - mu_s) / (mu_2 - mu);
            let dalpha = k * k / ((mu_2 - mu) * (mu_2 - mu));
            let f = c * (g - g_n) - diffusion - alpha * g + beta * mu * g * g;
            let df = c - (dalpha * dmu * g + alpha) + beta * (dmu * g * g + 2.0 * mu * g);
            (f, df)
        };
        // Where the bracket starts: mu(g) must lie below mu_2.
        let mu_tr = tau_tr / p;
        let mut lo = if mu_tr >= mu_2 {
            assert!(
                gdt > 0.0,
                "a fluidity held at mu = {mu_tr} >= mu_2 has no steady value"
            );
            (tau_tr / mu_2 - p) / gdt
        } else {
            if c * (-g_n) - diffusion >= 0.0 {
                // F(0) >= 0: the diffusion drains the point; the fluidity cannot go negative.
                return 0.0;
            }
            0.0
        };
        // Newton from `g_n`, kept inside the bracket (lo, hi) it narrows: F < 0 at lo,
        // F >= 0 at hi. For mu_tr < mu_2, F is convex in g (its three terms are), so past
        // the first step the iterates fall monotonically onto the root; where F is not
        // (mu_tr > mu_2) or Newton would leave the bracket, the step bisects it, or, with no
        // upper end found yet, doubles the distance from lo.
        let unit = self.rate_scale(p);
        let (mut hi, mut f_lo, mut f_hi) = (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY);
        let mut g = if g_n > lo { g_n } else { lo + unit };
        for _ in 0..MAX_ITERATIONS {
            let (f, df) = eval(g);
            let newton = g - f / df;
            if df > 0.0 && (newton - g).abs() <= TOLERANCE * g {
                return newton.max(lo);
            }
            if f < 0.0 {
                (lo, f_lo) = (g, f);
            } else {
                (hi, f_hi) = (g, f);
            }
            g = if df > 0.0 && newton > lo && newton < hi {
                newton
            } else if !hi.is_finite() {
                lo + 2.0 * (g - lo).max(unit)
            } else {
                // The secant through the bracket's ends if it falls well inside, else halve.
                let secant = lo - f_lo * (hi - lo) / (f_hi - f_lo);
                let width = hi - lo;
                if secant > lo + 0.1 * width && secant < hi - 0.1 * width {
                    secant
                } else {
                    0.5 * (lo + hi)
                }
            };
            if hi - lo <= TOLERANCE * hi {
                break;
            }
        }
        g
    }

    /// One point's update: the elastic trial, the fluidity, the return.
    pub fn update_point(
        &self,
        stress: &mut Stress,
        history: &mut FluidityHistory,
        step: &PointStep,
    ) -> PointOutcome {
        let m = &self.base;
        let (shear, dt) = (m.shear, step.dt);
        let trial = match m.dense_trial(stress, step) {
            Ok(trial) => trial,
            Err(disconnected) => {
                *history = FluidityHistory::default();
                return disconnected;
            }
        };
        let p = trial.pressure();
        let tau_trial = trial.equivalent_shear();
        let mu_trial = tau_trial / p;
        let mut g_n = history.fluidity;
        if mu_trial <= m.mu_s {
            history.seeded = false;
        } else if !history.seeded {
            if g_n == 0.0 {
                g_n = self.seed * self.rate_scale(p);
            }
            history.seeded = true;
        }
        let laplacian = step.fields.first().copied().unwrap_or(0.0);
        let ad = self.amplitude * m.grain_diameter;
        let gdt = shear * dt;
        let mut g = self.advance(g_n, ad * ad * laplacian, tau_trial, p, gdt, dt);
        if gdt * g < f64::EPSILON * p {
            g = 0.0;
        }
        history.fluidity = g;
        if g == 0.0 {
            *stress = trial;
            return PointOutcome {
                plastic_strain_rate: 0.0,
                phase: Phase::Solid,
            };
        }
        let scale = p / (p + gdt * g);
        *stress = trial.deviator().scaled(scale) + Stress::isotropic(p);
        PointOutcome {
            plastic_strain_rate: g * mu_trial * scale,
            phase: Phase::Flowing,
        }
    }
}

impl Item for Nonlocal {
    const NAME: &'static str = "Nonlocal";
}

impl Material for Nonlocal {
    type History = FluidityHistory;

    fn density(&self) -> f64 {
        self.base.critical_density
    }
    fn wave_speed(&self) -> f64 {
        self.base.wave_speed()
    }
    /// Isotropic lithostatic start, as `MuI`'s.
    fn lithostatic_ratio(&self) -> f64 {
        1.0
    }
    fn initial_volume(&self, mass: f64, stress: &Stress) -> f64 {
        self.base.initial_volume(mass, stress)
    }
    fn inertial_scale(&self) -> Option<f64> {
        Some(self.base.grain_diameter * self.base.grain_density.sqrt())
    }
    /// The explicit Laplacian needs the diffusion number `A^2 d^2 dt/(t0 h^2)` at most 1/4.
    fn check_step(&self, cell_size: f64, max_dt: f64) -> Result<(), String> {
        let ad = self.amplitude * self.base.grain_diameter;
        let number = ad * ad * max_dt / (self.time_scale * cell_size * cell_size);
        if number <= 0.25 {
            return Ok(());
        }
        Err(format!(
            "the fluidity's diffusion number A^2 d^2 dt/(t0 h^2) would reach {number:.3} \
             (dt = {max_dt:.3e} s, h = {cell_size} m), above the 1/4 its explicit Laplacian \
             allows: take a smaller step, larger cells or a longer fluidity_time_scale \
             (now {} s)",
            self.time_scale
        ))
    }
    /// With more than one point per cell the grid cannot see part of the points' fluidity,
    /// and that part grows at the local rate whatever the layer's thickness (measured:
    /// docs/VALIDATION.md, "Nonlocal granular fluidity").
    fn warning(&self, points_per_cell: usize) -> Option<String> {
        (points_per_cell > 1).then(|| {
            format!(
                "Nonlocal with {points_per_cell} x {points_per_cell} points per cell: the \
                 fluidity's sub-cell modes are invisible to the grid's Laplacian and grow \
                 unchecked, so thin layers flow below H_stop (at 25 degrees a layer of 0.8 H_stop \
                 flows at 1.9 mm/s with 2 x 2 points, creeps at 2e-5 m/s with 1 x 1; \
                 docs/VALIDATION.md); the material is not yet validated \
                 in MPM (issue 36)"
            )
        })
    }
    fn point_fields() -> &'static [&'static str] {
        LAPLACIAN
    }
    fn add_field_systems(schedule: &mut Schedule) {
        schedule.add_systems(
            fluidity_field
                .in_set(StepSet::ParticleToGrid)
                .after(Core(StepSet::ParticleToGrid)),
        );
    }
    fn update(
        &self,
        stress: &mut Stress,
        history: &mut FluidityHistory,
        step: &PointStep,
    ) -> PointOutcome {
        self.update_point(stress, history, step)
    }
}

/// What the fluidity's grid field reads and writes of a body.
type FluidityBody<'a> = (
    &'a MaterialState<Nonlocal>,
    &'a Points,
    &'a PointStates,
    &'a Location,
    &'a Bands,
    &'a mut GridFields,
    &'a mut PointFields,
);

/// The fluidity's grid field of every body of this material: its Laplacian at each point
/// (module docs, step 1).
pub fn fluidity_field(
    grid: Res<GridGeometry>,
    boundaries: Res<Boundaries>,
    mut bodies: Query<FluidityBody>,
) {
    for (state, points, states, location, bands, mut nodal, mut at_points) in &mut bodies {
        let walls = state.params.walls.resolve(&boundaries.0);
        let history = &state.history;
        let mut laplacian = std::mem::take(&mut nodal.field_mut(LAPLACIAN[0]).value);
        let fluidity = nodal.field_mut("fluidity");
        grid_field::scatter(&grid, location, bands, fluidity, |p| {
            let dense = states.phase[p] != Phase::Disconnected && points.mass[p] > 0.0;
            dense.then(|| (points.volume[p], history[p].fluidity))
        });
        grid_field::laplacian(&grid, fluidity, &walls, &mut laplacian);
        at_points.fill(0, |k| grid_field::gather(location, &laplacian, k));
        nodal.field_mut(LAPLACIAN[0]).value = laplacian;
    }
}
