//! The authors' own impact against their own code (issue 37; docs/VALIDATION.md, "Against
//! the authors' code"): `scenes/authors_impact_coarse.ron` with their numerics where regolith
//! has them (pure FLIP, per-point dilatation; one velocity field, which `NoSlip` is) must
//! follow the depths their code gives on the same input, within 3%.
//!
//! The reference numbers below were made by their code (neocpp89/mpm-2d, branch
//! research-impact, commit 3ee06f1), built and run outside this repository on the same
//! points, masses, stresses and grid (50 x 50 cells, dt = 3 us), with its two shape-function
//! choices that regolith does not offer switched to regolith's: CPDI gradients in y as in x
//! (their snapshot takes the y gradient of plain linear MPM) and a point extent fixed at
//! the start (theirs follows the volume). Those two moved their depths by at most 3.5% on
//! this grid (their unmodified code: 0.0893 / 0.1197 / 0.1283 / 0.1339 m at 3 m/s,
//! 0.1288 / 0.1689 / 0.1782 / 0.1857 m at 5 m/s); the docs list every difference and its
//! size. Depth is the intruder's centre of mass below its start, as their scripts take it.

use regolith::Simulation;

/// Times (s) at which the depths are compared.
const TIMES: [f64; 4] = [0.05, 0.10, 0.15, 0.20];

/// Their code's depths (m) at [`TIMES`], matched numerics, at 3 and 5 m/s.
const THEIRS: [(f64, [f64; 4]); 2] = [
    (3.0, [0.088722, 0.119501, 0.132833, 0.137830]),
    (5.0, [0.126795, 0.165697, 0.179784, 0.185947]),
];

/// The intruder's depth at [`TIMES`] in regolith, with their numerics, at `speed`.
fn depths(speed: f64) -> [f64; 4] {
    let velocity = format!("bodies.intruder.velocity=(0.0, -{speed})");
    let scene = crate::common::scene(
        "authors_impact_coarse",
        &["transfer=Flip", "dilatation=PerPoint", &velocity],
    );
    let mut sim = Simulation::new(&scene);
    sim.run(|_| {})
        .unwrap_or_else(|e| panic!("the authors' impact at {speed} m/s: {e}"));
    let tr = sim.trajectory();
    let t = tr.series(0);
    let depth = tr.series(tr.column("intruder", "depth").unwrap());
    TIMES.map(|at| {
        let k = (0..t.len())
            .min_by(|&a, &b| (t[a] - at).abs().total_cmp(&(t[b] - at).abs()))
            .unwrap();
        assert!((t[k] - at).abs() < 1e-3, "no record near {at} s");
        depth[k]
    })
}

/// Within 3% of their code at every compared time, at both speeds. Measured: -0.8% to
/// -1.3% at 3 m/s, -0.6% to -1.5% at 5 m/s.
#[test]
fn the_authors_impact_follows_their_code() {
    for (speed, theirs) in THEIRS {
        let ours = depths(speed);
        eprintln!("{speed} m/s: regolith {ours:.4?}, their code {theirs:.4?}");
        for ((at, o), t) in TIMES.iter().zip(ours).zip(theirs) {
            assert!(
                (o - t).abs() < 0.03 * t,
                "{speed} m/s at {at} s: regolith {o:.4} m, their code {t:.4} m ({:+.1}%)",
                100.0 * (o / t - 1.0)
            );
        }
    }
}
