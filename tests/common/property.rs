//! The one place where the property tests' draws are set (issue 58).
//!
//! proptest draws a new seed on every run unless told otherwise, so a test whose verdict
//! hangs on rare inputs passed or failed by chance, and a failure found could not be
//! replayed. Every property test the workspace runs takes its `Config` from [`config`]: a
//! fixed seed, so the same tree draws the same cases and gives the same verdict and counts.
//!
//! - `PROPTEST_RNG_SEED=N` draws another set (the long randomised runs of
//!   docs/ROBUSTNESS.md); the seed is printed, and the same variable replays it.
//! - `PROPTEST_CASES=N` draws more (or fewer) cases.
//! - A failing case is saved in `tests/<file>.proptest-regressions` beside the test's
//!   source (commit it) and replayed before the drawn cases on every later run.
//!
//! Included by path from the plugins' tests, so it uses nothing but proptest.
#![allow(dead_code)]

use proptest::test_runner::{Config, FileFailurePersistence, RngSeed, contextualize_config};

/// The seed every property test draws from when `PROPTEST_RNG_SEED` is not set.
pub const SEED: u64 = 58;

/// `cases` cases drawn from [`SEED`] (or the environment's seed and count), with failures
/// kept beside `source` (the test file, `file!()`). Prints the seed and count it uses, so a
/// failure seen in any log can be replayed.
pub fn config(cases: u32, source: &'static str) -> Config {
    let config = contextualize_config(Config {
        cases,
        rng_seed: RngSeed::Fixed(SEED),
        source_file: Some(source),
        failure_persistence: Some(Box::new(FileFailurePersistence::WithSource(
            "proptest-regressions",
        ))),
        ..Config::default()
    });
    let (cases, seed) = (config.cases, config.rng_seed);
    eprintln!(
        "proptest: {cases} cases from seed {seed} (replay: PROPTEST_RNG_SEED={seed} \
         PROPTEST_CASES={cases})"
    );
    config
}
