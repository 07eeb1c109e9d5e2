//! Tests of the Kirchhoff–Love shell (docs/math.md §10); tolerances in `support::tol`.

mod support;

mod derivatives;
mod obstacle;
