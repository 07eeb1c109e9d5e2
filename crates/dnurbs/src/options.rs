//! Numerical options of the D-NURBS discretization (docs/math.md §3).

use crate::{DnurbsError, Geometry, Material, ScalarMatrices};

/// The measure of the D-NURBS integrals (docs/math.md §3).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Integration {
    /// `du dv` over the parameter domain: the paper's literal reading (default).
    #[default]
    Parameter,
    /// The surface area element `dA = |c_u × c_v| du dv` (curves: arc length `|c'| du`),
    /// evaluated on the geometry at which the matrices are assembled.
    Area,
}

/// The rest shape `p_rest` of the elastic force `K (p − p_rest)` (docs/math.md §3).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum RestShape {
    /// `p_rest = p(0)`: displacement form, the initial surface is the steady state (default).
    #[default]
    Initial,
    /// `p_rest = 0`: Terzopoulos–Qin's literal energy on `p` itself.
    Zero,
}

impl RestShape {
    /// "initial" or "zero", as in scene files.
    pub fn name(self) -> &'static str {
        match self {
            RestShape::Initial => "initial",
            RestShape::Zero => "zero",
        }
    }
}

/// Discretization options; in a scene file the `[dnurbs]` table, key for key.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct DnurbsOptions {
    /// Gauss–Legendre points per knot span and direction, 1..=[`MAX_QUADRATURE_POINTS`];
    /// `None` (the default, key omitted) chooses them from the geometry
    /// ([`DnurbsOptions::quadrature_for`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub quadrature_points: Option<usize>,
    /// Parameter-domain (default) or area integration (scene key `integrate_over`).
    #[serde(rename = "integrate_over")]
    pub integration: Integration,
    /// Weights as generalized coordinates: 4 dofs per control point (docs/math.md §2–3).
    pub weights_as_dofs: bool,
    /// The rest shape.
    pub rest_shape: RestShape,
}

/// Largest Gauss–Legendre rule per direction.
pub const MAX_QUADRATURE_POINTS: usize = 32;

impl DnurbsOptions {
    /// The rules on the options, each problem naming its field: `quadrature_points` in
    /// `1..=MAX_QUADRATURE_POINTS`.
    pub fn validate(&self) -> Result<(), DnurbsError> {
        match self.quadrature_points {
            Some(points) => check_quadrature_points(points),
            None => Ok(()),
        }
    }

    /// The Gauss–Legendre rule for `geometry` (docs/math.md §3, Quadrature).
    ///
    /// A degree-p polynomial integrand of the mass needs `p + 1` points per direction to be
    /// exact; that is the choice for equal weights, constant weights and parameter
    /// integration. Otherwise (unequal weights, weights as unknowns, area integration) the
    /// integrands are not polynomials and no rule is exact: the error of a rule `g` is
    /// estimated as the relative Frobenius change of the scalar mass and stiffness matrices
    /// (unit coefficients) from `g` to `g + 1` points, and the automatic choice is the
    /// smallest `g ≥ p + 1` (with weights as unknowns `g ≥ p + 2`) whose estimate is at most
    /// [`QUADRATURE_TOLERANCE`]. A `quadrature_points` key is used as given, with its
    /// estimate.
    pub fn quadrature_for(&self, geometry: &Geometry) -> Result<QuadratureChoice, DnurbsError> {
        let (p, q) = geometry.degrees();
        let exact_points = p.max(q) + 1;
        let polynomial = geometry.has_uniform_weights()
            && !self.weights_as_dofs
            && self.integration == Integration::Parameter;
        if polynomial {
            let points = self.quadrature_points.unwrap_or(exact_points);
            check_quadrature_points(points)?;
            return Ok(QuadratureChoice {
                points,
                automatic: self.quadrature_points.is_none(),
                polynomial: true,
                estimated_error: if points >= exact_points {
                    0.0
                } else {
                    self.change(geometry, points)?
                },
            });
        }
        if let Some(points) = self.quadrature_points {
            check_quadrature_points(points)?;
            return Ok(QuadratureChoice {
                points,
                automatic: false,
                polynomial: false,
                estimated_error: self.change(geometry, points)?,
            });
        }
        let start = (exact_points + usize::from(self.weights_as_dofs)).min(MAX_QUADRATURE_POINTS);
        // Each candidate costs one assembly (the previous one is kept), and the search stops
        // AUTO_SPAN rules above the start: a hostile geometry cannot make it assemble 2 × 30
        // times at up to 32² points an element; what is left over is warned about.
        let last_rule = (start + AUTO_SPAN).min(MAX_QUADRATURE_POINTS);
        let mut previous = self.unit_matrices(geometry, start)?;
        let mut last = (start, f64::INFINITY);
        for points in start..last_rule {
            let next = self.unit_matrices(geometry, points + 1)?;
            let e = relative_change(&previous, &next);
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

    /// `max(|S_M(g+1) − S_M(g)|, |S_K(g+1) − S_K(g)|)` relative, for unit coefficients
    /// (`g − 1` against `g` at the largest rule).
    fn change(&self, geometry: &Geometry, points: usize) -> Result<f64, DnurbsError> {
        let (a, b) = if points < MAX_QUADRATURE_POINTS {
            (points, points + 1)
        } else {
            (points - 1, points)
        };
        let material = unit_material(geometry);
        let (lo, hi) = (
            self.unit_matrices_with(geometry, &material, a)?,
            self.unit_matrices_with(geometry, &material, b)?,
        );
        Ok(relative_change(&lo, &hi))
    }

    /// The scalar M and K for unit coefficients at the rule `g`.
    fn unit_matrices(&self, geometry: &Geometry, g: usize) -> Result<ScalarMatrices, DnurbsError> {
        self.unit_matrices_with(geometry, &unit_material(geometry), g)
    }

    fn unit_matrices_with(
        &self,
        geometry: &Geometry,
        material: &Material,
        g: usize,
    ) -> Result<ScalarMatrices, DnurbsError> {
        let options = DnurbsOptions {
            quadrature_points: Some(g),
            weights_as_dofs: false,
            ..self.clone()
        };
        crate::assemble_scalar(geometry, material, &options)
    }
}

/// Unit coefficients for every term the geometry has.
fn unit_material(geometry: &Geometry) -> Material {
    if geometry.is_curve() {
        Material {
            mu: 1.0,
            alpha11: 1.0,
            beta11: 1.0,
            ..Material::default()
        }
    } else {
        Material {
            mu: 1.0,
            alpha11: 1.0,
            alpha22: 1.0,
            beta11: 1.0,
            beta12: 1.0,
            beta22: 1.0,
            ..Material::default()
        }
    }
}

/// `max(‖M_a − M_b‖/‖M_b‖, ‖K_a − K_b‖/‖K_b‖)` (Frobenius).
fn relative_change(lo: &ScalarMatrices, hi: &ScalarMatrices) -> f64 {
    let rel = |x: &nurbspring_linalg::SparseMatrix, y: &nurbspring_linalg::SparseMatrix| {
        let d = nurbspring_linalg::SparseMatrix::linear_combination(1.0, x, -1.0, y)
            .map(|d| d.frobenius_norm())
            .unwrap_or(f64::INFINITY);
        let n = y.frobenius_norm();
        if n > 0.0 { d / n } else { d }
    };
    rel(&lo.mass, &hi.mass).max(rel(&lo.stiffness, &hi.stiffness))
}

/// How many rules above the first the automatic choice tries at most.
pub const AUTO_SPAN: usize = 8;

/// The automatic rule's target: estimated relative error of M and K.
pub const QUADRATURE_TOLERANCE: f64 = 1e-10;

/// Estimated relative quadrature errors above this are reported as a warning.
pub const QUADRATURE_WARNING: f64 = 1e-8;

/// The Gauss–Legendre rule a model uses ([`DnurbsOptions::quadrature_for`]).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct QuadratureChoice {
    /// Points per knot span and direction.
    pub points: usize,
    /// Chosen automatically (no `quadrature_points` key).
    pub automatic: bool,
    /// The integrands are polynomials (equal constant weights, parameter integration).
    pub polynomial: bool,
    /// Estimated relative error of M and K (0 when the rule is exact).
    pub estimated_error: f64,
}

impl QuadratureChoice {
    /// A warning when the estimated error exceeds [`QUADRATURE_WARNING`], naming the key.
    pub fn warning(&self) -> Option<String> {
        (self.estimated_error > QUADRATURE_WARNING).then(|| {
            format!(
                "dnurbs.quadrature_points = {}: the integrands are not polynomials ({}) and the \
                 estimated relative quadrature error of M and K is {:.1e}; raise \
                 dnurbs.quadrature_points (at most {MAX_QUADRATURE_POINTS}) or omit it for the \
                 automatic choice",
                self.points,
                if self.polynomial {
                    "too few points for the degree"
                } else {
                    "unequal weights, weights as unknowns or area integration"
                },
                self.estimated_error
            )
        })
    }
}

/// The rule on the number of Gauss–Legendre points per direction.
pub(crate) fn check_quadrature_points(points: usize) -> Result<(), DnurbsError> {
    if !(1..=MAX_QUADRATURE_POINTS).contains(&points) {
        return Err(DnurbsError::InvalidOption {
            name: "quadrature_points",
            value: points.to_string(),
            reason: format!("must be in 1..={MAX_QUADRATURE_POINTS}"),
        });
    }
    Ok(())
}

impl Default for DnurbsOptions {
    fn default() -> Self {
        Self {
            quadrature_points: None,
            integration: Integration::Parameter,
            weights_as_dofs: false,
            rest_shape: RestShape::Initial,
        }
    }
}
