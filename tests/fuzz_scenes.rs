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
