//! The Kirchhoff–Love shell material: St. Venant–Kirchhoff, plane stress (docs/math.md §10).

use crate::DnurbsError;

/// A homogeneous isotropic St. Venant–Kirchhoff material of a thin shell (docs/math.md §10.1):
/// Young's modulus `E`, Poisson's ratio `ν`, thickness `t`, mass density `ρ` (per volume) and
/// mass-proportional damping `γ` (per area, as the tension plate's `gamma`).
///
/// The shell's stiffnesses follow: membrane `E t / (1 − ν²)`, bending
/// `D = E t³ / (12 (1 − ν²))`, mass per area `ρ t`.
///
/// ```
/// use nurbspring_dnurbs::ShellMaterial;
/// // 1 mm steel: D = 210e9 · 1e-9 / (12 · 0.91) = 19.23 N·m.
/// let steel = ShellMaterial { young: 210e9, poisson: 0.3, thickness: 1e-3, density: 7850.0, gamma: 0.0 };
/// assert!((steel.bending_stiffness() - 19.230769230769).abs() < 1e-9);
/// assert!((steel.mass_per_area() - 7.85).abs() < 1e-12);
/// assert!(steel.validate().is_ok());
/// let bad = ShellMaterial { poisson: 0.5, ..steel };
/// assert_eq!(bad.validate().unwrap_err().to_string(),
///     "material.poisson = 0.5: Poisson's ratio must be in [0, 0.5)");
/// ```
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ShellMaterial {
    /// Young's modulus E (force / area), > 0.
    pub young: f64,
    /// Poisson's ratio ν, in `[0, 0.5)`.
    pub poisson: f64,
    /// Thickness t (length), > 0.
    pub thickness: f64,
    /// Mass density ρ (mass / volume), > 0.
    pub density: f64,
    /// Mass-proportional damping γ (mass / time per area): `D = γ ∫ R Rᵀ dA ⊗ I₃`, ≥ 0.
    #[serde(default)]
    pub gamma: f64,
}

impl ShellMaterial {
    /// The values with their names, in declaration order.
    pub fn named(&self) -> [(&'static str, f64); 5] {
        [
            ("young", self.young),
            ("poisson", self.poisson),
            ("thickness", self.thickness),
            ("density", self.density),
            ("gamma", self.gamma),
        ]
    }

    /// Membrane stiffness `E t / (1 − ν²)` (force / length).
    pub fn membrane_stiffness(&self) -> f64 {
        self.young * self.thickness / (1.0 - self.poisson * self.poisson)
    }

    /// Bending stiffness `D = E t³ / (12 (1 − ν²))` (force · length).
    pub fn bending_stiffness(&self) -> f64 {
        self.membrane_stiffness() * self.thickness * self.thickness / 12.0
    }

    /// Mass per unit area `ρ t`.
    pub fn mass_per_area(&self) -> f64 {
        self.density * self.thickness
    }

    /// Every rule on the values, each problem naming its field: all finite, `E`, `t`, `ρ`
    /// positive, `0 ≤ ν < 0.5` (a plane-stress tensor that is positive definite and, for the
    /// spring derivations, a Poisson ratio springs can approach), `γ ≥ 0`. Empty when valid.
    pub fn problems(&self) -> Vec<DnurbsError> {
        let mut out = Vec::new();
        for (name, value) in self.named() {
            let rule = if !nurbspring_sim::representable(value) {
                Some("must be a finite number of magnitude at most 1e30 (larger values overflow)")
            } else {
                match name {
                    "young" if value <= 0.0 => Some("Young's modulus must be positive"),
                    "thickness" if value <= 0.0 => Some("the thickness must be positive"),
                    "density" if value <= 0.0 => Some("the mass density must be positive"),
                    "poisson" if !(0.0..0.5).contains(&value) => {
                        Some("Poisson's ratio must be in [0, 0.5)")
                    }
                    "gamma" if value < 0.0 => Some("the damping must not be negative"),
                    _ => None,
                }
            };
            if let Some(rule) = rule {
                out.push(DnurbsError::InvalidMaterial { name, value, rule });
            }
        }
        out
    }

    /// The first of [`ShellMaterial::problems`], if any.
    pub fn validate(&self) -> Result<(), DnurbsError> {
        match self.problems().into_iter().next() {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }

    /// The plane-stress material tensor `C^{αβγδ}` of the rest metric, in Voigt form over
    /// `(11, 22, 12)` (docs/math.md §10.1):
    /// `C^{αβγδ} = E/(1 − ν²) [ν A^{αβ} A^{γδ} + ½ (1 − ν)(A^{αγ} A^{βδ} + A^{αδ} A^{βγ})]`
    /// with `A^{αβ}` the inverse of the rest metric, given as `[A^{11}, A^{22}, A^{12}]`.
    /// With the Voigt strain `[ε11, ε22, 2 ε12]`, `ε : C : ε = εᵀ C ε`.
    pub fn voigt_tensor(&self, inverse_metric: [f64; 3]) -> [[f64; 3]; 3] {
        let [g11, g22, g12] = inverse_metric;
        let g = |a: usize, b: usize| match (a, b) {
            (0, 0) => g11,
            (1, 1) => g22,
            _ => g12,
        };
        let nu = self.poisson;
        let scale = self.young / (1.0 - nu * nu);
        let c = |a: usize, b: usize, c: usize, d: usize| {
            scale
                * (nu * g(a, b) * g(c, d)
                    + 0.5 * (1.0 - nu) * (g(a, c) * g(b, d) + g(a, d) * g(b, c)))
        };
        const VOIGT: [(usize, usize); 3] = [(0, 0), (1, 1), (0, 1)];
        std::array::from_fn(|i| {
            std::array::from_fn(|j| c(VOIGT[i].0, VOIGT[i].1, VOIGT[j].0, VOIGT[j].1))
        })
    }
}
