//! Material coefficients of D-NURBS (paper eqs. (3)–(4), docs/math.md §3).

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
/// assert!(paper.validate(false).is_ok());
/// let bad = Material { gamma: -1.0, ..Material::default() };
/// assert_eq!(bad.validate(false).unwrap_err().to_string(),
///     "material.gamma = -1: material constants must not be negative");
/// ```
///
/// In a scene file this is the `[material]` table, key for key (serde, unknown keys refused).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Material {
    /// Mass density μ (> 0).
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

/// The coefficients that only a surface has.
const SURFACE_ONLY: [&str; 3] = ["alpha22", "beta12", "beta22"];

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

    /// Every rule on the coefficients, each problem naming its field (docs/math.md §3): all
    /// finite, `μ > 0` (the mass matrix must be positive definite), the others `≥ 0`; on a
    /// curve (`curve = true`) only `mu`, `gamma`, `alpha11` and `beta11` apply, the others
    /// must be 0. Empty when the material is valid.
    pub fn problems(&self, curve: bool) -> Vec<DnurbsError> {
        let mut out = Vec::new();
        for (name, value) in self.named() {
            let rule = if !nurbspring_sim::representable(value) {
                Some("must be a finite number of magnitude at most 1e30 (larger values overflow)")
            } else if name == "mu" && value <= 0.0 {
                Some("the mass density must be positive")
            } else if value < 0.0 {
                Some("material constants must not be negative")
            } else if curve && SURFACE_ONLY.contains(&name) && value != 0.0 {
                Some("applies to surfaces only; a curve uses alpha11 and beta11")
            } else {
                None
            };
            if let Some(rule) = rule {
                out.push(DnurbsError::InvalidMaterial { name, value, rule });
            }
        }
        out
    }

    /// The first of [`Material::problems`], if any.
    pub fn validate(&self, curve: bool) -> Result<(), DnurbsError> {
        match self.problems(curve).into_iter().next() {
            Some(e) => Err(e),
            None => Ok(()),
        }
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

/// The energy of a D-NURBS (docs/math.md §3, §10): the paper's tension plate or the
/// Kirchhoff–Love shell. In a scene file, `[material] model = "tension-plate"` (the default)
/// or `"kirchhoff-love"`.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
#[serde(tag = "model", rename_all = "kebab-case")]
pub enum MaterialModel {
    /// The paper's energy (α, β per unit parameter area), linear in the control points.
    TensionPlate(Material),
    /// The isogeometric Kirchhoff–Love shell (E, ν, t, ρ), geometrically nonlinear.
    KirchhoffLove(crate::ShellMaterial),
}

impl Default for MaterialModel {
    fn default() -> Self {
        MaterialModel::TensionPlate(Material::default())
    }
}

impl MaterialModel {
    /// "tension-plate" or "kirchhoff-love", as in scene files.
    pub fn name(&self) -> &'static str {
        match self {
            MaterialModel::TensionPlate(_) => "tension-plate",
            MaterialModel::KirchhoffLove(_) => "kirchhoff-love",
        }
    }

    /// The tension plate's coefficients, if the model is the tension plate.
    pub fn tension_plate(&self) -> Option<&Material> {
        match self {
            MaterialModel::TensionPlate(m) => Some(m),
            MaterialModel::KirchhoffLove(_) => None,
        }
    }

    /// The shell material, if the model is the shell.
    pub fn shell(&self) -> Option<&crate::ShellMaterial> {
        match self {
            MaterialModel::TensionPlate(_) => None,
            MaterialModel::KirchhoffLove(m) => Some(m),
        }
    }

    /// The damping per unit mass, `γ / μ` (the shell: `γ / ρt`): the D-NURBS's `D` is this
    /// times its `M` (docs/math.md §3).
    pub fn damping_per_mass(&self) -> f64 {
        match self {
            MaterialModel::TensionPlate(m) => m.gamma / m.mu,
            MaterialModel::KirchhoffLove(m) => m.gamma / m.mass_per_area(),
        }
    }

    /// The mass-proportional damping γ.
    pub fn gamma(&self) -> f64 {
        match self {
            MaterialModel::TensionPlate(m) => m.gamma,
            MaterialModel::KirchhoffLove(m) => m.gamma,
        }
    }
}
