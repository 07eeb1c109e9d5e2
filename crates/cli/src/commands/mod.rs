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

use clap::{Args, ValueEnum};

use nurbspring_scene::{Class, Constants, IntegratorKind, MsmOverrides, SpringKind};

/// MSM parameters that override the scene's `[msm]` section or the msm.json file.
#[derive(Args, Debug, Default, Clone)]
pub struct MsmFlags {
    /// Structural spring constant.
    #[arg(long, allow_negative_numbers = true)]
    pub k_edge: Option<f64>,
    /// Shear spring constant.
    #[arg(long, allow_negative_numbers = true)]
    pub k_diag: Option<f64>,
    /// Bending spring constant.
    #[arg(long, allow_negative_numbers = true)]
    pub k_bend: Option<f64>,
    /// Node mass.
    #[arg(long, allow_negative_numbers = true)]
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

/// The values of `--integrator`: every integrator by its scene name (which ones apply is the
/// model's rule, checked when the run starts).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum IntegratorChoice {
    /// Terzopoulos–Qin backward differences (D-NURBS); unconditionally stable.
    TerzopoulosQin,
    /// Newmark average acceleration; unconditionally stable, no numerical damping.
    Newmark,
    /// Generalized-α (rho_inf = 0.8); unconditionally stable, damps the highest frequencies
    /// (neither model lists it yet: refused with the model's list).
    GeneralizedAlpha,
    /// Backward Euler with Newton iterations (MSM); unconditionally stable, dissipative.
    BackwardEuler,
    /// Symplectic Euler (MSM); explicit: stable below dt_critical.
    SymplecticEuler,
    /// Velocity Verlet (MSM); explicit: stable below dt_critical.
    #[value(alias = "velocity-verlet", alias = "central-difference")]
    Verlet,
    /// Classical Runge–Kutta (MSM); explicit: stable below dt_critical.
    Rk4,
    /// Exact modal solution of the undamped linear system (linear models).
    Modal,
}

impl From<IntegratorChoice> for IntegratorKind {
    fn from(c: IntegratorChoice) -> Self {
        match c {
            IntegratorChoice::TerzopoulosQin => IntegratorKind::TerzopoulosQin,
            IntegratorChoice::Newmark => IntegratorKind::Newmark,
            IntegratorChoice::GeneralizedAlpha => IntegratorKind::GeneralizedAlpha,
            IntegratorChoice::BackwardEuler => IntegratorKind::BackwardEuler,
            IntegratorChoice::SymplecticEuler => IntegratorKind::SymplecticEuler,
            IntegratorChoice::Verlet => IntegratorKind::VelocityVerlet,
            IntegratorChoice::Rk4 => IntegratorKind::Rk4,
            IntegratorChoice::Modal => IntegratorKind::Modal,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every integrator has exactly one choice, under its scene name.
    #[test]
    fn integrator_choices_are_the_scene_names() {
        let choices = IntegratorChoice::value_variants();
        assert_eq!(choices.len(), IntegratorKind::ALL.len());
        for kind in IntegratorKind::ALL {
            let found: Vec<_> = choices
                .iter()
                .filter(|c| IntegratorKind::from(**c) == kind)
                .collect();
            assert_eq!(found.len(), 1, "{kind}");
            let value = found[0].to_possible_value().unwrap();
            assert_eq!(value.get_name(), kind.name());
        }
        let verlet = IntegratorChoice::from_str("velocity-verlet", false).unwrap();
        assert_eq!(IntegratorKind::from(verlet), IntegratorKind::VelocityVerlet);
    }
}
