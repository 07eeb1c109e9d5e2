//! The isogeometric Kirchhoff–Love shell (Kiendl, Bletzinger, Linhard, Wüchner 2009): a
//! physical D-NURBS energy over the same control points (docs/math.md §10).

mod energy;
mod kinematics;
mod material;
pub mod obstacle;

pub use energy::ShellEnergy;
pub use material::ShellMaterial;

use nurbspring_linalg::SparseMatrix;

use crate::options::check_quadrature_points;
use crate::{
    AUTO_SPAN, DnurbsError, DnurbsOptions, Geometry, Integration, MAX_QUADRATURE_POINTS, Material,
    QUADRATURE_TOLERANCE, QuadratureChoice,
};

/// The Gauss–Legendre rule of a shell (docs/math.md §10.4): the integrands (the tangent at rest
/// and the mass over the rest area) are rational in general, so the error of a rule `g` is
/// estimated as the relative Frobenius change of the tangent at rest and of the area mass from
/// `g` to `g + 1` points. Without `quadrature_points` the rule is the smallest `g ≥ p + 1`
/// (p the larger degree) whose estimate is at most [`QUADRATURE_TOLERANCE`], at most
/// [`AUTO_SPAN`] rules above the first; a given rule is used as is, with its estimate.
pub(crate) fn quadrature(
    geometry: &Geometry,
    material: &ShellMaterial,
    options: &DnurbsOptions,
) -> Result<QuadratureChoice, DnurbsError> {
    let (p, q) = geometry.degrees();
    let start = (p.max(q) + 1).min(MAX_QUADRATURE_POINTS);
    let matrices = |g: usize| -> Result<(SparseMatrix, SparseMatrix), DnurbsError> {
        let tangent =
            ShellEnergy::new(geometry, material, g)?.tangent(&geometry.coordinates(false));
        let unit = Material::default();
        let options = DnurbsOptions {
            quadrature_points: Some(g),
            integration: Integration::Area,
            weights_as_dofs: false,
            ..options.clone()
        };
        Ok((
            tangent,
            crate::assemble_scalar(geometry, &unit, &options)?.mass,
        ))
    };
    let change = |lo: &(SparseMatrix, SparseMatrix), hi: &(SparseMatrix, SparseMatrix)| {
        let rel = |x: &SparseMatrix, y: &SparseMatrix| {
            let d = SparseMatrix::linear_combination(1.0, x, -1.0, y)
                .map(|d| d.frobenius_norm())
                .unwrap_or(f64::INFINITY);
            let n = y.frobenius_norm();
            if n > 0.0 { d / n } else { d }
        };
        rel(&lo.0, &hi.0).max(rel(&lo.1, &hi.1))
    };
    if let Some(points) = options.quadrature_points {
        check_quadrature_points(points)?;
        let (a, b) = if points < MAX_QUADRATURE_POINTS {
            (points, points + 1)
        } else {
            (points - 1, points)
        };
        return Ok(QuadratureChoice {
            points,
            automatic: false,
            polynomial: false,
            estimated_error: change(&matrices(a)?, &matrices(b)?),
        });
    }
    let last_rule = (start + AUTO_SPAN).min(MAX_QUADRATURE_POINTS);
    let mut previous = matrices(start)?;
    let mut last = (start, f64::INFINITY);
    for points in start..last_rule {
        let next = matrices(points + 1)?;
        let e = change(&previous, &next);
        last = (points, e);
        if e <= QUADRATURE_TOLERANCE {
            break;
        }
        previous = next;
    }
    Ok(QuadratureChoice {
        points: last.0,
        automatic: true,
        polynomial: false,
        estimated_error: last.1,
    })
}
