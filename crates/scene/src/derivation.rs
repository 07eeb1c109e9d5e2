//! A scene's derivation: which one runs ([`Scene::choose_derivation`]: the caller's, else the
//! scene's `fit.derivation`, else the default with its fallback), running it
//! ([`Scene::derive`]), and which key an error of it is blamed on.

use std::sync::Arc;
use std::sync::atomic::AtomicBool;

use nurbspring_derive::{Config, Derivation, DeriveError, Method, Setup};
use nurbspring_sim::ErrorKind;

use crate::{Error, Scene};

/// The scene key that names the derivation.
pub const DERIVATION_KEY: &str = "fit.derivation";

/// The derivation chosen for a scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DerivationChoice {
    /// The derivation.
    pub method: Method,
    /// The key or option that chose it (`fit.derivation` when the scene did), blamed for the
    /// input errors of the derivation that name no key of their own.
    pub key: &'static str,
    /// Why the scene's default is not the usual one (a scene the linear derivations cannot
    /// take), when it is not.
    pub fallback: Option<&'static str>,
}

impl Scene {
    /// The derivation to run: `requested` (a method with the name of the option that gave
    /// it: `--derivation`, `derivation`), else [`Scene::derivation`].
    pub fn choose_derivation(&self, requested: Option<(Method, &'static str)>) -> DerivationChoice {
        match requested {
            Some((method, key)) => DerivationChoice {
                method,
                key,
                fallback: None,
            },
            None => {
                let (method, fallback) = self.derivation();
                DerivationChoice {
                    method,
                    key: DERIVATION_KEY,
                    fallback,
                }
            }
        }
    }

    /// True when `choice` derives from a Kirchhoff–Love shell: every derivation of a shell
    /// scene (a spring model, [`crate::springs_report::derive_springs`], or the reduction,
    /// [`crate::springs_report::reduce_shell`]), and `springs` of any (the tension plate's is
    /// refused there, naming `material.model`).
    pub fn derives_from_shell(&self, choice: &DerivationChoice) -> bool {
        choice.method == Method::Springs || self.material.shell().is_some()
    }

    /// The derivation `choice` of this scene, configured and ready to run.
    pub fn prepare_derivation(
        &self,
        choice: DerivationChoice,
    ) -> Result<PreparedDerivation<'_>, Error> {
        Ok(PreparedDerivation {
            scene: self,
            config: self.derivation_config(Some(choice.method))?,
            choice,
        })
    }

    /// Runs the derivation `choice` of this scene ([`Scene::prepare_derivation`], then
    /// [`PreparedDerivation::run`]).
    pub fn derive(
        &self,
        choice: DerivationChoice,
        cancel: Option<Arc<AtomicBool>>,
        progress: &mut dyn FnMut(usize, usize),
    ) -> Result<(Derivation, Setup), Error> {
        self.prepare_derivation(choice)?.run(cancel, progress)
    }

    /// An error of a derivation of this scene, with the key behind it: an input the
    /// derivation refuses names its own key ([`crate::keys::refusal`]); other input errors
    /// are the derivation's (`key`, the one that chose it).
    pub fn derive_error(&self, key: &str, e: DeriveError) -> Error {
        let named = crate::keys::refusal(&e).is_some();
        let input = e.kind() == ErrorKind::Input;
        Error::model(&self.path, (input && !named).then_some(key), e)
    }
}

/// A derivation of a scene, configured ([`Scene::prepare_derivation`]).
pub struct PreparedDerivation<'a> {
    scene: &'a Scene,
    /// Its configuration.
    pub config: Config,
    /// The choice it was made from.
    pub choice: DerivationChoice,
}

impl PreparedDerivation<'_> {
    /// Runs it; `cancel` stops it between steps, `progress(done, total)` follows the paper's
    /// mass scan. An error is blamed on the key behind it ([`Scene::derive_error`]).
    pub fn run(
        &self,
        cancel: Option<Arc<AtomicBool>>,
        progress: &mut dyn FnMut(usize, usize),
    ) -> Result<(Derivation, Setup), Error> {
        nurbspring_derive::derive(&self.config, cancel, progress)
            .map_err(|e| self.scene.derive_error(self.choice.key, e))
    }
}
