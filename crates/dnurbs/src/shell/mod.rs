//! The isogeometric Kirchhoff–Love shell (Kiendl, Bletzinger, Linhard, Wüchner 2009): a
//! physical D-NURBS energy over the same control points (docs/math.md §10).

mod energy;
mod kinematics;
mod material;

pub use energy::ShellEnergy;
pub use material::ShellMaterial;
