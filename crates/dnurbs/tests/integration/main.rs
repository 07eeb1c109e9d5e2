//! Integration tests of nurbspring-dnurbs (one binary; tolerances in `support::tol`).

mod support;

mod assembly;
mod closed_form;
mod constraints;
mod convergence;
mod current_state;
mod errors;
mod integrators;
mod omega_weights;
mod properties;
mod rational;
mod small_functions;
