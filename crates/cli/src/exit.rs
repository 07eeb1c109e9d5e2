//! The one table from error kinds to exit codes: 0 success, 2 bad input (a scene, a file, a
//! flag), 1 a failure during a run, 130 interrupted.

use nurbspring_scene::Error;
use nurbspring_scene::ErrorKind;

/// Bad input.
pub const INPUT: u8 = 2;
/// A failure during a run.
pub const RUN: u8 = 1;
/// Interrupted (Ctrl-C or a signal).
pub const CANCELLED: u8 = 130;

/// The exit code of an error.
pub fn code(e: &Error) -> u8 {
    match e.kind() {
        ErrorKind::Input => INPUT,
        ErrorKind::Run => RUN,
        ErrorKind::Cancelled => CANCELLED,
    }
}
