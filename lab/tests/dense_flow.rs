//! Dense granular flow, long enough to see a layer lose its state.
//!
//! The failures these guard against take seconds of simulated time: with the FLIP transfer
//! (the default until 2026-12-02) the chute layer packed into 57% of its height within 5 s while its point
//! volumes still said `rho = rho_c`, and most of it disconnected (docs/numerics.md,
//! "Dense flow"). A test of a few hundred steps cannot see that; these run 10^5 steps and
//! more on a coarse grid (10 cells per depth; the resolution study is in
//! docs/VALIDATION.md, `cargo run --release -p regolith-lab --example dense_flow`).
//!
//! They run with `transfer: Apic`, which holds these flows (but one, at 20 degrees at the
//! default settings, which hold the chute there too); with FLIP the steady-flow test fails
//! within 1 s, and with the default affine FLIP within about 5 s (the cell-averaged
//! dilatation's sub-cell modes grow under a FLIP-type update: docs/numerics.md, "What breaks
//! the chute"). APIC is not the default because its per-step projection makes the impact
//! and the collapses depend on the time step; until one setting does both, these tests say
//! which transfer holds a dense flow, and the issue stays open.

use regolith_lab::verify::chute::{
    Bagnold, ChuteState, DEPTH, Disturbance, Steady, least_acceleration, ps1, run,
};

/// The shipped `MuI` chute scene, `scenes/chute_flow_mui.ron`.
fn chute_scene() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/chute_flow_mui.ron")
}

/// The shipped chute scene at `deg` degrees with 10 mm cells (10 per depth) and APIC, run
/// for `end` seconds from the lithostatic state, moving with `profile` if given; `each`
/// sees the measures at t = 0, every 0.25 s and at the end. Returns the steps.
fn run_chute(
    deg: f64,
    end: f64,
    profile: Option<&dyn Steady>,
    each: impl FnMut(f64, &ChuteState),
) -> u64 {
    run_chute_with(deg, end, &["transfer=Apic".to_string()], profile, each)
}

/// As `run_chute`, with `sets` instead of APIC (none: the default numerical settings).
fn run_chute_with(
    deg: f64,
    end: f64,
    sets: &[String],
    profile: Option<&dyn Steady>,
    each: impl FnMut(f64, &ChuteState),
) -> u64 {
    run(
        &chute_scene(),
        deg,
        10,
        end,
        sets,
        profile,
        None,
        0.25,
        each,
    )
    .unwrap_or_else(|e| panic!("{e}"))
}

/// 25 degrees, between atan(mu_s) and atan(mu_2): started on the analytic profile the layer
/// stays on it for 5 s (2.7 10^5 steps), keeps its depth within 1%, its summed point volume
/// equal to the area it occupies within 1%, and no point below the surface cells
/// disconnects. With FLIP 42% of the bulk is disconnected at 1 s.
#[test]
fn a_steady_chute_flow_stays_steady_and_dense() {
    let profile = Bagnold::new(&ps1(), 25f64.to_radians(), DEPTH, 9.81).unwrap();
    let mut worst_error: f64 = 0.0;
    let steps = run_chute(25.0, 5.0, Some(&profile), |t, m| {
        assert!(
            (m.top / DEPTH - 1.0).abs() < 0.01,
            "t = {t:.2} s: top at {:.4} m",
            m.top
        );
        assert!(
            (m.volume_ratio - 1.0).abs() < 0.01,
            "t = {t:.2} s: sum V / area = {:.4}",
            m.volume_ratio
        );
        assert_eq!(
            m.disconnected_bulk, 0.0,
            "t = {t:.2} s: bulk points disconnected"
        );
        worst_error = worst_error.max(m.profile_error.unwrap());
    });
    assert!(steps > 100_000, "{steps} steps");
    assert!(
        worst_error < 0.05,
        "profile rms error {worst_error:.3} of u_s"
    );
}

/// MuI's envelope at the default transfer (docs/VALIDATION.md, "NGF stage 2", item 4): at 20
/// degrees the chute holds 20 s, at 25 it opens after about 4 s. What tells them apart
/// early is the grid-scale mode normal to the bed, which grows from round-off: at 20 degrees
/// at about 0.5 per second (1.2e-15 m/s at 4 s), at 25 at about 6 per second (2.0e-6 m/s at
/// 4 s; the layer opens once it reaches about 1e-4). So, for 3 s at 20 degrees at the
/// default settings (under a minute in CI): the layer keeps its depth, its volume, its dense
/// state and its Bagnold profile within 1%, and the mode stays below 1e-12 m/s. The same
/// run at 25 degrees fails, its mode at 5.2e-10 m/s.
#[test]
fn at_20_degrees_the_default_transfer_holds_the_chute() {
    let profile = Bagnold::new(&ps1(), 20f64.to_radians(), DEPTH, 9.81).unwrap();
    let mut worst_error: f64 = 0.0;
    let mut worst_mode: f64 = 0.0;
    run_chute_with(20.0, 3.0, &[], Some(&profile), |t, m| {
        assert!(
            (m.top / DEPTH - 1.0).abs() < 0.01 && (m.volume_ratio - 1.0).abs() < 0.01,
            "t = {t:.2} s: top at {:.4} m, sum V / area = {:.4}",
            m.top,
            m.volume_ratio
        );
        assert_eq!(m.disconnected, 0.0, "t = {t:.2} s: points disconnected");
        worst_error = worst_error.max(m.profile_error.unwrap());
        worst_mode = worst_mode.max(m.modes.grid_scale);
    });
    assert!(
        worst_error < 0.01,
        "profile rms error {worst_error:.4} of u_s"
    );
    assert!(
        worst_mode < 1e-12,
        "grid-scale mode reached {worst_mode:.1e} m/s"
    );
}

/// 15 degrees, below atan(mu_s) = 17.7: a layer thrown down the slope at the 25-degree
/// profile (mean speed 2.07 m/s) stops and stays dense. The base resists at least
/// `mu_s p`, so the layer slows at least at `g (mu_s cos th - sin th) = 0.49 m/s^2`:
/// stopped within 4.2 s; the test looks at 6 s.
#[test]
fn below_the_static_friction_angle_the_layer_stops() {
    let thrown = Bagnold::new(&ps1(), 25f64.to_radians(), DEPTH, 9.81).unwrap();
    let mut last = ChuteState::default();
    run_chute(15.0, 6.0, Some(&thrown), |_, m| last = *m);
    assert!(
        last.speed_95 < 0.01,
        "95% of the points slower than {} m/s",
        last.speed_95
    );
    assert!(
        last.disconnected < 0.05,
        "{} disconnected",
        last.disconnected
    );
    assert!(
        (last.top / DEPTH - 1.0).abs() < 0.01,
        "top at {:.4} m",
        last.top
    );
}

/// 35 degrees, above atan(mu_2) = 30.9: no steady state; the base resists at most mu_2 p,
/// so the layer's mean speed grows at least at g (sin th - mu_2 cos th) = 0.82 m/s^2.
#[test]
fn above_the_dynamic_friction_angle_the_layer_accelerates() {
    let th = 35f64.to_radians();
    let mut speeds = Vec::new();
    run_chute(35.0, 2.0, None, |t, m| speeds.push((t, m.mean_speed)));
    let bound = least_acceleration(&ps1(), th, 9.81);
    for w in speeds.windows(2).skip(1) {
        let rate = (w[1].1 - w[0].1) / (w[1].0 - w[0].0);
        assert!(
            rate > bound,
            "mean speed grew at {rate:.3} m/s^2 at t = {:.2} s (at least {bound:.3})",
            w[1].0
        );
    }
}

/// The grid-modes issue's measure: a periodic layer four cells long (it admits a wavelength
/// of two cells) at 25 degrees, started in its steady state with a normal-velocity
/// disturbance of 1e-4 m/s and a wavelength of two cells, run for 2 s with the transfer
/// `transfer`; returns the grid-scale amplitude at the start, at 1 s and at 2 s.
fn seeded_two_cell_mode(transfer: &str) -> [f64; 3] {
    let profile = Bagnold::new(&ps1(), 25f64.to_radians(), DEPTH, 9.81).unwrap();
    let sets = [
        format!("transfer={transfer}"),
        "domain.size=(0.04, 0.15)".into(),
        "domain.cells=(4, 15)".into(),
        "bodies.layer.shape=Rectangle(min: (0.0, 0.0), max: (0.04, 0.1))".into(),
    ];
    let seed = Disturbance {
        amplitude: 1e-4,
        cells: 2.0,
    };
    let mut amplitudes = Vec::new();
    run(
        &chute_scene(),
        25.0,
        10,
        2.0,
        &sets,
        Some(&profile),
        Some(seed),
        1.0,
        |_, m| {
            assert_eq!(m.modes.grid_scale_cells, 2.0);
            amplitudes.push(m.modes.grid_scale);
        },
    )
    .unwrap_or_else(|e| panic!("{e}"));
    amplitudes.try_into().expect("measured at 0, 1 and 2 s")
}

/// With APIC the seeded two-cell mode is gone within a step's projection and stays gone:
/// the measure sees a decay (7e-5 m/s to 1e-16), so the test below can pass.
#[test]
fn apic_removes_a_seeded_two_cell_mode() {
    let [start, one, two] = seeded_two_cell_mode("Apic");
    assert!(start > 5e-5, "seeded amplitude {start:.1e} m/s");
    assert!(
        one < 1e-3 * start && two < 1e-3 * start,
        "two-cell mode {start:.1e} -> {one:.1e} -> {two:.1e} m/s"
    );
}

/// The grid-modes issue's acceptance test: at the default transfer a seeded two-cell mode
/// must decay. It does not yet: after a fast initial decay it grows at 4-13 per second
/// (7.1e-5 m/s at the start, 1.1e-5 at 1 s, 3.4e-4 at 2 s; docs/numerics.md, "A measure of
/// the modes"). `cargo test --release -p regolith-lab --test dense_flow -- --ignored`.
#[test]
#[ignore = "issue 60: the default transfer lets the two-cell mode grow"]
fn the_default_transfer_damps_a_seeded_two_cell_mode() {
    let [start, one, two] = seeded_two_cell_mode("AffineFlip(relaxation: 25)");
    assert!(
        two < 0.1 * start && two < one,
        "two-cell mode {start:.1e} -> {one:.1e} -> {two:.1e} m/s"
    );
}
