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

    /// The `--set` overrides that apply the preset to `scene`, or why it cannot: `Fast`
    /// halves the cells per axis, which keeps them square only when both counts are even.
    /// With `grid_given` (the command line sets the grid, which wins anyway) the preset
    /// leaves the cells alone.
    pub fn overrides(self, scene: &Scene, grid_given: bool) -> Result<Vec<String>, String> {
        let (nx, ny) = scene.domain.cells;
        if self == Preset::Fast && !grid_given && !(nx.is_multiple_of(2) && ny.is_multiple_of(2)) {
            return Err(format!(
                "preset Fast halves the cells per axis, which keeps them square only for even \
                 counts, and this scene has {nx} x {ny} cells: give even domain.cells, or use \
                 preset Accurate"
            ));
        }
        let ((nx, ny), points, cfl) = match self {
            Preset::Fast => ((nx / 2, ny / 2), 2, 0.5),
            Preset::Accurate => ((nx, ny), 2, 0.5),
            Preset::Fine => ((nx, ny), 3, 0.2),
            Preset::Paper => ((nx, ny), 2, 0.09),
        };
        let mut sets = vec![
            "integration=CpdiFixed".to_string(),
            format!("time.step=Cfl({cfl})"),
        ];
        if !grid_given {
            sets.insert(0, format!("domain.cells=({nx}, {ny})"));
        }
        sets.extend(
            scene
                .bodies
                .iter()
                .map(|b| format!("bodies.{}.points_per_cell={points}", b.name)),
        );
        Ok(sets)
    }
}
