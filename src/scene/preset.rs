//! Numerical presets: `preset: Fast | Accurate | Fine | Paper` in any scene (or `--preset`).
//! The first three are placed by the speed-accuracy study `studies/impact_knobs.ron`
//! (docs/ACCURACY.md, rerun at the default affine FLIP transfer): `Accurate` and `Paper`
//! (the paper's own numerics, at five times `Accurate`'s cost) are on its frontier, `Fine` is
//! its reference, `Fast` is next to it (the frontier's CFL 1.0 at the same cells is at the
//! stability limit and closer only by an error cancellation).
//!
//! A preset sets the numerical knobs relative to the scene as written, so that a scene at
//! the paper's resolution gets the study's settings: `Fast` halves the cells per axis, and
//! all three set the points per cell of every body, the integration scheme and the time
//! step. It is applied as overrides before the command line's `--set`s, so an explicit
//! `--set` still wins over the preset.

use serde::{Deserialize, Serialize};

use super::Scene;

/// A named set of numerical settings.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize)]
pub enum Preset {
    /// Half the scene's cells per axis, 2 x 2 points per cell, CPDI, CFL 0.5.
    Fast,
    /// The scene's cells, 2 x 2 points per cell, CPDI, CFL 0.5.
    Accurate,
    /// The scene's cells, 3 x 3 points per cell, CPDI, CFL 0.2: the study's reference.
    Fine,
    /// The paper's numerics: the scene's cells, 2 x 2 points per cell, CPDI, CFL 0.09 (the
    /// paper's c dt / h for the impact).
    Paper,
}

impl Preset {
    /// The preset's name as the command line takes it.
    pub fn parse(name: &str) -> Option<Preset> {
        match name.to_ascii_lowercase().as_str() {
            "fast" => Some(Preset::Fast),
            "accurate" => Some(Preset::Accurate),
            "fine" => Some(Preset::Fine),
            "paper" => Some(Preset::Paper),
            _ => None,
        }
    }

    /// The `--set` overrides that apply the preset to `scene`.
    pub fn overrides(self, scene: &Scene) -> Vec<String> {
        let (nx, ny) = scene.domain.cells;
        let ((nx, ny), points, cfl) = match self {
            Preset::Fast => ((nx.div_ceil(2), ny.div_ceil(2)), 2, 0.5),
            Preset::Accurate => ((nx, ny), 2, 0.5),
            Preset::Fine => ((nx, ny), 3, 0.2),
            Preset::Paper => ((nx, ny), 2, 0.09),
        };
        let mut sets = vec![
            format!("domain.cells=({nx}, {ny})"),
            "integration=CpdiFixed".to_string(),
            format!("time.step=Cfl({cfl})"),
        ];
        sets.extend(
            scene
                .bodies
                .iter()
                .map(|b| format!("bodies.{}.points_per_cell={points}", b.name)),
        );
        sets
    }
}
