//! # nurbspring-geom
//!
//! NURBS geometry for nurbspring: validated knot vectors, B-spline bases and their
//! derivatives (The NURBS Book A2.1–A2.3), rational curves and surfaces with derivatives up to
//! second order, the Jacobian `J = ∂c/∂p` of a point with respect to the control points (and
//! weights) with its parametric derivatives (docs/math.md §2), knot insertion and refinement as
//! matrices, and Gauss–Legendre quadrature.
//!
//! ```
//! use nurbspring_geom::{Deriv, KnotVector, NurbsSurface, surface_rule};
//! // The paper's bicubic patch (Section IV), flat at z = 2.
//! let ku = KnotVector::try_new(vec![0., 0., 0., 0., 0.25, 0.5, 0.75, 1., 1., 1., 1.], 3).unwrap();
//! let kv = KnotVector::try_new(vec![0., 0., 0., 0., 0.5, 1., 1., 1., 1.], 3).unwrap();
//! let (px, py) = ([0., 0.25, 0.75, 1.52, 2.5, 2.75, 3.], [0., 0.83, 2.5, 4.16, 5.]);
//! let pts: Vec<[f64; 3]> = px.iter().flat_map(|&x| py.iter().map(move |&y| [x, y, 2.0])).collect();
//! let s = NurbsSurface::try_new(ku, kv, pts, vec![1.0; 35]).unwrap();
//! assert_eq!(s.point(0.5, 0.5).unwrap()[2], 2.0);
//! // ∫∫ du dv over the domain with 4 Gauss points per span: 1.
//! let rule = surface_rule(s.basis_u(), s.basis_v(), 4).unwrap();
//! let area: f64 = rule.iter().flat_map(|e| &e.points).map(|q| q.weight).sum();
//! assert!((area - 1.0).abs() < 1e-14);
//! // The Jacobian has 16 non-zero blocks.
//! assert_eq!(s.jacobian(0.3, 0.3, 2, false).unwrap().n_local(), 16);
//! // Uniform refinement (A5.4) as a matrix: P^w_fine = C P^w_coarse, same surface.
//! let (fine, c) = s.refine_uniform(1).unwrap();
//! assert_eq!((fine.n_u(), fine.n_v()), (7 + 4, 5 + 2));
//! assert_eq!((c.nrows, c.ncols), (77, 35));
//! let (a, b) = (s.point(0.3, 0.8).unwrap(), fine.point(0.3, 0.8).unwrap());
//! assert!((0..3).all(|x| (a[x] - b[x]).abs() < 1e-14));
//! # let _ = Deriv::UV;
//! ```

mod basis;
mod curve;
mod differential;
mod error;
mod jacobian;
mod knots;
mod quadrature;
mod refine;
mod surface;

pub use basis::{BSplineBasis, BasisScratch};
pub use curve::{CurveDerivatives, NurbsCurve};
pub use differential::{area_element, cross, line_element, norm, quotient_rule};
pub use error::GeomError;
pub use jacobian::{Deriv, Jacobian, SurfaceJacobian};
pub use knots::{KnotVector, LINEAR_SPAN_SEARCH};
pub use quadrature::{GaussLegendre, QuadratureElement, QuadraturePoint, curve_rule, surface_rule};
pub use refine::{
    RefinementMatrix, elevate_degree, from_homogeneous, insert_knot, refine_knots, refine_uniform,
    span_subdivision_knots, to_homogeneous,
};
pub use surface::{LocalRationalBasis, NurbsSurface, SurfaceDerivatives, linspace};
