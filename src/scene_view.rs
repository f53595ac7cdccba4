//! What a scene item (an output, a condition) sees of the scene it is checked against: the
//! bodies, as the scene file describes them, and the grid.
//!
//! The scene holds its items, so an item's check cannot name the scene without the two
//! importing each other; it names this view instead, which stands below the items. The
//! scene builds it (`Scene::view` is the one way in) once it is parsed.

use glam::DVec2;
use serde::Deserialize;

use crate::geometry::Shape;
use crate::grid::GridGeometry;
use crate::material::MaterialSpec;
use crate::registry::Named;

/// The bodies and the grid of a parsed scene, as an item's `check_scene` sees them.
pub struct SceneView<'a> {
    bodies: &'a [BodySpec],
    grid: GridGeometry,
}

impl<'a> SceneView<'a> {
    pub fn new(bodies: &'a [BodySpec], grid: GridGeometry) -> Self {
        SceneView { bodies, grid }
    }

    /// The body called `name`, or a message naming the scene's bodies: what an item that
    /// names a body checks.
    pub fn body(&self, name: &str) -> Result<&'a BodySpec, String> {
        body_named(self.bodies, name)
    }

    /// Every body, in the scene's order.
    pub fn bodies(&self) -> &'a [BodySpec] {
        self.bodies
    }

    /// The grid the scene's domain and walls describe.
    pub fn grid(&self) -> GridGeometry {
        self.grid.clone()
    }
}

/// The body called `name` among `bodies`, or a message naming them all (the scene's
/// `Scene::body` and the view's [`SceneView::body`]).
pub(crate) fn body_named<'a>(bodies: &'a [BodySpec], name: &str) -> Result<&'a BodySpec, String> {
    bodies.iter().find(|b| b.name == name).ok_or_else(|| {
        let names: Vec<String> = bodies.iter().map(|b| format!("\"{}\"", b.name)).collect();
        format!(
            "body \"{name}\" is not in the scene (its bodies: {})",
            names.join(", ")
        )
    })
}

/// One body.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BodySpec {
    pub name: String,
    pub shape: Named<dyn Shape>,
    pub material: Named<dyn MaterialSpec>,
    /// Material points per cell along each direction (2 gives the paper's 2x2 at quadrant
    /// centres); default 2.
    #[serde(default = "default_ppc")]
    pub points_per_cell: usize,
    /// Initial velocity (m/s); default zero.
    #[serde(default)]
    pub velocity: DVec2,
    /// Initial stress; default `None`.
    #[serde(default)]
    pub initial_stress: InitialStress,
    /// With `Lithostatic`: `T_xx = T_zz = k T_yy` with this `k` instead of the material's
    /// own ratio (1 for the granular materials, `nu / (1 - nu)` for `LinearElastic`). A
    /// free-standing column is in equilibrium with `k = 0`.
    #[serde(default)]
    pub lateral_stress_ratio: Option<f64>,
    /// Whether the body's centre of mass goes into `trajectory.csv`; default false.
    #[serde(default)]
    pub tracked: bool,
}

fn default_ppc() -> usize {
    2
}

/// How a body's stress starts.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
pub enum InitialStress {
    /// Stress free.
    #[default]
    None,
    /// In equilibrium under gravity (which must point along -y): `T_yy = -rho g (H - y)` below
    /// the body's top surface `H` at each x, lateral components from the material's ratio.
    Lithostatic,
}
