//! Scene errors: where (file, line and column, or key path), what value, and why.

use std::fmt;
use std::path::PathBuf;

/// Which kind of failure, so the binary can choose its exit code.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SceneErrorKind {
    /// The text is not valid TOML, or does not fit the scene schema (unknown key, wrong type,
    /// missing key).
    Parse,
    /// The TOML is well formed but a value is not acceptable.
    Invalid,
    /// The file could not be read.
    Io,
}

/// One invalid value: `key = value: message`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Problem {
    /// Key path, e.g. `surface.weights[2][1]`.
    pub key: String,
    /// The offending value as written in messages (empty when the key is missing).
    pub value: String,
    /// Why it is refused.
    pub message: String,
}

impl Problem {
    /// A problem with `key` having `value`.
    pub fn new(
        key: impl Into<String>,
        value: impl Into<String>,
        message: impl Into<String>,
    ) -> Self {
        Self {
            key: key.into(),
            value: value.into(),
            message: message.into(),
        }
    }
}

impl fmt::Display for Problem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.value.is_empty() {
            write!(f, "{}: {}", self.key, self.message)
        } else {
            write!(f, "{} = {}: {}", self.key, self.value, self.message)
        }
    }
}

/// Everything that can be wrong with a scene file.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The file could not be read.
    #[error("{}: cannot read the {what} file: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// What it was read as: `"scene"` or `"msm.json"`.
        what: &'static str,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
    /// TOML syntax or schema error at a position in the file.
    #[error("{}", fmt_parse(path, message, *line, *column, suggestion.as_deref()))]
    Parse {
        /// The scene file.
        path: PathBuf,
        /// What is wrong (e.g. "unknown key `bta11` in \[material\]").
        message: String,
        /// 1-based line (0 when unknown).
        line: usize,
        /// 1-based column in characters (0 when unknown).
        column: usize,
        /// The nearest valid key or value, for a misspelling.
        suggestion: Option<String>,
    },
    /// One or more values are invalid; every problem found is listed.
    #[error("{}", fmt_invalid(path, problems))]
    Invalid {
        /// The scene file (empty for a section validated on its own).
        path: PathBuf,
        /// The problems, in file order as far as possible.
        problems: Vec<Problem>,
    },
}

fn prefix(path: &std::path::Path) -> String {
    if path.as_os_str().is_empty() {
        String::new()
    } else {
        format!("{}: ", path.display())
    }
}

fn fmt_parse(
    path: &std::path::Path,
    message: &str,
    line: usize,
    column: usize,
    suggestion: Option<&str>,
) -> String {
    let mut s = format!("{}{message}", prefix(path));
    if line > 0 {
        s.push_str(&format!(" at line {line}, column {column}"));
    }
    if let Some(sug) = suggestion {
        s.push_str(&format!("; did you mean `{sug}`?"));
    }
    s
}

fn fmt_invalid(path: &std::path::Path, problems: &[Problem]) -> String {
    problems
        .iter()
        .map(|p| format!("{}{p}", prefix(path)))
        .collect::<Vec<_>>()
        .join("\n")
}

impl SceneError {
    /// Parse, Invalid or Io.
    pub fn kind(&self) -> SceneErrorKind {
        match self {
            SceneError::Io { .. } => SceneErrorKind::Io,
            SceneError::Parse { .. } => SceneErrorKind::Parse,
            SceneError::Invalid { .. } => SceneErrorKind::Invalid,
        }
    }

    /// The problems of an `Invalid` error (empty otherwise).
    pub fn problems(&self) -> &[Problem] {
        match self {
            SceneError::Invalid { problems, .. } => problems,
            _ => &[],
        }
    }

    /// The same error attributed to `path`.
    pub(crate) fn with_path(mut self, new: &std::path::Path) -> Self {
        match &mut self {
            SceneError::Io { path, .. }
            | SceneError::Parse { path, .. }
            | SceneError::Invalid { path, .. } => *path = new.to_path_buf(),
        }
        self
    }
}
