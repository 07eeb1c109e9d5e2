//! The errors of the scene layer: where (file, key or option), what value, and why; each
//! answers [`Error::kind`] (bad input, a run failure, or a cancellation).

use std::path::PathBuf;

use nurbspring_derive::DeriveError;
use nurbspring_exchange::ExchangeError;
use nurbspring_io::OutputError;
use nurbspring_msm::MsmError;
use nurbspring_sim::ErrorKind;

use crate::SceneError;

/// Everything the scene layer reports.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The scene file: unreadable, TOML syntax or schema, invalid values (all listed).
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// An `msm.json` file that cannot be read or does not describe a valid model.
    #[error("{}: {source}", path.display())]
    MsmFile {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        source: Box<MsmError>,
    },
    /// An option given to a command (a command-line flag or an argument of the API).
    #[error("{name} {value}: {message}")]
    Option {
        /// The option, as the user wrote it (`--dt`).
        name: String,
        /// Its value.
        value: String,
        /// Why it is refused.
        message: String,
    },
    /// Building or running a model of the scene (or msm.json) at `path` failed; `key` is the
    /// scene key or option that caused it, when known.
    #[error("{}: {}{}", path.display(), key.as_ref().map(|k| format!("{k}: ")).unwrap_or_default(), crate::keys::message(source))]
    Model {
        /// The scene or msm.json file.
        path: PathBuf,
        /// The key or option behind it.
        key: Option<String>,
        /// The model's error.
        source: Box<DeriveError>,
    },
    /// A value of the scene (or msm.json) at `path` that a model refuses: `name` is the key
    /// (or option) holding it; `key`, when given, the one that caused it.
    #[error("{}: {}{name} = {value}: {reason}", path.display(), key.as_ref().map(|k| format!("{k}: ")).unwrap_or_default())]
    Refused {
        /// The scene or msm.json file.
        path: PathBuf,
        /// The key or option behind it.
        key: Option<String>,
        /// The key or option holding the value.
        name: String,
        /// The value.
        value: String,
        /// Why it is refused.
        reason: String,
    },
    /// The job would need more memory or write more than its limits allow (refused before
    /// anything is allocated; [`crate::resources`]).
    #[error("{}: {key}: {message}", path.display())]
    Resources {
        /// The scene file.
        path: PathBuf,
        /// The key that sets the size.
        key: String,
        /// The estimate against the limit.
        message: String,
    },
    /// Keys a command needs that the scene leaves out (a model is never built from
    /// placeholders): the keys, and what to do instead.
    #[error("{}: {keys}: {message}", path.display())]
    Missing {
        /// The scene file.
        path: PathBuf,
        /// The keys, comma-separated (`msm.k_edge, msm.mass`).
        keys: String,
        /// Why they are needed and how to get them.
        message: String,
    },
    /// A geometry file (geomdl JSON, IGES, OBJ) that cannot be read or does not describe valid
    /// curves and surfaces; the message names the line where the format has lines.
    #[error("{}", exchange_message(path, source))]
    Exchange {
        /// The file.
        path: PathBuf,
        /// What is wrong, and where in the file.
        source: Box<ExchangeError>,
    },
    /// Writing an output failed.
    #[error(transparent)]
    Output(#[from] OutputError),
    /// The work was interrupted (Ctrl-C or a signal).
    #[error("interrupted")]
    Cancelled,
    /// A run interrupted after some samples: the output folder was left as it was and what was
    /// computed kept aside.
    #[error(
        "interrupted: {} is as it was; the samples computed so far are in {}",
        out.display(),
        kept.display()
    )]
    CancelledKept {
        /// The output folder, unchanged.
        out: PathBuf,
        /// Where the interrupted run's files are.
        kept: PathBuf,
    },
}

impl Error {
    /// Input, Run or Cancelled.
    pub fn kind(&self) -> ErrorKind {
        match self {
            Error::Scene(_)
            | Error::Option { .. }
            | Error::Refused { .. }
            | Error::Resources { .. }
            | Error::Missing { .. }
            | Error::Exchange { .. } => ErrorKind::Input,
            Error::MsmFile { source, .. } => source.kind(),
            Error::Model { source, .. } => source.kind(),
            Error::Output(_) => ErrorKind::Run,
            Error::Cancelled | Error::CancelledKept { .. } => ErrorKind::Cancelled,
        }
    }

    /// A model error of the file `path`, caused by `key` when known; an input a derivation
    /// refuses is named by its scene key ([`crate::keys::refusal`]).
    pub fn model(
        path: impl Into<PathBuf>,
        key: Option<&str>,
        source: impl Into<DeriveError>,
    ) -> Self {
        let source = source.into();
        if matches!(source, DeriveError::Cancelled) {
            return Error::Cancelled;
        }
        if let Some((name, value, reason)) = crate::keys::refusal(&source) {
            return Error::refused(path, key, name, value, reason);
        }
        Error::Model {
            path: path.into(),
            key: key.map(str::to_string),
            source: Box::new(source),
        }
    }

    /// A value of the file `path` that a model refuses.
    pub fn refused(
        path: impl Into<PathBuf>,
        key: Option<&str>,
        name: &str,
        value: impl std::fmt::Display,
        reason: impl Into<String>,
    ) -> Self {
        Error::Refused {
            path: path.into(),
            key: key.map(str::to_string),
            name: name.to_string(),
            value: value.to_string(),
            reason: reason.into(),
        }
    }

    /// A refused option.
    pub fn option(name: &str, value: impl std::fmt::Display, message: impl Into<String>) -> Self {
        Error::Option {
            name: name.to_string(),
            value: value.to_string(),
            message: message.into(),
        }
    }
}

/// `path: message`, without repeating the path when the exchange error names it already.
fn exchange_message(path: &std::path::Path, e: &ExchangeError) -> String {
    match e {
        ExchangeError::Io { .. }
        | ExchangeError::FileTooLarge { .. }
        | ExchangeError::NotRegularFile { .. }
        | ExchangeError::NotText { .. } => e.to_string(),
        _ => format!("{}: {e}", path.display()),
    }
}
