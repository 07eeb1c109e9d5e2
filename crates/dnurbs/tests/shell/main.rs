//! Tests of the Kirchhoff–Love shell (docs/math.md §10); tolerances in `support::tol`.

mod support;

mod analytic;
mod derivatives;
mod dynamics;
mod large_deflection;
mod obstacle;
