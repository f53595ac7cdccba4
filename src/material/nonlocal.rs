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
//! How a step advances it, per body of this material (docs/model.md §4.2). The fluidity's
//! equation is solved on the grid's nodes, and each point carries the nodal increments, the
//! usual treatment of a diffused field in MPM (as thermal and damage fields are):
//! 1. `advance_fluidity` (the system of the [`Fluidity`] field, `crate::field`, in the
//!    `Fields` set, once the velocity gradient and the density are known; the points' `g`
//!    and seeding flag are the field's columns, [`FLUIDITY`] and [`SEEDED`]): each point's elastic trial stress; the
//!    seeding rule (below) on its `g`; the dense points' `g` and trial pressure `p` scattered
//!    to the nodes with their volumes as weights; the nodal Laplacian of `g` with the walls'
//!    conditions (`g = 0` on no-slip walls and obstacles, zero flux elsewhere, settable per
//!    wall); each point's ratio were it returned with its cell's present fluidity,
//!    `q = tau_tr/(p + G dt g_cell)`, scattered the same way; and at each free node the
//!    equation above with the Laplacian explicit and everything else implicit, `mu` being
//!    `q_i (p_i + G dt g_i)/(p_i + G dt g)` of the unknown `g`: one scalar root, found by a
//!    safeguarded Newton iteration in a bracket (`Nonlocal::advance`), so `mu` stays below
//!    `mu_2`. The node's ratio at its present fluidity is so the mean of the ratios its
//!    points will return to. (Scattering `tau_tr` itself and taking `tau_tr/(p + G dt g)`
//!    makes it the ratio of means, which is not the mean of the points' ratios where the
//!    fluidity varies across a node's support: in a steady 2 `H_stop` layer on 6 cells the
//!    nodal ratios sat 2% below `tan theta`, and the layer ran 17% slower than the 1D model
//!    on its own nodes, 1% faster when the step was halved; docs/VALIDATION.md.)
//!    Each point then adds the interpolated increment `sum N (g_new - g_old)` to its `g`
//!    (over the active nodes, renormalised: `grid_field::gather_active`).
//! 2. The update (per point): the elastic trial again, and the return with `g_hat`, the new
//!    nodal fluidity at the centre of the point's cell (`grid_field::cell_centres`, left in
//!    column [`INTERPOLATED`] by the field, which the material reads by name):
//!    `tau = tau_tr p/(p + G dt g_hat)`, `gamma_dot_p = g_hat mu`. The velocity gradient is
//!    constant over a cell, so a `g_hat` interpolated to each point would make the points of
//!    a cell return to ratios in inverse proportion to their `g_hat` (three to one in the
//!    cell on a `g = 0` wall at 2 x 2 points per cell), a pattern of stress the grid's forces
//!    cannot see either: measured, a layer at rest kept ratios from `mu_s` to `mu_2` in
//!    alternate rows, and a layer at 1.1 `H_stop` flowed at half the speed it had at 1 x 1
//!    (docs/VALIDATION.md). A point whose trial shear is well above its cell's could still
//!    return above `mu_2`, which no fluidity reaches (its rate of growth diverges there): it
//!    takes at least the fluidity that returns it onto `mu_2`. That bound never feeds the
//!    points' `g`, so it cannot grow what the grid cannot see.
//!
//! Why on the nodes: with more points than nodes, part of the points' fluidity (a pattern
//! alternating from point to point inside the cells) scatters to nothing. Advanced on the
//! points, that part has no Laplacian and grew at the local rate whatever the layer's
//! thickness: a layer below `H_stop` flowed at 2 x 2 points per cell (docs/VALIDATION.md).
//! On the nodes, what the grid cannot see neither grows nor smooths, and the stress never
//! sees it (`g_hat` comes from the nodes). The diffusion number
//! `A^2 d^2 dt/(t0 h^2)` must stay below 1/4 for the explicit Laplacian; the scene check
//! refuses a scene whose largest step would break it.
//!
//! `g = 0` solves the equation, so a body at rest stays at rest unless something starts it: a
//! point whose trial stress ratio rises above `mu_s` has its `g` raised to at least the seed
//! `fluidity_seed sqrt(p/rho_s)/d`, once until it falls back below `mu_s` or disconnects;
//! the seeds reach the nodes through the scatter. (At least, not only from zero: a point at
//! rest may still carry a small part the grid cannot see, of either sign.) Disconnected
//! points carry no fluidity and are left out of the scatter; a point that reconnects takes
//! the nodes' new fluidity interpolated to it, or the seed (if its ratio is above `mu_s`)
//! where no node of its footprint is active. A dense point that no active node reaches (a
//! clump too small to fill an eighth of any node's support) keeps its `g` unchanged and
//! returns with it: it is outside the field. Where the
//! stress exceeds `mu_2` no seed is needed: no `g` short of the one bringing `mu` below
//! `mu_2` solves the equation. A nodal fluidity below `REST` (`1e-12`) times the rate scale
//! `sqrt(p/rho_s)/d`, or too small to change the stress in floating point, is set to zero, so
//! a layer below `H_stop` comes exactly to rest.

use serde::{Deserialize, Serialize};

use bevy_ecs::prelude::*;
use rayon::prelude::*;

use super::granular::{TransPhase, check_positive, trans_phase_params};
use bevy_ecs::schedule::ScheduleConfigs;
use bevy_ecs::system::ScheduleSystem;
use bevy_ecs::world::EntityWorldMut;

use super::{Material, MaterialState, PointOutcome, PointStep};
use crate::body::{Phase, PointStates, Points};
use crate::field::Field;
use crate::grid::GridGeometry;
use crate::grid_field::{self, FieldColumns, FieldWalls, GridFields, NodeCondition, StartBands};
use crate::obstacle::Obstacles;
use crate::registry::Item;
use crate::resources::{Boundaries, Clock, Wall, Walls};
use crate::step::Location;
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

/// A nodal fluidity below this many times the rate scale `sqrt(p/rho_s)/d` is rest (zero):
/// a creep ten orders of magnitude below the default seed. The nodes' values are means of
/// the points', which carry what the grid cannot see (of either sign, as large as the seed);
/// the round-off of those means keeps a layer below `H_stop` at about `1e-15` /s where exact
/// arithmetic would decay it for ever, so "too small to change the stress" alone never came.
pub const REST: f64 = 1e-12;

/// The fluidity solve stops when a step changes `g` by less than this, relatively.
const TOLERANCE: f64 = 1e-13;
/// And gives up after this many steps (bisection alone would halve the bracket this often).
const MAX_ITERATIONS: usize = 200;

/// The fluidity's columns (`Fluidity`, a field of every `Nonlocal` body): each point's `g`
/// (1/s; zero on a disconnected point), its seeding flag (1 when seeded, or flowing, since
/// its trial ratio last sat at or below `mu_s`; else 0), and the nodes' fluidity at the
/// centre of its cell after the step's advance, which the return reads (`g_hat`).
pub const FLUIDITY: &str = "fluidity";
pub const SEEDED: &str = "fluidity_seeded";
pub const INTERPOLATED: &str = "fluidity_interpolated";
const COLUMNS: &[&str] = &[FLUIDITY, SEEDED, INTERPOLATED];

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
    /// The conditions on the grid field, given the scene's walls and obstacles; the wall
    /// segments and the obstacles take their own wall's default
    /// (`NodeCondition::default_for`: zero on a `NoSlip` obstacle, zero flux on any other).
    pub fn resolve<'a>(&self, walls: &'a Walls, obstacles: &'a Obstacles) -> FieldWalls<'a> {
        let side = |choice: Option<FluidityWall>, wall: Wall| match choice {
            None => NodeCondition::default_for(wall),
            Some(FluidityWall::Zero) => NodeCondition::Fixed(0.0),
            Some(FluidityWall::ZeroFlux) => NodeCondition::ZeroFlux,
        };
        FieldWalls {
            left: side(self.left, walls.left),
            right: side(self.right, walls.right),
            bottom: side(self.bottom, walls.bottom),
            top: side(self.top, walls.top),
            segments: &walls.segments,
            obstacles: obstacles.held_nodes(),
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
        if seed < 1e3 * REST {
            return Err(format!(
                "fluidity_seed = {seed:e} is within three orders of magnitude of the fluidity \
                 taken as rest ({REST:e} sqrt(p/rho_s)/d), so a seeded point would be at rest \
                 in a few steps: give at least {:e}",
                1e3 * REST
            ));
        }
        Ok(Nonlocal {
            base,
            amplitude,
            time_scale,
            seed,
            walls: p.fluidity_walls,
        })
    }
}

/// A point's fluidity and what the seeding rule remembers (its columns [`FLUIDITY`] and
/// [`SEEDED`], as the seeding rule reads them).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct FluidityHistory {
    /// `g` (1/s); zero on a disconnected point.
    pub fluidity: f64,
    /// Seeded, or flowing, since the trial ratio last sat at or below `mu_s`.
    pub seeded: bool,
}

impl FluidityHistory {
    /// Runs `edit` on the point whose columns hold `g` and `seeded`, and writes back what it
    /// leaves.
    #[inline]
    fn edit<R>(g: &mut f64, seeded: &mut f64, edit: impl FnOnce(&mut Self) -> R) -> R {
        let mut history = FluidityHistory {
            fluidity: *g,
            seeded: *seeded != 0.0,
        };
        let out = edit(&mut history);
        *g = history.fluidity;
        *seeded = if history.seeded { 1.0 } else { 0.0 };
        out
    }
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

    /// The seeding rule on a point's `g` at trial pressure `p` and ratio `mu_trial`
    /// (module docs).
    fn seed(&self, history: &mut FluidityHistory, p: f64, mu_trial: f64) {
        if mu_trial <= self.base.mu_s {
            history.seeded = false;
        } else if !history.seeded {
            history.fluidity = history.fluidity.max(self.seed * self.rate_scale(p));
            history.seeded = true;
        }
    }

    /// The fluidity a node takes after a step `dt` from `g_n`, given its Laplacian
    /// `laplacian` (explicit) and the scattered trial shear `tau_tr` and pressure `p > 0`:
    /// [`Nonlocal::advance`] with the return's ratio, set to zero at rest (below [`REST`]
    /// times the rate scale, or too small to change the stress in floating point).
    pub fn advance_node(&self, g_n: f64, laplacian: f64, tau_tr: f64, p: f64, dt: f64) -> f64 {
        let ad = self.amplitude * self.base.grain_diameter;
        let gdt = self.base.shear * dt;
        let g = self.advance(g_n, ad * ad * laplacian, tau_tr, p, gdt, dt);
        if g < REST * self.rate_scale(p) || gdt * g < f64::EPSILON * p {
            0.0
        } else {
            g
        }
    }

    /// One point's update: the elastic trial and the return with the fluidity interpolated
    /// from the nodes, column [`INTERPOLATED`] of `step.fields` (`g_hat`; module docs). (A
    /// disconnected point's own fluidity is cleared by the field, `advance_fluidity`, which
    /// finds it disconnected by the same trial.)
    pub fn update_point(&self, stress: &mut Stress, step: &PointStep) -> PointOutcome {
        let m = &self.base;
        let trial = match m.dense_trial(stress, step) {
            Ok(trial) => trial,
            Err(disconnected) => return disconnected,
        };
        let p = trial.pressure();
        let tau_trial = trial.equivalent_shear();
        let gdt = m.shear * step.dt;
        // The nodes solve for `mu < mu_2`; a point whose trial shear is above its nodes'
        // mean could still return above `mu_2`, where the fluidity would grow without bound,
        // so it takes at least the fluidity that brings it onto `mu_2`.
        let g_hat = step.fields.get(INTERPOLATED).unwrap_or(0.0);
        let g = g_hat.max((tau_trial / m.mu_2 - p) / gdt);
        if gdt * g < f64::EPSILON * p {
            *stress = trial;
            return PointOutcome {
                plastic_strain_rate: 0.0,
                phase: Phase::Solid,
            };
        }
        let scale = p / (p + gdt * g);
        *stress = trial.deviator().scaled(scale) + Stress::isotropic(p);
        PointOutcome {
            plastic_strain_rate: g * tau_trial / p * scale,
            phase: Phase::Flowing,
        }
    }
}

impl Item for Nonlocal {
    const NAME: &'static str = "Nonlocal";
}

impl Material for Nonlocal {
    /// None: the fluidity is a field of its own ([`Fluidity`]).
    type History = ();

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
    fn granular(&self) -> bool {
        true
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
    fn point_fields() -> &'static [&'static str] {
        &[INTERPOLATED]
    }
    fn fields(&self) -> Vec<Box<dyn Field>> {
        vec![Box::new(Fluidity)]
    }
    fn update(&self, stress: &mut Stress, _: &mut (), step: &PointStep) -> PointOutcome {
        self.update_point(stress, step)
    }
}

/// The fluidity as a field (`crate::field`): the one every `Nonlocal` body carries, its
/// columns [`FLUIDITY`], [`SEEDED`] and [`INTERPOLATED`], advanced by [`advance_fluidity`]
/// with its body's material parameters. Scenes do not list it: the material brings it.
#[derive(Clone, Copy, Debug, Deserialize)]
pub struct Fluidity;

impl Item for Fluidity {
    const NAME: &'static str = "Fluidity";
    const UNIT: bool = true;
}

impl Field for Fluidity {
    fn columns(&self) -> &'static [&'static str] {
        COLUMNS
    }
    /// Its bodies are found by their `MaterialState<Nonlocal>`; its columns start at zero
    /// (at rest, not seeded).
    fn attach(&self, body: &mut EntityWorldMut) {
        let points = body.get::<Points>().map_or(0, Points::len);
        let mut columns = body
            .get_mut::<FieldColumns>()
            .expect("the builder gives a body with fields its columns");
        for name in COLUMNS {
            columns
                .add(name, vec![0.0; points])
                .expect("a Nonlocal body carries one fluidity");
        }
    }
    fn system(&self) -> ScheduleConfigs<ScheduleSystem> {
        advance_fluidity.into_configs()
    }
}

/// What the fluidity's grid field reads and writes of a body.
type FluidityBody<'a> = (
    &'a MaterialState<Nonlocal>,
    &'a Points,
    &'a PointStates,
    &'a Location,
    &'a StartBands,
    &'a mut GridFields,
    &'a mut FieldColumns,
);

/// What the fluidity's step knows of a point after its elastic trial.
#[derive(Clone, Copy, Debug, Default)]
enum Trial {
    /// Disconnected (or retired): no fluidity.
    #[default]
    Out,
    /// Dense, and dense at the start of the step: scattered to the nodes.
    Dense { p: f64, tau: f64 },
    /// Dense again after a disconnected step: takes the nodes' fluidity (module docs).
    Reconnecting { p: f64, tau: f64 },
}

/// Scratch reused from step to step.
#[derive(Default)]
pub struct FluidityScratch {
    trials: Vec<Trial>,
    next: Vec<f64>,
    increment: Vec<f64>,
    /// The nodes' fluidity at the centre of each cell (`grid_field::cell_centres`).
    centres: Vec<Option<f64>>,
}

/// The fluidity's step on the nodes for every body of this material (module docs, step 1).
pub fn advance_fluidity(
    grid: Res<GridGeometry>,
    boundaries: Res<Boundaries>,
    obstacles: Res<Obstacles>,
    clock: Res<Clock>,
    mut bodies: Query<FluidityBody>,
    mut scratch: Local<FluidityScratch>,
) {
    let dt = clock.dt;
    let scratch = &mut *scratch;
    for (state, points, states, location, bands, mut nodal, mut columns) in &mut bodies {
        let params = &state.params;
        let [fluidity_at, seeded_at, interpolated] = columns
            .many_mut([FLUIDITY, SEEDED, INTERPOLATED])
            .expect("a Nonlocal body carries the fluidity's columns");
        let walls = params.walls.resolve(&boundaries.0, &obstacles);
        // The elastic trial of every point, and the seeding rule on the dense ones.
        scratch.trials.clear();
        scratch.trials.par_extend(
            fluidity_at
                .par_iter_mut()
                .zip(seeded_at.par_iter_mut())
                .enumerate()
                .map(|(k, (g, seeded))| {
                    FluidityHistory::edit(g, seeded, |history| {
                        if points.mass[k] == 0.0 {
                            *history = FluidityHistory::default();
                            return Trial::Out;
                        }
                        let step =
                            PointStep::new(points.velocity_gradient[k], dt, points.density[k]);
                        let mut stress = points.stress[k];
                        let Ok(trial) = params.base.dense_trial(&mut stress, &step) else {
                            *history = FluidityHistory::default();
                            return Trial::Out;
                        };
                        let (p, tau) = (trial.pressure(), trial.equivalent_shear());
                        if states.phase[k] == Phase::Disconnected {
                            return Trial::Reconnecting { p, tau };
                        }
                        params.seed(history, p, tau / p);
                        Trial::Dense { p, tau }
                    })
                }),
        );
        let trials = &scratch.trials;
        let dense = |k: usize| match trials[k] {
            Trial::Dense { p, tau } => Some((points.volume[k], p, tau)),
            _ => None,
        };
        let fluidity_now = &*fluidity_at;
        let mut fluidity = std::mem::take(nodal.field_mut("fluidity"));
        let mut pressure = std::mem::take(nodal.field_mut("trial_pressure"));
        let mut ratio = std::mem::take(nodal.field_mut("trial_ratio"));
        let mut laplacian = std::mem::take(&mut nodal.field_mut("fluidity_laplacian").value);
        let bands = &bands.0;
        grid_field::scatter_many(
            &grid,
            location,
            bands,
            [&mut fluidity, &mut pressure],
            |k| dense(k).map(|(v, p, _)| (v, [fluidity_now[k], p])),
        );
        let fixed = grid_field::laplacian(&grid, &mut fluidity, &walls, &mut laplacian);
        // Each point's ratio if it returned with the fluidity its cell has now: the node's
        // ratio at its own fluidity is their mean (module docs, step 1).
        let gdt = params.base.shear * dt;
        grid_field::cell_centres(&grid, &fluidity, &fluidity.value, &mut scratch.centres);
        let centres = &scratch.centres;
        grid_field::scatter(&grid, location, bands, &mut ratio, |k| {
            dense(k).map(|(v, p, tau)| {
                let g = centres[grid.cell_of(points.position[k])];
                (v, tau / (p + gdt * g.unwrap_or(0.0)))
            })
        });
        // The nodal update: free active nodes solve the equation, fixed ones keep the wall's
        // value (set on `fluidity` by the Laplacian), inactive ones stay at zero.
        scratch.next.clear();
        scratch
            .next
            .par_extend((0..grid.node_count()).into_par_iter().map(|n| {
                if !fluidity.active(n) || fixed[n] {
                    return fluidity.value[n];
                }
                let (g, p) = (fluidity.value[n], pressure.value[n]);
                params.advance_node(g, laplacian[n], ratio.value[n] * (p + gdt * g), p, dt)
            }));
        scratch.increment.clear();
        scratch.increment.par_extend(
            scratch
                .next
                .par_iter()
                .zip(fluidity.value.par_iter())
                .map(|(new, old)| new - old),
        );
        grid_field::cell_centres(&grid, &fluidity, &scratch.next, &mut scratch.centres);
        let (next, increment, centres) = (&scratch.next, &scratch.increment, &scratch.centres);
        // The points: the increment on dense ones, the nodes' fluidity on reconnecting ones
        // (over the active nodes of their footprints; a point that reaches none keeps its `g`,
        // or is seeded if it reconnects); then the return's fluidity, the nodes' at the
        // centre of the point's cell (module docs), or the point's own outside the field.
        let each = fluidity_at.par_iter_mut().zip(seeded_at.par_iter_mut());
        let each = each.zip(interpolated.par_iter_mut());
        each.enumerate().for_each(|(k, ((g, seeded), g_hat))| {
            let interpolated = |nodal| grid_field::gather_active(location, &fluidity, [nodal], k);
            FluidityHistory::edit(g, seeded, |history| match trials[k] {
                Trial::Out => {}
                // Not clipped at zero: the point's `g` is the nodes' plus what the grid
                // cannot see, which may be of either sign; only nodal values (and so
                // `g_hat`) are kept non-negative, by the nodal solve.
                Trial::Dense { .. } => {
                    if let Some([dg]) = interpolated(increment) {
                        history.fluidity += dg;
                    }
                }
                Trial::Reconnecting { p, tau } => match interpolated(next) {
                    Some([g_hat]) => {
                        history.fluidity = g_hat;
                        history.seeded = tau > params.base.mu_s * p;
                    }
                    None => params.seed(history, p, tau / p),
                },
            });
            *g_hat = centres[grid.cell_of(points.position[k])].unwrap_or(*g);
        });
        *nodal.field_mut("fluidity") = fluidity;
        *nodal.field_mut("trial_pressure") = pressure;
        *nodal.field_mut("trial_ratio") = ratio;
        nodal.field_mut("fluidity_laplacian").value = laplacian;
    }
}
