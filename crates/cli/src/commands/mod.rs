//! One module per subcommand, and the flags several share.

pub mod check;
pub mod derive;
pub mod eval;
pub mod export;
pub mod import;
pub mod matrices;
pub mod modes;
pub mod paper;
pub mod refine;
pub mod simulate;
pub mod stability;
pub mod steady;

use clap::Args;
use nurbspring_msm::{Class, Constants, SpringKind};
use nurbspring_scene::MsmOverrides;
use nurbspring_sim::IntegratorKind;

/// MSM parameters that override the scene's `[msm]` section or the msm.json file.
#[derive(Args, Debug, Default, Clone)]
pub struct MsmFlags {
    /// Structural spring constant.
    #[arg(long)]
    pub k_edge: Option<f64>,
    /// Shear spring constant.
    #[arg(long)]
    pub k_diag: Option<f64>,
    /// Bending spring constant.
    #[arg(long)]
    pub k_bend: Option<f64>,
    /// Node mass.
    #[arg(long)]
    pub mass: Option<f64>,
}

impl MsmFlags {
    /// The overrides they give.
    pub fn overrides(&self) -> MsmOverrides {
        let constants = Constants::from_pairs(
            [
                (SpringKind::Structural, self.k_edge),
                (SpringKind::Shear, self.k_diag),
                (SpringKind::Bend, self.k_bend),
            ]
            .into_iter()
            .filter_map(|(kind, k)| k.map(|k| (Class::Spring(kind), k))),
        );
        MsmOverrides {
            constants,
            mass: self.mass,
        }
    }
}

/// The flag of an overridden field: `k_edge` → `--k-edge`.
pub fn flag(field: &str) -> String {
    format!("--{}", field.replace('_', "-"))
}

/// Parses `--integrator`: any integrator by name (which ones apply is the model's rule).
pub fn parse_integrator(s: &str) -> Result<IntegratorKind, String> {
    IntegratorKind::parse(s).ok_or_else(|| {
        format!(
            "unknown integrator; expected one of {}",
            nurbspring_dnurbs::integrator_names(&IntegratorKind::ALL)
        )
    })
}
