//! Which scene key an input error of a derivation is about: the one table from the typed
//! errors of `nurbspring-derive` ([`DeriveError`], [`Input`]) to key paths and the scene's
//! words.

use nurbspring_derive::{DeriveError, Input, ScalarObstacle};

/// The scene key of each derivation input.
pub fn input_key(input: Input) -> &'static str {
    match input {
        Input::Derivation => "fit.derivation",
        Input::Grid => "msm.grid",
        Input::Elements => "msm.elements",
        Input::Mass => "fit.mass",
        Input::Constraints => "constraints",
        Input::Material => "material",
        Input::ModalFit => "modal fit",
        Input::EdgeLoads => "loads.edge",
    }
}

/// An input error of a derivation as the scene names it: the key, its value and why it is
/// refused; `None` for the errors that are not about one input.
pub fn refusal(e: &DeriveError) -> Option<(&'static str, String, String)> {
    Some(match e {
        DeriveError::InvalidInput {
            input,
            value,
            reason,
        } => (input_key(*input), value.clone(), reason.clone()),
        DeriveError::NotScalar { method, obstacle } => (
            input_key(Input::Derivation),
            format!("\"{method}\""),
            match obstacle {
                ScalarObstacle::WeightsAsDofs => {
                    "needs constant weights (dnurbs.weights_as_dofs = false)"
                }
                ScalarObstacle::LinearConstraints => "needs a model without constraints.linear",
                ScalarObstacle::NoFreeControlPoint => "needs at least one free control point",
            }
            .to_string(),
        ),
        DeriveError::TooManyNodes {
            free_nodes,
            control_points,
        } => (
            input_key(Input::Grid),
            format!("{free_nodes} free nodes"),
            format!(
                "the reduction needs at most as many free nodes as free control points ({control_points}); use grid = \"greville\""
            ),
        ),
        DeriveError::NoExcitation => (
            "initial.velocity",
            "0 everywhere, and no displacement or load".to_string(),
            "the excitation derivation weights the modes the scene's initial velocity and loads excite, and this scene excites none (give initial.velocity, initial.displacement or loads)".to_string(),
        ),
        _ => return None,
    })
}

/// The message of a derivation error that is not about one input, in the scene's words.
pub fn message(e: &DeriveError) -> String {
    match e {
        DeriveError::NoMassCandidate { tried, first } => format!(
            "every mass candidate failed to run ({tried} tried; the first: {first}); give a mass with fit.mass = \"fixed\" and msm.mass"
        ),
        e => e.to_string(),
    }
}
