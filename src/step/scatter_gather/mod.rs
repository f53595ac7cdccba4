//! Particle-to-grid scatter and grid-to-particle gather (docs/model.md §2, steps 2, 5 and 6).
//!
//! Each body scatters only to its own nodal field and gathers only from it; bodies meet
//! through the Contact set. The gathers are parallel over points; the scatter is parallel
//! over bands of cell rows without locks (`bands`).
//!
//! USL gathers velocity, acceleration and velocity gradient in one pass. MUSL splits it:
//! the velocity pass updates `v_p` and keeps the advection velocity, the remap scatters the
//! new `m_p v_p` back to the grid, and the gradient pass takes `L` from those remapped nodal
//! velocities, which are weighted averages of point velocities and so stay bounded at nodes
//! of tiny mass. Either way the points move (and their volumes change) in a last pass,
//! after the optional cell averaging of the dilatation (`dilatation`).

mod advect;
mod gather;
mod musl;
mod scatter;

pub(crate) use advect::kept_box;
pub use advect::{advect_points, point_density};
pub use gather::{VelocityUpdate, affine_to_particle, apic_gather, grid_to_particle};
pub use musl::{musl_apic_gradient, musl_gradient, musl_remap, musl_velocity};
pub use scatter::particle_to_grid;
