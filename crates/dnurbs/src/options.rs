//! Numerical options of the D-NURBS discretization (docs/math.md §3).

use crate::DnurbsError;

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
    /// Gauss–Legendre points per knot span and direction, 1..=[`MAX_QUADRATURE_POINTS`]
    /// (default 4: exact for bicubic polynomial integrands with constant weights).
    pub quadrature_points: usize,
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
        check_quadrature_points(self.quadrature_points)
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
            quadrature_points: 4,
            integration: Integration::Parameter,
            weights_as_dofs: false,
            rest_shape: RestShape::Initial,
        }
    }
}
