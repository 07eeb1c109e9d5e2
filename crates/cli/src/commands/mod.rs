//! One module per subcommand.

pub mod check;
pub mod derive;
pub mod eval;
pub mod matrices;
pub mod modes;
pub mod paper;
pub mod simulate;
pub mod stability;
pub mod steady;
