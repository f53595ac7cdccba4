//! The APIC transfer (`transfer: Apic`, Jiang et al. 2015): what makes it a transfer
//! without a hidden viscosity.
//!
//! * An affine velocity field on the grid comes back to a point exactly: its velocity is
//!   the field at the point and its affine matrix `C_p` is the field's gradient.
//! * The gather conserves angular momentum: with `C_p = B_p D_p^-1` (the velocity gradient
//!   for bilinear weights) the points' angular
//!   momentum, `sum_p m_p (x_p x v_p + (C_p D_p)_yx - (C_p D_p)_xy)`, equals the grid's,
//!   `sum_i m_i x_i x v_i`, whatever the nodal velocities.
//! * The scatter conserves linear and angular momentum: the grid momentum of a step's
//!   scatter has the points' total momentum and angular momentum.

use crate::common::Rng;
use regolith::Simulation;
use regolith::defaults::parse_scene;
use regolith::glam::{DMat2, DVec2};
use regolith::grid::GridGeometry;
use regolith::shape_functions::{CpdiFixed, Footprint, Linear, QuadraticBspline, Scheme};
use regolith::step::scatter_gather::apic_gather;

fn grid() -> GridGeometry {
    GridGeometry {
        origin: DVec2::new(-0.3, 0.1),
        cell_size: 0.05,
        cells: [20, 16],
        periodic: [false, false],
    }
}

fn node_positions(grid: &GridGeometry) -> Vec<DVec2> {
    let mut x = Vec::with_capacity(grid.node_count());
    for j in 0..grid.nodes_along(1) {
        for i in 0..grid.nodes_along(0) {
            x.push(grid.node_position(i, j));
        }
    }
    x
}

/// Random points at least two cells from the domain edges, with half-widths of a quarter
/// cell (2 x 2 points per cell).
fn interior_points(grid: &GridGeometry, rng: &mut Rng, n: usize) -> Vec<DVec2> {
    let (lo, hi) = (grid.origin, grid.max());
    let margin = 2.0 * grid.cell_size;
    (0..n)
        .map(|_| {
            let u = 0.5 * (rng.vec() + DVec2::ONE);
            lo + DVec2::splat(margin) + u * (hi - lo - DVec2::splat(2.0 * margin))
        })
        .collect()
}

fn affine_field_comes_back<S: Scheme>() {
    let grid = grid();
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let v0 = rng.vec();
    let a = DMat2::from_cols(rng.vec(), rng.vec());
    let nodal: Vec<DVec2> = node_positions(&grid).iter().map(|&x| v0 + a * x).collect();
    let half = 0.25 * grid.cell_size;
    for x in interior_points(&grid, &mut rng, 500) {
        let f = Footprint::new::<S>(&grid, x, half);
        let (v, l, c) = apic_gather::<S>(&f, &grid, x, &nodal);
        assert!(
            (v - (v0 + a * x)).length() < 1e-13,
            "{}: v {v} at {x}",
            S::NAME
        );
        for (name, m) in [("C", c), ("L", l)] {
            let err = (m - a)
                .to_cols_array()
                .iter()
                .map(|e| e.abs())
                .fold(0.0, f64::max);
            assert!(err < 1e-11, "{}: {name} off by {err:e} at {x}", S::NAME);
        }
    }
}

#[test]
fn an_affine_field_comes_back_exactly() {
    affine_field_comes_back::<CpdiFixed>();
    affine_field_comes_back::<Linear>();
    affine_field_comes_back::<QuadraticBspline>();
}

/// `m (x x v + (C D)_yx - (C D)_xy)`: a point's APIC angular momentum (z component).
fn point_angular_momentum(
    f: &Footprint,
    grid: &GridGeometry,
    x: DVec2,
    m: f64,
    v: DVec2,
    c: DMat2,
) -> f64 {
    let (dx, dy) = f.offsets(grid, x);
    let b = c * f.affine_inertia(&dx, &dy);
    m * (x.perp_dot(v) + b.x_axis.y - b.y_axis.x)
}

fn gather_keeps_angular_momentum<S: Scheme>() {
    let grid = grid();
    let mut rng = Rng(0x2545_f491_4f6c_dd1d);
    let nodes = node_positions(&grid);
    let nodal: Vec<DVec2> = nodes.iter().map(|_| rng.vec()).collect();
    let half = 0.25 * grid.cell_size;
    let mut node_mass = vec![0.0; nodes.len()];
    let mut points = 0.0;
    for x in interior_points(&grid, &mut rng, 400) {
        let m = 1.0 + 0.5 * rng.next();
        let f = Footprint::new::<S>(&grid, x, half);
        f.for_each_entry(|n, w, _| node_mass[n] += w * m);
        let (v, _, c) = apic_gather::<S>(&f, &grid, x, &nodal);
        points += point_angular_momentum(&f, &grid, x, m, v, c);
    }
    let on_grid: f64 = (0..nodes.len())
        .map(|n| node_mass[n] * nodes[n].perp_dot(nodal[n]))
        .sum();
    assert!(
        (points - on_grid).abs() < 1e-11 * on_grid.abs().max(1.0),
        "{}: points {points}, grid {on_grid}",
        S::NAME
    );
}

#[test]
fn the_gather_conserves_angular_momentum() {
    gather_keeps_angular_momentum::<CpdiFixed>();
    gather_keeps_angular_momentum::<Linear>();
    gather_keeps_angular_momentum::<QuadraticBspline>();
}

/// A stress-free body without gravity on the test grid, with the APIC transfer.
fn scatter_scene(integration: &str, shape: &str) -> Simulation {
    let scene = parse_scene(&format!(
        r#"(
        name: "apic_scatter",
        domain: (origin: (-0.3, 0.1), size: (1.0, 0.8), cells: (20, 16)),
        time: (end: 1.0, step: Fixed(1e-5), output_every: 1.0),
        gravity: (0.0, 0.0),
        walls: (left: Free, right: Free, bottom: Free, top: Free),
        integration: {integration},
        transfer: Apic,
        bodies: [(
            name: "body",
            shape: {shape},
            material: LinearElastic(density: 1000.0, youngs_modulus: 1e6, poisson_ratio: 0.3),
        )],
    )"#
    ))
    .unwrap();
    Simulation::new(&scene)
}

/// The grid momentum of one step (stress free, no gravity: the scatter's).
fn grid_momentum(sim: &mut Simulation) -> DVec2 {
    sim.step().unwrap();
    sim.grid_field("body").unwrap().momentum.iter().sum()
}

/// One step of a stress-free body without gravity: the grid momentum after the step is the
/// scatter's, which must carry the points' momentum and APIC angular momentum.
#[test]
fn the_scatter_conserves_momentum_and_angular_momentum() {
    for integration in ["CpdiFixed", "Linear", "QuadraticBspline"] {
        let mut sim = scatter_scene(integration, "Disc(centre: (0.2, 0.5), radius: 0.25)");
        let grid = sim.grid().clone();
        let mut rng = Rng(0xdead_beef_cafe_f00d);
        let (mut momentum, mut angular) = (DVec2::ZERO, 0.0);
        {
            let mut p = sim.points_mut("body").unwrap();
            for k in 0..p.len() {
                p.velocity[k] = rng.vec();
                p.affine[k] = DMat2::from_cols(rng.vec(), rng.vec()) * 10.0;
                let (x, m, v, c) = (p.position[k], p.mass[k], p.velocity[k], p.affine[k]);
                let f = match integration {
                    "Linear" => Footprint::new::<Linear>(&grid, x, p.half_width[k]),
                    "QuadraticBspline" => {
                        Footprint::new::<QuadraticBspline>(&grid, x, p.half_width[k])
                    }
                    _ => Footprint::new::<CpdiFixed>(&grid, x, p.half_width[k]),
                };
                momentum += m * v;
                angular += point_angular_momentum(&f, &grid, x, m, v, c);
            }
        }
        let on_grid = grid_momentum(&mut sim);
        let nodes = node_positions(&grid);
        let field = sim.grid_field("body").unwrap();
        let on_grid_angular: f64 = nodes
            .iter()
            .zip(&field.momentum)
            .map(|(x, p)| x.perp_dot(*p))
            .sum();
        assert!(
            (on_grid - momentum).length() < 1e-12 * momentum.length().max(1.0),
            "{integration}: momentum {on_grid} vs {momentum}"
        );
        assert!(
            (on_grid_angular - angular).abs() < 1e-11 * angular.abs().max(1.0),
            "{integration}: angular momentum {on_grid_angular} vs {angular}"
        );
    }
}

/// Points pressed against the domain's corner, so that CPDI clips their extents at the
/// edge: the scatter still hands the grid exactly their momentum. (Measured from the point
/// instead of its weighted centre, the affine term created momentum at every step there,
/// and the coarse impact's bed climbed its side walls until it blew up.)
#[test]
fn the_scatter_conserves_momentum_next_to_a_wall() {
    for integration in ["CpdiFixed", "Linear", "QuadraticBspline"] {
        let mut sim = scatter_scene(integration, "Rectangle(min: (-0.3, 0.1), max: (-0.1, 0.3))");
        let mut rng = Rng(0x0123_4567_89ab_cdef);
        let mut momentum = DVec2::ZERO;
        {
            let mut p = sim.points_mut("body").unwrap();
            for k in 0..p.len() {
                let shift = 0.9 * p.half_width[k] * 0.5 * (rng.vec() + DVec2::ONE);
                p.position[k] -= shift;
                p.velocity[k] = rng.vec();
                p.affine[k] = DMat2::from_cols(rng.vec(), rng.vec()) * 10.0;
                momentum += p.mass[k] * p.velocity[k];
            }
        }
        let on_grid = grid_momentum(&mut sim);
        assert!(
            (on_grid - momentum).length() < 1e-12 * momentum.length().max(1.0),
            "{integration}: momentum {on_grid} vs {momentum}"
        );
    }
}
