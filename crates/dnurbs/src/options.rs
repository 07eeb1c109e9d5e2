//! Numerical options of the D-NURBS discretization (SPEC §3).

/// The measure of the D-NURBS integrals (SPEC §3).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Integration {
    /// `du dv` over the parameter domain: the paper's literal reading (default).
    #[default]
    Parameter,
    /// The surface area element `dA = |c_u × c_v| du dv` (curves: arc length `|c'| du`),
    /// evaluated on the geometry at which the matrices are assembled.
    Area,
}

/// The rest shape `p_rest` of the elastic force `K (p − p_rest)` (SPEC §3).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum RestShape {
    /// `p_rest = p(0)`: displacement form, the initial surface is the steady state (default).
    #[default]
    Initial,
    /// `p_rest = 0`: Terzopoulos–Qin's literal energy on `p` itself.
    Zero,
}

/// Discretization options.
#[derive(Clone, Debug, PartialEq)]
pub struct DnurbsOptions {
    /// Gauss–Legendre points per knot span and direction (default 4: exact for bicubic
    /// polynomial integrands with constant weights).
    pub quadrature_points: usize,
    /// Parameter-domain (default) or area integration.
    pub integration: Integration,
    /// Weights as generalized coordinates: 4 dofs per control point (SPEC §2–3).
    pub weights_as_dofs: bool,
    /// The rest shape.
    pub rest_shape: RestShape,
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
