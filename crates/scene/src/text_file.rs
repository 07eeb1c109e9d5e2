//! Reading a scene or msm.json file: the bounded reader of `nurbspring-exchange`
//! ([`read_text_bounded`]), its refusals named as scene problems.

use std::path::Path;

use nurbspring_exchange::{BoundedReadError, read_text_bounded};

use crate::{Problem, SceneError};

/// Reads a text file of at most `limit` bytes ([`read_text_bounded`]); `what` names the file
/// in messages ("scene").
pub(crate) fn read_text(path: &Path, limit: u64, what: &'static str) -> Result<String, SceneError> {
    let io = |source| SceneError::Io {
        path: path.to_path_buf(),
        what,
        source,
    };
    let invalid = |value: String, message: String| SceneError::Invalid {
        path: path.to_path_buf(),
        problems: vec![Problem::new("(file)", value, message)],
    };
    read_text_bounded(path, limit).map_err(|e| match e {
        BoundedReadError::Io(source) => io(source),
        BoundedReadError::NotRegularFile { folder } => invalid(
            if folder {
                "a folder"
            } else {
                "not a regular file (a FIFO, socket or device)"
            }
            .to_string(),
            format!("a {what} file must be a regular file"),
        ),
        BoundedReadError::TooLarge { limit } => invalid(
            format!("more than {limit} bytes"),
            format!("{what} files are limited to {limit} bytes"),
        ),
        BoundedReadError::NotText { offset } => invalid(
            format!("invalid UTF-8 at byte {offset}"),
            format!("a {what} file must be UTF-8 text"),
        ),
    })
}
