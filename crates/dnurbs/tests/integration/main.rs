//! Integration tests of nurbspring-dnurbs (one binary; tolerances in `support::tol`).

mod support;

mod assembly;
mod constraints;
mod convergence;
mod current_state;
mod errors;
mod integrators;
mod properties;
mod rational;
