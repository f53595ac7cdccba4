//! Numerical presets: what each sets, relative to the scene as written, and that an
//! explicit `--set` wins over the preset.

use regolith::scene::{Preset, TimeStep};

#[test]
fn presets_set_the_studied_knobs_relative_to_the_scene() {
    let written = crate::common::scene("impact_tipped", &[]);
    assert_eq!(written.domain.cells, (100, 100));
    let cases = [
        ("Fast", (50, 50), 2, 0.5),
        ("Accurate", (100, 100), 2, 0.5),
        ("Fine", (100, 100), 3, 0.2),
        ("Paper", (100, 100), 2, 0.09),
    ];
    for (name, cells, points, cfl) in cases {
        let s = crate::common::scene(
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
    let s = crate::common::scene("impact_tipped", &["preset=Fast", "domain.cells=(80, 80)"]);
    assert_eq!(s.domain.cells, (80, 80));
}

/// `Fast` halves the cells per axis: a scene with an odd count cannot keep square cells, so
/// it is refused at the preset's line with what to do (it was refused as "cells must be
/// square", with overrides the user never wrote), unless the command line gives the grid.
#[test]
fn fast_refuses_an_odd_cell_count_unless_the_grid_is_given() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("odd.ron");
    let text = std::fs::read_to_string(crate::common::scene_path("impact_tipped_coarse")).unwrap();
    let odd = text.replace("cells: (50, 50)", "cells: (51, 51)");
    assert_ne!(odd, text);
    let odd = odd.replace("    domain:", "    preset: Fast,\n    domain:");
    std::fs::write(&file, &odd).unwrap();
    let registries = regolith::Regolith::default().registries();
    let e = regolith::Scene::load(&file, &[], &registries).unwrap_err();
    let line = odd
        .lines()
        .position(|l| l.contains("preset: Fast"))
        .unwrap()
        + 1;
    assert_eq!(e.line, Some(line), "{e}");
    assert!(
        e.message.contains("51 x 51 cells") && e.message.contains("even domain.cells"),
        "{e}"
    );
    let sets = ["domain.cells=(41, 41)".to_string()];
    let (s, _) = regolith::Scene::load(&file, &sets, &registries).unwrap();
    assert_eq!(s.domain.cells, (41, 41));
    assert_eq!(s.bodies[0].points_per_cell, 2);
}
