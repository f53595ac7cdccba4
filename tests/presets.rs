//! Numerical presets: what each sets, relative to the scene as written, and that an
//! explicit `--set` wins over the preset.

mod common;

use regolith::scene::{Preset, TimeStep};

#[test]
fn presets_set_the_studied_knobs_relative_to_the_scene() {
    let written = common::scene("impact_tipped", &[]);
    assert_eq!(written.domain.cells, (100, 100));
    let cases = [
        ("Fast", (50, 50), 2, 0.5),
        ("Accurate", (100, 100), 2, 0.5),
        ("Fine", (100, 100), 3, 0.2),
        ("Paper", (100, 100), 2, 0.09),
    ];
    for (name, cells, points, cfl) in cases {
        let s = common::scene(
            "impact_tipped",
            &[&format!("preset={name}"), "integration=Linear"],
        );
        assert_eq!(s.preset, Preset::parse(name));
        assert_eq!(s.domain.cells, cells, "{name}");
        assert!(
            s.bodies.iter().all(|b| b.points_per_cell == points),
            "{name}"
        );
        assert!(
            matches!(s.time.step, TimeStep::Cfl(c) if c == cfl),
            "{name}"
        );
        // The explicit override came after the preset's CpdiFixed and wins.
        assert_eq!(s.integration.name(), "Linear", "{name}");
    }
    // An explicit grid wins too.
    let s = common::scene("impact_tipped", &["preset=Fast", "domain.cells=(80, 80)"]);
    assert_eq!(s.domain.cells, (80, 80));
}
