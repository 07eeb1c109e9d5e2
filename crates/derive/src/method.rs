//! The derivations ([`Method`]; [`crate::derive`] runs each). A method knows
//! its default lattice grid and the element classes its lattice is built of; the linear
//! derivations have their own type ([`LinearMethod`]), so that the paper's cannot reach them.

use nurbspring_msm::ParameterGrid;
use serde::{Deserialize, Serialize};

/// Which derivation.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// Class constants and node masses fitted to the lowest D-NURBS modes, then one mass
    /// scale for the lowest frequency (docs/math.md §8.3; the default).
    #[default]
    Modal,
    /// The paper's: eq. (15) and the eigenvalue scan of M (docs/math.md §6).
    Paper,
    /// The modal fit refined on the modes the scene's own loads and initial velocity excite.
    Excitation,
    /// The exact linear reduction of the D-NURBS onto the nodes (not an MSM: a reference).
    Reduction,
    /// Rest-length springs and dihedral hinges from a Kirchhoff–Love shell, calibrated on its
    /// lowest modes (docs/math.md §11; the default for shell scenes).
    Springs,
}

/// How the calibration of a spring model from a Kirchhoff–Love shell groups the elements that
/// share one scale (docs/math.md §11.3).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum SpringGroups {
    /// One scale per element class ([`Method::Springs`]).
    Classes,
    /// One scale per class and band of the lattice along u and v, the groups of the modal
    /// fit ([`crate::Band`]) ([`Method::Modal`] and [`Method::Excitation`] of a shell).
    Bands,
}

/// The element classes a derivation's lattice is built of.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ElementClasses {
    /// The paper's springs: structural, shear and bending, each class with its constant.
    Springs,
    /// The linear elements (docs/math.md §8.1), one constant per element, fitted.
    LinearElements,
    /// Rest-length springs and dihedral hinges on a triangulated lattice (docs/math.md §11).
    SpringsAndHinges,
}

/// The linear derivations (docs/math.md §8): a node-space linear model judged by its exact
/// modes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LinearMethod {
    /// [`Method::Modal`].
    Modal,
    /// [`Method::Excitation`].
    Excitation,
    /// [`Method::Reduction`].
    Reduction,
}

impl Method {
    /// Every derivation.
    pub const ALL: [Method; 5] = [
        Method::Modal,
        Method::Paper,
        Method::Excitation,
        Method::Reduction,
        Method::Springs,
    ];

    /// `"modal"`, `"paper"`, `"excitation"`, `"reduction"` or `"springs"`.
    pub fn name(self) -> &'static str {
        match self {
            Method::Modal => "modal",
            Method::Paper => "paper",
            Method::Excitation => "excitation",
            Method::Reduction => "reduction",
            Method::Springs => "springs",
        }
    }

    /// The calibration groups of the spring model this derivation makes of a Kirchhoff–Love
    /// shell; `None` for a derivation that takes only the tension plate.
    pub fn spring_groups(self) -> Option<SpringGroups> {
        match self {
            Method::Springs => Some(SpringGroups::Classes),
            Method::Modal | Method::Excitation => Some(SpringGroups::Bands),
            Method::Paper | Method::Reduction => None,
        }
    }

    /// True when this derivation takes a Kirchhoff–Love scene (`shell`: a spring model, or the
    /// reduction of the shell linearized at rest) or a tension-plate one.
    pub fn takes(self, shell: bool) -> bool {
        if shell {
            self.spring_groups().is_some() || self == Method::Reduction
        } else {
            self != Method::Springs
        }
    }

    /// The derivations that take a Kirchhoff–Love scene (`shell`) or a tension-plate one,
    /// named and joined for an error message: `"modal", "excitation" or "springs"`.
    pub fn names_taking(shell: bool) -> String {
        Self::names_where(|m| m.takes(shell))
    }

    /// The derivations `keep` keeps, named and joined for an error message.
    pub fn names_where(keep: impl Fn(Method) -> bool) -> String {
        let names: Vec<String> = Self::ALL
            .into_iter()
            .filter(|&m| keep(m))
            .map(|m| format!("\"{}\"", m.name()))
            .collect();
        match names.split_last() {
            Some((last, rest)) if !rest.is_empty() => format!("{} or {last}", rest.join(", ")),
            _ => names.join(""),
        }
    }

    /// Parses a [`Method::name`].
    pub fn parse(s: &str) -> Option<Method> {
        Self::ALL.into_iter().find(|m| m.name() == s)
    }

    /// The linear derivation this is, if it is one.
    pub fn linear(self) -> Option<LinearMethod> {
        match self {
            Method::Modal => Some(LinearMethod::Modal),
            Method::Excitation => Some(LinearMethod::Excitation),
            Method::Reduction => Some(LinearMethod::Reduction),
            Method::Paper | Method::Springs => None,
        }
    }

    /// True for the derivations whose model is linear (validated by exact modes).
    pub fn is_linear(self) -> bool {
        self.linear().is_some()
    }

    /// The lattice grid when the scene names none: the distinct knots for the paper's (its
    /// "u_i ∈ U"), the Greville abscissae (one node per control point) for the others.
    pub fn default_grid(self) -> ParameterGrid {
        match self.element_classes() {
            ElementClasses::Springs => ParameterGrid::Knots,
            ElementClasses::LinearElements | ElementClasses::SpringsAndHinges => {
                ParameterGrid::Greville
            }
        }
    }

    /// The element classes of the lattice: the paper's springs for the paper's derivation,
    /// linear elements for the others.
    pub fn element_classes(self) -> ElementClasses {
        match self {
            Method::Paper => ElementClasses::Springs,
            Method::Modal | Method::Excitation | Method::Reduction => {
                ElementClasses::LinearElements
            }
            Method::Springs => ElementClasses::SpringsAndHinges,
        }
    }
}

impl LinearMethod {
    /// The [`Method`] this is.
    pub fn method(self) -> Method {
        match self {
            LinearMethod::Modal => Method::Modal,
            LinearMethod::Excitation => Method::Excitation,
            LinearMethod::Reduction => Method::Reduction,
        }
    }

    /// True for the derivations that fit element constants and node masses to the D-NURBS
    /// modes (modal, excitation); false for the exact reduction.
    pub fn is_fitted(self) -> bool {
        self != LinearMethod::Reduction
    }
}
