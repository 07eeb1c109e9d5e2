//! [`derive`]: the one place that chooses the derivation a [`Config`] names ([`Method`]).

use std::sync::Arc;
use std::sync::atomic::AtomicBool;

use crate::method::{LinearMethod, Method};
use crate::outcome::Derivation;
use crate::setup::{Config, Setup};
use crate::{DeriveError, linear, pipeline};

/// Runs the derivation `config.method`: the one place that chooses between them. `cancel`
/// stops between steps; `progress(done, total)` follows the paper's mass scan.
pub fn derive(
    config: &Config,
    cancel: Option<Arc<AtomicBool>>,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<(Derivation, Setup), DeriveError> {
    match config.method {
        Method::Paper => pipeline::derive_msm(config, cancel, progress),
        Method::Modal => linear::derive_linear(config, LinearMethod::Modal, cancel),
        Method::Excitation => linear::derive_linear(config, LinearMethod::Excitation, cancel),
        Method::Reduction => linear::derive_linear(config, LinearMethod::Reduction, cancel),
        // A shell's derivation: its configuration holds the shell (crate::derive_springs).
        Method::Springs => Err(DeriveError::InvalidInput {
            input: crate::Input::Derivation,
            value: "\"springs\"".into(),
            reason: "the spring derivation takes a Kirchhoff–Love shell (material.model = \
                     \"kirchhoff-love\"); the tension plate derives modal, excitation, \
                     reduction or paper"
                .into(),
        }),
    }
}
