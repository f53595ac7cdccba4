//! The fluidity equation of the `Nonlocal` material, checked without the MPM step against its
//! exact answers (docs/VALIDATION.md, "Nonlocal granular fluidity"): the local fluidity
//! in uniform flow, the creep slab's `cosh` profile with second-order convergence of the grid
//! field's Laplacian, the growth rate of a small mode about `g = 0`, and the return's
//! `gamma_dot_p = g mu`.

use glam::{DMat2, DVec2};
use regolith::grid::GridGeometry;
use regolith::grid_field::{FieldValues, FieldWalls, NodalScalar, NodeCondition, laplacian};
use regolith::material::PointStep;
use regolith::material::nonlocal::{INTERPOLATED, Nonlocal};
use regolith::stress::Stress;

/// The paper's PS-1 material (section 4.1) with the default fluidity parameters, as a scene
/// writes it.
fn ps1() -> Nonlocal {
    ron::Options::default()
        .with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME)
        .from_str(
            "(youngs_modulus: 2.0e7, poisson_ratio: 0.45, grain_density: 1280.0, \
             packing_fraction: 0.79, grain_diameter: 5.0e-3, mu_s: 0.320, mu_2: 0.598, \
             i_0: 0.278)",
        )
        .expect("the PS-1 parameters")
}

#[test]
fn uniform_flow_relaxes_to_the_local_fluidity() {
    let m = ps1();
    let p = 800.0;
    for mu in [0.33, 0.4, 0.4663, 0.55, 0.59] {
        // The ratio held (no return): g -> g_loc(mu, p).
        let dt = 1e-4;
        let mut g = 1e-3 * m.rate_scale(p);
        for _ in 0..20_000 {
            g = m.advance(g, 0.0, mu * p, p, 0.0, dt);
        }
        let local = m.local_fluidity(mu, p);
        assert!(
            (g / local - 1.0).abs() < 1e-6,
            "mu = {mu}: g = {g}, g_loc = {local}"
        );
        // With the return (a fixed trial stress): g -> g_loc of the returned ratio, and the
        // plastic rate is the mu(I) rate of that ratio.
        let gdt = m.base.shear * 2e-5;
        let tau_tr = mu * p * 1.5;
        let mut g = 1e-3 * m.rate_scale(p);
        for _ in 0..20_000 {
            g = m.advance(g, 0.0, tau_tr, p, gdt, dt);
        }
        let returned = tau_tr / (p + gdt * g);
        let local = m.local_fluidity(returned, p);
        assert!(
            (g / local - 1.0).abs() < 1e-6,
            "mu_tr = {}: g = {g}, g_loc(mu = {returned}) = {local}",
            1.5 * mu
        );
        let i = g * returned * m.base.grain_diameter * (m.base.grain_density / p).sqrt();
        let mu_of_i = regolith::material::granular::mu_of_i(0.32, 0.598, 0.278, i);
        assert!((mu_of_i / returned - 1.0).abs() < 1e-6);
    }
}

/// A line of `cells` cells along x (one cell high, periodic in y).
fn line(cells: usize, h: f64, periodic: bool) -> GridGeometry {
    GridGeometry {
        origin: DVec2::ZERO,
        cell_size: h,
        cells: [cells, 1],
        periodic: [periodic, true],
    }
}

/// Steps the nodal field `g` with the material's update at every node (ratio `mu` held,
/// pressure `p`), the grid field's Laplacian explicit, until it stops changing.
fn relax(
    m: &Nonlocal,
    grid: &GridGeometry,
    walls: &FieldWalls,
    g: &mut NodalScalar,
    mu: f64,
    p: f64,
) -> usize {
    let ad2 = (m.amplitude * m.base.grain_diameter).powi(2);
    // Diffusion number 0.2 (the explicit limit is 1/4).
    let dt = 0.2 * m.time_scale * grid.cell_size.powi(2) / ad2;
    let mut lap = Vec::new();
    for step in 0..10_000_000 {
        laplacian(grid, g, walls, &mut lap);
        let mut change: f64 = 0.0;
        for (n, l) in lap.iter().enumerate() {
            if let NodeCondition::Fixed(_) = walls.left
                && n == 0
            {
                continue;
            }
            let next = m.advance(g.value[n], ad2 * l, mu * p, p, 0.0, dt);
            change = change.max((next - g.value[n]).abs());
            g.value[n] = next;
        }
        if change < 1e-15 {
            return step;
        }
    }
    panic!("the slab did not settle");
}

/// Creep below mu_s: `g = g0` at x = 0, zero flux at x = L: `g0 cosh((L - x)/xi)/cosh(L/xi)`.
/// The error falls as h^2.
#[test]
fn a_creep_slab_matches_the_cosh_profile_to_second_order() {
    let m = ps1();
    let mu = 0.25;
    let xi = m.cooperativity_length(mu);
    let len = 3.0 * xi;
    // A pressure so high that the g^2 term is negligible: the equation is then linear.
    let (p, g0) = (1e12, 1e-3);
    let walls = FieldWalls {
        left: NodeCondition::Fixed(g0),
        right: NodeCondition::ZeroFlux,
        bottom: NodeCondition::ZeroFlux,
        top: NodeCondition::ZeroFlux,
        segments: &[],
        obstacles: &[],
    };
    let mut errors = Vec::new();
    for cells in [10, 20, 40] {
        let grid = line(cells, len / cells as f64, false);
        let nodes = cells + 1;
        let mut g = NodalScalar {
            weight: vec![1.0; nodes],
            value: vec![0.0; nodes],
        };
        relax(&m, &grid, &walls, &mut g, mu, p);
        let exact = |x: f64| g0 * ((len - x) / xi).cosh() / (len / xi).cosh();
        let error = (0..nodes)
            .map(|i| (g.value[i] - exact(i as f64 * grid.cell_size)).abs() / g0)
            .fold(0.0, f64::max);
        errors.push(error);
    }
    eprintln!("creep slab max errors on 10, 20, 40 cells: {errors:?}");
    assert!(errors[0] < 5e-3, "{errors:?}");
    for k in 1..errors.len() {
        let order = (errors[k - 1] / errors[k]).log2();
        assert!(
            (1.8..2.3).contains(&order),
            "order {order:.2} between refinements ({errors:?})"
        );
    }
}

/// About `g = 0` a mode `cos(kx)` grows at `s = [growth(mu) - A^2 d^2 k^2]/t0`: on the grid
/// with the discrete `k_h^2 = (2 - 2 cos kh)/h^2` exactly per step, and within 0.2% of the
/// continuum rate at 64 cells per wavelength and a step of 1e-3 t0.
#[test]
fn a_small_mode_about_zero_grows_at_the_linear_rate() {
    let m = ps1();
    let mu = 25f64.to_radians().tan();
    let (cells, h) = (64, 1e-3);
    let grid = line(cells, h, true);
    let p = 1e3;
    let dt = 1e-3 * m.time_scale;
    let ad2 = (m.amplitude * m.base.grain_diameter).powi(2);
    let k = 2.0 * std::f64::consts::PI / (64.0 * h);
    // A small positive field: a mean and a cosine of half its size.
    let eps = 1e-12;
    let mut g = NodalScalar {
        weight: vec![1.0; cells],
        value: (0..cells)
            .map(|i| eps * (1.0 + 0.5 * (k * i as f64 * h).cos()))
            .collect(),
    };
    let walls = FieldWalls {
        left: NodeCondition::ZeroFlux,
        right: NodeCondition::ZeroFlux,
        bottom: NodeCondition::ZeroFlux,
        top: NodeCondition::ZeroFlux,
        segments: &[],
        obstacles: &[],
    };
    let amplitude = |g: &NodalScalar| {
        2.0 / cells as f64
            * (0..cells)
                .map(|i| g.value[i] * (k * i as f64 * h).cos())
                .sum::<f64>()
    };
    let a0 = amplitude(&g);
    let steps = 2000;
    let mut lap = Vec::new();
    for _ in 0..steps {
        laplacian(&grid, &mut g, &walls, &mut lap);
        for (n, l) in lap.iter().enumerate() {
            g.value[n] = m.advance(g.value[n], ad2 * l, mu * p, p, 0.0, dt);
        }
    }
    let rate = (amplitude(&g) / a0).ln() / (steps as f64 * dt);
    let kh2 = (2.0 - 2.0 * (k * h).cos()) / (h * h);
    let c = dt / m.time_scale;
    let per_step = (1.0 - c * ad2 * kh2) / (1.0 - c * m.growth(mu));
    let discrete = per_step.ln() / dt;
    let continuum = (m.growth(mu) - ad2 * k * k) / m.time_scale;
    eprintln!("growth rate {rate:.3} 1/s; discrete {discrete:.3}; continuum {continuum:.3}");
    assert!(((rate - discrete) / discrete).abs() < 1e-6);
    assert!(((rate - continuum) / continuum).abs() < 2e-3);
    assert!(rate > 0.0, "at 25 degrees a mode 64 mm long grows");
}

/// The return at the fluidity a node solves for (handed to the point as `g_hat`):
/// `gamma_dot_p = g mu` and `tau = tau_tr - G dt gdp`, to round-off, for points below, on
/// and above the mu(I) range, and the returned ratio below `mu_2`.
#[test]
fn the_return_gives_a_plastic_rate_of_g_mu() {
    let m = ps1();
    let p = 600.0;
    let dt = 1.8e-5;
    for (shear, g_n) in [
        (0.2, 0.0),
        (0.35, 50.0),
        (0.5, 120.0),
        (0.9, 0.0),
        (3.0, 10.0),
    ] {
        let stress = Stress {
            xx: -p,
            yy: -p,
            zz: -p,
            xy: shear * p,
        };
        let mut s = stress;
        let (tau_tr, p) = (stress.equivalent_shear(), stress.pressure());
        let g = m.advance_node(g_n, 0.0, tau_tr, p, dt);
        let g_hat = [g];
        let columns = [(INTERPOLATED, &g_hat[..])];
        let step = PointStep {
            fields: FieldValues::new(&columns, 0),
            ..PointStep::new(DMat2::ZERO, dt, m.base.critical_density * 1.001)
        };
        let out = m.update_point(&mut s, &step);
        let tau = s.equivalent_shear();
        let gdp = out.plastic_strain_rate;
        assert!(
            (gdp - g * tau / p).abs() <= 1e-12 * gdp.max(1e-300),
            "ratio {shear}: gdp {gdp} against g mu {}",
            g * tau / p
        );
        let returned = tau_tr - m.base.shear * dt * gdp;
        assert!(
            (tau - returned).abs() <= 1e-12 * tau_tr,
            "ratio {shear}: tau {tau} against tau_tr - G dt gdp = {returned}"
        );
        assert!(
            tau / p < m.base.mu_2,
            "ratio {shear}: mu = {} not below mu_2",
            tau / p
        );
    }
}
