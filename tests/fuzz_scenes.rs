//! Fuzzing the scene parser and the `--set` editor: no input makes them panic.
//!
//! Inputs are mutations of the shipped scenes (cut, duplicated, spliced and overwritten
//! spans, random bytes) and random `--set` assignments. The default case count keeps CI
//! fast; the long run recorded in docs/ROBUSTNESS.md sets PROPTEST_CASES.

use proptest::prelude::*;
use regolith::Regolith;
use regolith::scene::Scene;

fn shipped() -> Vec<String> {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut texts: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.path().extension().is_some_and(|x| x == "ron"))
        .map(|e| std::fs::read_to_string(e.path()).unwrap())
        .collect();
    texts.sort();
    texts
}

/// One edit of a text: (kind, position, length, replacement).
fn edit() -> impl Strategy<Value = (u8, f64, usize, String)> {
    (
        0u8..5,
        0.0f64..1.0,
        0usize..40,
        "[ -~\\n]{0,12}|[(){}\\[\\]:,\"]{1,4}|-?[0-9.e]{1,8}",
    )
}

fn apply(text: &str, (kind, at, len, with): &(u8, f64, usize, String)) -> String {
    let bytes = text.as_bytes();
    let i = ((bytes.len() as f64) * at) as usize;
    let j = (i + len).min(bytes.len());
    let mut out = Vec::from(&bytes[..i]);
    match kind {
        0 => {}                                      // cut
        1 => out.extend_from_slice(&bytes[i..j]),    // duplicate
        2 => out.extend_from_slice(with.as_bytes()), // overwrite
        3 => {
            // insert
            out.extend_from_slice(with.as_bytes());
            out.extend_from_slice(&bytes[i..j]);
        }
        _ => out.extend_from_slice(&bytes[j..(j + len).min(bytes.len())]), // splice
    }
    out.extend_from_slice(&bytes[j..]);
    String::from_utf8_lossy(&out).into_owned()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(1500))]

    #[test]
    fn mutated_scenes_never_panic(which in 0usize..64, edits in prop::collection::vec(edit(), 1..4)) {
        let texts = shipped();
        let mut text = texts[which % texts.len()].clone();
        for e in &edits {
            text = apply(&text, e);
        }
        let registries = Regolith::default().registries();
        let _ = Scene::parse(&text, "fuzz.ron", &registries);
    }

    #[test]
    fn random_overrides_never_panic(which in 0usize..64, path in "[a-z_.0-9]{0,30}", value in "[ -~]{0,20}") {
        let texts = shipped();
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("s.ron");
        std::fs::write(&file, &texts[which % texts.len()]).unwrap();
        let registries = Regolith::default().registries();
        let _ = Scene::load(&file, &[format!("{path}={value}")], &registries);
    }

    #[test]
    fn random_text_never_panics(text in "\\PC{0,200}") {
        let registries = Regolith::default().registries();
        let _ = Scene::parse(&text, "fuzz.ron", &registries);
    }
}

/// One choice from each list (by index, wrapping), so proptest shrinks toward the first.
fn pick<'a>(from: &[&'a str], k: usize) -> &'a str {
    from[k % from.len()]
}

/// Mostly one of `valid`, one time in eight one of `invalid` (which `check` must refuse), so
/// that most assembled scenes run rather than being refused for their first fault.
fn choose<'a>(valid: &[&'a str], invalid: &[&'a str], k: usize) -> &'a str {
    if k % 8 == 7 && !invalid.is_empty() {
        pick(invalid, k / 8)
    } else {
        pick(valid, k / 8)
    }
}

/// A small scene (a granular or elastic bed and a disc, 4 to 16 by 4 to 40 cells) assembled
/// from items chosen by `k`: walls (periodic in x, in y, in both), cell counts, schemes,
/// transfer, contact law, materials, outputs (some listed twice or naming a missing body), a
/// preset, and `--set` overrides, each now and then an invalid one. Only a few steps long,
/// so that running it is cheap.
fn semantic_scene(k: &[usize]) -> (String, Vec<String>) {
    const SIDE: [&str; 4] = ["Free", "Open", "Slip", "NoSlip"];
    let (left, right) = if k[0] % 8 == 7 {
        (pick(&SIDE, k[1]), "Periodic")
    } else if k[0].is_multiple_of(2) {
        ("Periodic", "Periodic")
    } else {
        (pick(&SIDE, k[1]), pick(&SIDE, k[1] / 4))
    };
    let (bottom, top) = if k[22] % 8 == 7 {
        ("Periodic", pick(&SIDE, k[3]))
    } else if k[22].is_multiple_of(3) {
        ("Periodic", "Periodic")
    } else {
        (pick(&SIDE, k[2]), pick(&SIDE, k[3]))
    };
    let walls = format!("(left: {left}, right: {right}, bottom: {bottom}, top: {top})");
    // Square cells of 25 mm, 4 to 16 across and 4 to 40 high; the bed fills the lower half,
    // the disc sits above it.
    let (nx, ny) = (4 + k[23] % 13, 4 + k[24] % 37);
    let (w, h) = (0.025 * nx as f64, 0.025 * ny as f64);
    let radius = 0.2 * w.min(h);
    let integration = pick(&["CpdiFixed", "Linear", "QuadraticBspline"], k[4]);
    let update = pick(&["Usl", "Musl"], k[5]);
    let dilatation = pick(&["CellAveraged", "PerPoint"], k[6]);
    let transfer = choose(
        &[
            "AffineFlip(relaxation: 25)",
            "Flip",
            "Apic",
            "AffineFlip(relaxation: 0.5)",
        ],
        &["AffineFlip(relaxation: 0)", "AffineFlip(relaxation: -2)"],
        k[7],
    );
    let flip = match (transfer, k[8] % 8) {
        ("Flip", 0..=3) => "flip: 0.95,",
        (_, 7) => pick(&["flip: 1.5,", "flip: 0.95,"], k[8] / 8),
        _ => "",
    };
    let contact = choose(
        &[
            "NoSlip",
            "Frictional(friction: 0.1)",
            "Frictional(friction: 0.0, normal: Body(\"disc\"))",
            "Frictional(friction: 0.3, normal: Body(\"bed\"))",
        ],
        &["Frictional(friction: 0.1, normal: Body(\"nobody\"))"],
        k[9],
    );
    let bed = pick(
        &[
            "MuI(youngs_modulus: 2.0e7, poisson_ratio: 0.45, grain_density: 1280.0, \
             packing_fraction: 0.79, grain_diameter: 5.0e-3, mu_s: 0.32, mu_2: 0.598, i_0: 0.278)",
            "DruckerPrager(youngs_modulus: 2.0e7, poisson_ratio: 0.45, grain_density: 1280.0, \
             packing_fraction: 0.79, mu_s: 0.32)",
            "LinearElastic(density: 1011.2, youngs_modulus: 2.0e7, poisson_ratio: 0.45)",
        ],
        k[10],
    );
    let stress = pick(&["Lithostatic", "None"], k[11]);
    let tracked = choose(&["true"], &["false"], k[12]);
    let outputs: Vec<&str> = (0..k[13] % 4)
        .map(|i| {
            choose(
                &[
                    "Impact(body: \"disc\", surface: 0.1)",
                    "Snapshots(every: 1e-5)",
                    "Snapshots(at: [0.0, 2e-5])",
                    "FreeSurface(body: \"bed\", every: 1e-5)",
                    "PressureFront(body: \"bed\", centre: (0.1, 0.1), radius: 0.1, bins: 4, \
                     every: 1e-5)",
                    "FlowField(body: \"bed\", intruder: \"disc\", scale: 0.04, at: [1e-5])",
                ],
                &[
                    "Impact(body: \"nobody\", surface: 0.1)",
                    "FreeSurface(body: \"nobody\", every: 1e-5)",
                ],
                k[14 + i],
            )
        })
        .collect();
    let preset = pick(
        &["", "preset: Fast,", "preset: Accurate,", "preset: Fine,"],
        k[18],
    );
    let text = format!(
        r#"(
    name: "semantic",
    domain: (size: ({w}, {h}), cells: ({nx}, {ny})),
    time: (end: 4e-5, step: Cfl(0.5), output_every: 1e-5),
    walls: {walls},
    integration: {integration},
    update: {update},
    dilatation: {dilatation},
    transfer: {transfer},
    {flip}
    contact: {contact},
    {preset}
    bodies: [
        (name: "bed", shape: Rectangle(min: (0.0, 0.0), max: ({w}, {bed_top})), material: {bed},
         initial_stress: {stress}),
        (name: "disc", shape: Disc(centre: ({half}, {disc_y}), radius: {radius}),
         material: LinearElastic(density: 6500.0, youngs_modulus: 4.0e7, poisson_ratio: 0.45),
         velocity: (0.0, -3.0), tracked: {tracked}),
    ],
    outputs: [{outputs}],
)"#,
        outputs = outputs.join(", "),
        bed_top = 0.5 * h,
        half = 0.5 * w,
        disc_y = 0.5 * h + 1.25 * radius,
    );
    // The same cell counts over twice the domain: cells twice as large.
    let coarse = format!("domain.size=({}, {})", 2.0 * w, 2.0 * h);
    let sets = (0..k[19] % 3)
        .map(|i| {
            choose(
                &[
                    "gravity=(0.0, 0.0)",
                    "bodies.disc.velocity=(0.0, -300.0)",
                    "bodies.bed.points_per_cell=1",
                    "time.step=Fixed(1e-6)",
                    &coarse,
                    "limits=(max_kinetic_energy: 1e-9)",
                ],
                &[
                    "time.step=Cfl(3.0)",
                    "bodies.disc.shape=Disc(centre: (0.1, 0.05), radius: 0.02)",
                ],
                k[20 + i],
            )
            .to_string()
        })
        .collect();
    (text, sets)
}

/// The run's status and each body's `state_hash`, from its summary.
fn outcome(dir: &std::path::Path) -> (String, Vec<String>) {
    let text = std::fs::read_to_string(dir.join("summary.json")).unwrap();
    let s: serde_json::Value = serde_json::from_str(&text).unwrap();
    let hashes = s["bodies"].as_array().unwrap().iter();
    let hashes = hashes.map(|b| b["state_hash"].as_str().unwrap().to_string());
    (s["status"].as_str().unwrap().to_string(), hashes.collect())
}

/// Loads and, if accepted, runs one assembled scene on 1 to 4 threads; returns whether it
/// ran. One run in three is also run on one thread uninterrupted, while the drawn one is
/// interrupted after a drawn step and resumed: both must end in the same state, bit for bit.
fn load_and_run(k: &[usize]) -> bool {
    let (text, sets) = semantic_scene(k);
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("semantic.ron");
    std::fs::write(&file, &text).unwrap();
    let registries = Regolith::default().registries();
    let Ok((scene, resolved)) = Scene::load(&file, &sets, &registries) else {
        return false;
    };
    let from = regolith::run::Provenance {
        file: "semantic.ron",
        text: &resolved,
        overrides: &sets,
    };
    let run = |threads: usize, out: &std::path::Path, stop: Option<u64>| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| match stop {
            None => regolith::run::run_scene(
                &scene,
                &from,
                out,
                regolith::run::CheckpointEvery(Some(2)),
                &mut |_: &regolith::sim::Clock| {},
            ),
            Some(at) => regolith::run::run_scene(
                &scene,
                &from,
                out,
                regolith::run::CheckpointEvery(None),
                &mut regolith::run::StopAfter(at),
            ),
        })
    };
    let threads = 1 + k[25] % 4;
    let out = dir.path().join("out");
    if !k[26].is_multiple_of(3) {
        let _ = run(threads, &out, None);
        return true;
    }
    let straight = dir.path().join("straight");
    let _ = run(1, &straight, None);
    let at = 1 + (k[26] / 3) as u64 % 4;
    if let Err(regolith::error::Error::Interrupted { .. }) = run(threads, &out, Some(at)) {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let _ = pool.install(|| {
            regolith::run::resume_run(
                &registries,
                &out,
                regolith::run::CheckpointEvery(None),
                |_| Ok(()),
                &mut |_: &regolith::sim::Clock| {},
            )
        });
    }
    assert_eq!(
        outcome(&out),
        outcome(&straight),
        "{text}\n{sets:?}: {threads} threads, interrupted after step {at} and resumed, against one thread straight"
    );
    true
}

/// Valid items in random combinations: each scene is refused with a message, or it runs (to
/// its end or to a fault with a summary); none panics. A share of them must run, or the test
/// would only exercise the refusals.
#[test]
fn valid_items_in_any_combination_run_or_are_refused() {
    use proptest::test_runner::{Config, TestRunner};
    // 150 in CI; PROPTEST_CASES sets the long run (docs/ROBUSTNESS.md).
    let cases = std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(150);
    let mut runner = TestRunner::new(Config::with_cases(cases));
    let ran = std::cell::Cell::new(0u32);
    runner
        .run(&prop::collection::vec(0usize..64, 27), |k| {
            ran.set(ran.get() + u32::from(load_and_run(&k)));
            Ok(())
        })
        .unwrap();
    eprintln!(
        "{} of {cases} assembled scenes ran, the others were refused",
        ran.get()
    );
    assert!(
        ran.get() >= cases / 5,
        "only {} of {cases} scenes ran",
        ran.get()
    );
}
