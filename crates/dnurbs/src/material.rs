//! Material coefficients of D-NURBS (paper eqs. (3)–(4), SPEC §3).

use crate::DnurbsError;

/// Mass density `μ`, damping density `γ`, membrane (stretching) coefficients `α11`, `α22` and
/// thin-plate (bending) coefficients `β11`, `β12`, `β22` of the D-NURBS energy
/// (paper eqs. (3)–(4)):
///
/// `M = ∫∫ μ JᵀJ`, `D = ∫∫ γ JᵀJ`,
/// `K = ∫∫ α11 J_uᵀJ_u + α22 J_vᵀJ_v + β11 J_uuᵀJ_uu + β12 J_uvᵀJ_uv + β22 J_vvᵀJ_vv`.
///
/// For curves only `alpha11` (the paper's α) and `beta11` (the paper's β) enter.
/// The coefficients are constant over the domain. `Default` is `μ = 1`, everything else 0.
///
/// ```
/// use nurbspring_dnurbs::Material;
/// let paper = Material { mu: 25.0, beta11: 0.01, beta22: 0.01, ..Material::default() };
/// assert!(paper.validate().is_ok());
/// let bad = Material { gamma: -1.0, ..Material::default() };
/// assert_eq!(bad.validate().unwrap_err().to_string(),
///     "material coefficient gamma must be finite and non-negative, got -1");
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// Mass density μ (≥ 0; 0 allows steady states only).
    pub mu: f64,
    /// Damping density γ.
    pub gamma: f64,
    /// Stretching along u, α11 (curves: α).
    pub alpha11: f64,
    /// Stretching along v, α22.
    pub alpha22: f64,
    /// Bending along u, β11 (curves: β).
    pub beta11: f64,
    /// Twist, β12.
    pub beta12: f64,
    /// Bending along v, β22.
    pub beta22: f64,
}

impl Default for Material {
    fn default() -> Self {
        Self {
            mu: 1.0,
            gamma: 0.0,
            alpha11: 0.0,
            alpha22: 0.0,
            beta11: 0.0,
            beta12: 0.0,
            beta22: 0.0,
        }
    }
}

impl Material {
    /// The coefficients with their names, in declaration order.
    pub fn named(&self) -> [(&'static str, f64); 7] {
        [
            ("mu", self.mu),
            ("gamma", self.gamma),
            ("alpha11", self.alpha11),
            ("alpha22", self.alpha22),
            ("beta11", self.beta11),
            ("beta12", self.beta12),
            ("beta22", self.beta22),
        ]
    }

    /// Checks that every coefficient is finite and `≥ 0` (SPEC §3); the first offending one is
    /// named in [`DnurbsError::InvalidMaterial`].
    pub fn validate(&self) -> Result<(), DnurbsError> {
        for (name, value) in self.named() {
            if !(value.is_finite() && value >= 0.0) {
                return Err(DnurbsError::InvalidMaterial { name, value });
            }
        }
        Ok(())
    }

    /// The stiffness coefficients per derivative slot `[·, u, v, uu, uv, vv]` of
    /// `nurbspring_geom::Deriv` (slot 0, the value, has none): paper eq. (4).
    /// For curves the v slots are ignored by the caller.
    pub fn stiffness_by_slot(&self) -> [f64; 6] {
        [
            0.0,
            self.alpha11,
            self.alpha22,
            self.beta11,
            self.beta12,
            self.beta22,
        ]
    }
}
