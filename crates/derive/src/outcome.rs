//! What every derivation reports (docs/math.md §8): the derived model, the fit, the masses
//! against the D-NURBS's, stability, a 3-D validation against the exact D-NURBS motion, a
//! second excitation, a frequency table and the warnings a user should read.

use nurbspring_linalg::DenseMatrix;
use nurbspring_msm::{Class, Constants, SpringLattice};
use nurbspring_sim::IntegratorKind;
use serde::Serialize;

use crate::Trajectory;
use crate::fit::FitResult;
use crate::method::Method;
use crate::modal::ModalFitReport;
use crate::reference::ReferenceKind;
use crate::validation::ModalTruncation;

/// One mass candidate of the paper's scan.
#[derive(Clone, Debug, Serialize)]
pub struct MassCandidate {
    /// Node mass tried.
    pub m: f64,
    /// RMS of the central node's z difference to the D-NURBS run (∞, and not written, when the
    /// MSM run failed or was pruned).
    #[serde(skip_serializing_if = "not_finite")]
    pub rms: f64,
    /// Max abs of that difference (as `rms`).
    #[serde(skip_serializing_if = "not_finite")]
    pub max_abs: f64,
    /// Where a pruned run stopped ([`crate::MassScan::Pruned`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pruned: Option<PrunedRun>,
    /// Integrator used for this candidate.
    pub integrator: IntegratorKind,
    /// Its steps per Δt (more than 1: an explicit scheme kept below its stability limit).
    pub substeps: usize,
    /// Why the run stopped early, if it did.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stopped: Option<String>,
}

/// A candidate's run stopped once the running sum of its squared errors exceeded the best
/// complete candidate's total.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct PrunedRun {
    /// The time the run stopped [s].
    pub at: f64,
    /// The lower bound of its RMS over the whole run (above the best's): `√(Σ d² / N)` of the
    /// samples it ran.
    pub rms_at_least: f64,
}

/// Serde's filter for a number that is not written (JSON has no infinity).
pub(crate) fn not_finite(x: &f64) -> bool {
    !x.is_finite()
}

/// The masses: how they were chosen, and their totals against the D-NURBS's.
#[derive(Clone, Debug, Default, Serialize)]
pub struct MassReport {
    /// Distinct non-null eigenvalues of the full M, ascending (the paper's candidates).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub eigenvalues: Vec<f64>,
    /// Distinct eigenvalues of M restricted to the free dofs, ascending.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub eigenvalues_free_dofs: Vec<f64>,
    /// Every candidate tried with its error (the paper's scan).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub candidates: Vec<MassCandidate>,
    /// The node mass selected (per-node masses: their mean over the free nodes).
    pub selected: f64,
    /// How the masses were chosen.
    pub rule: String,
    /// Σ m over every node of the derived model.
    pub total_msm: f64,
    /// Σ m over its free nodes.
    pub free_msm: f64,
    /// The D-NURBS mass `Σ_ij M_ij / 3`.
    pub total_dnurbs: f64,
    /// The free rows' share of it, `Σ_{i free, j} M_ij / 3`.
    pub free_dnurbs: f64,
}

/// A 3-D comparison of one probe.
#[derive(Clone, Debug, Serialize)]
pub struct ProbeError {
    /// Parameters of the probe node, where the D-NURBS is watched.
    pub u: f64,
    /// Parameter v.
    pub v: f64,
    /// The lattice node.
    pub node: usize,
    /// `RMS_t |x_MSM − x_DN| / max_t |x_DN − x_DN(0)|`.
    #[serde(skip_serializing_if = "not_finite")]
    pub relative_rms: f64,
    /// `RMS_t |x_MSM − x_DN|`.
    #[serde(skip_serializing_if = "not_finite")]
    pub rms: f64,
}

/// The derived model against the D-NURBS: the central node in 3-D at its own parameters.
#[derive(Clone, Debug, Serialize)]
pub struct Validation {
    /// How the MSM was run: an integrator's name, or `modal` (its exact solution).
    pub integrator: String,
    /// Steps of the integrator per sampling step (more than 1: an explicit scheme kept below
    /// its stability limit).
    pub substeps: usize,
    /// How the D-NURBS reference was computed.
    pub reference: ReferenceKind,
    /// Length of the comparison [s].
    pub horizon: f64,
    /// Sampling step [s].
    pub dt: f64,
    /// `RMS_t |x_MSM − x_DN|` of the central node.
    #[serde(skip_serializing_if = "not_finite")]
    pub rms: f64,
    /// `max_t |x_MSM − x_DN|`.
    #[serde(skip_serializing_if = "not_finite")]
    pub max_abs: f64,
    /// `rms / max_t |x_DN − x_DN(0)|`.
    #[serde(skip_serializing_if = "not_finite")]
    pub relative_rms: f64,
    /// The same on the z coordinate alone (the paper's Figure 3 reading).
    #[serde(skip_serializing_if = "not_finite")]
    pub relative_rms_z: f64,
    /// `max_t |x_DN − x_DN(0)|`.
    #[serde(skip_serializing_if = "not_finite")]
    pub dnurbs_amplitude: f64,
    /// Dominant period of the D-NURBS central node.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dnurbs_period: Option<f64>,
    /// Dominant period of the MSM central node.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub msm_period: Option<f64>,
    /// Samples compared.
    pub samples: usize,
    /// The largest change of the D-NURBS's total energy (kinetic + elastic + load) over the
    /// comparison, relative to its largest kinetic + elastic energy: zero without damping up
    /// to the integrator's error (round-off for the exact modal reference), the share
    /// dissipated with damping. Absent when the run recorded no energies.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dnurbs_energy_drift: Option<f64>,
    /// The same for the MSM run.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub msm_energy_drift: Option<f64>,
    /// Why the MSM run stopped early, if it did.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub msm_stopped: Option<String>,
    /// Steps of the MSM's implicit integrator taken in halves after Newton failed on them
    /// (absent when none was).
    #[serde(skip_serializing_if = "is_zero")]
    pub msm_halved_steps: usize,
    /// The D-NURBS reference's truncation, when it followed its lowest modes only (a system
    /// above `DENSE_MODES` unknowns).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dnurbs_truncation: Option<ModalTruncation>,
    /// The same for the MSM's modal run.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub msm_truncation: Option<ModalTruncation>,
    /// Every probe.
    pub probes: Vec<ProbeError>,
}

/// Stability, residuals and validation of a derived (or given) parameter set.
#[derive(Clone, Debug, Serialize)]
pub struct ParameterSet {
    /// The constants (`k_edge`, `k_diag`, `k_bend` and the linear classes in files).
    #[serde(flatten)]
    pub constants: Constants,
    /// Node mass (per-node masses: their mean over the free nodes).
    pub m: f64,
    /// ω_max of the linearized MSM at rest.
    pub omega_max: f64,
    /// Explicit stability limit 2/ω_max.
    pub dt_critical: f64,
    /// Whether the scene's Δt exceeds it.
    pub dt_exceeds_explicit_limit: bool,
    /// Relative residual of eq. (15), every dof (the paper's derivation).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub relative_residual_all_dofs: Option<f64>,
    /// Relative residual of eq. (15), free dofs (the paper's derivation).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub relative_residual_free_dofs: Option<f64>,
    /// The comparison with the D-NURBS.
    pub validation: Validation,
    /// When the scene's integrator is explicit and Δt exceeds its limit: what that run does.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub explicit_run: Option<Validation>,
}

/// Angular frequencies (rad/s) of both models linearized at rest, ascending, each with its
/// multiplicity (constant-weight models give triplets; the MSM's zeros are its directions
/// without linear stiffness). A model above `DENSE_MODES` unknowns lists its lowest
/// `TRUNCATED_MODES` (docs/math.md §8.6).
#[derive(Clone, Debug, Default, Serialize)]
pub struct Spectrum {
    /// D-NURBS: `K φ = ω² M φ` on the free dofs.
    pub dnurbs: Vec<f64>,
    /// MSM: `K_T φ = ω² M_S φ` on the free node dofs.
    pub msm: Vec<f64>,
}

/// One line of the frequency table: the i-th distinct frequency of both models and how alike
/// their shapes are at the nodes.
#[derive(Clone, Debug, Serialize)]
pub struct FrequencyRow {
    /// D-NURBS mode number, 1 = lowest.
    pub mode: usize,
    /// D-NURBS angular frequency.
    pub dnurbs: f64,
    /// The MSM mode matched to it (by MAC where the MSM's modes are isotropic triplets,
    /// else by rank), 1 = lowest.
    pub msm_mode: usize,
    /// Its angular frequency.
    pub msm: f64,
    /// `msm / dnurbs − 1`.
    pub relative_difference: f64,
    /// MAC of the two shapes at the free nodes (none when the MSM's modes are not the
    /// isotropic triplets of a linear model).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mac: Option<f64>,
}

/// The regime a derived model may be used in (docs/math.md §8.7).
#[derive(Clone, Debug, Default, Serialize)]
pub struct Regime {
    /// The D-NURBS modes up to this angular frequency each have a matched MSM mode within 1%
    /// (0: not even the lowest).
    pub frequency: f64,
    /// How many D-NURBS modes that is.
    pub modes: usize,
    /// The surface's size: the diagonal of its lattice's bounding box at rest.
    pub size: f64,
    /// The linear range: displacements up to this (a share of the size).
    pub amplitude: f64,
    /// The largest displacement of the D-NURBS at the probes in the scene's own run.
    pub motion: f64,
}

/// What the matrices of a [`NodeReduction`] act on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ReductionCoordinates {
    /// One row per free node: the same matrices act on the x, y and z displacements (the
    /// tension plate's three identical scalar systems).
    Scalar,
    /// Three rows per free node, its x, y and z displacements interleaved (a shell, whose
    /// tangent couples the directions).
    Xyz,
}

impl ReductionCoordinates {
    /// What `reduction.json`'s `ordering` says.
    pub fn ordering(self) -> &'static str {
        match self {
            ReductionCoordinates::Scalar => {
                "scalar matrices on the free nodes: the same K_T, M_T act on the x, y and z displacements"
            }
            ReductionCoordinates::Xyz => {
                "matrices on the free nodes' x, y and z displacements, interleaved (rows 3i, 3i + 1, 3i + 2 are free node i)"
            }
        }
    }
}

/// The exact reduction of the D-NURBS onto the free nodes (the `reduction` derivation): a
/// node-space linear model `M_T ẍ + (γ/μ) M_T ẋ + K_T x = F_T`, the same in x, y and z (the
/// tension plate) or on the nodes' three coordinates (a shell), [`ReductionCoordinates`].
#[derive(Clone, Debug)]
pub struct NodeReduction {
    /// Every node's rest position.
    pub positions: Vec<[f64; 3]>,
    /// Every node's parameters.
    pub params: Vec<(f64, f64)>,
    /// The free nodes, ascending (the rows of the matrices).
    pub free: Vec<usize>,
    /// `K_T`, scalar, on the free nodes.
    pub stiffness: DenseMatrix,
    /// `M_T`, scalar, on the free nodes.
    pub mass: DenseMatrix,
    /// `γ/μ`.
    pub damping_ratio: f64,
    /// `F_T` per free node.
    pub loads: Vec<[f64; 3]>,
    /// True when there are fewer free nodes than free control points (Guyan).
    pub guyan: bool,
    /// What the matrices act on.
    pub coordinates: ReductionCoordinates,
}

/// What the reduction reports.
#[derive(Clone, Debug, Serialize)]
pub struct ReductionReport {
    /// Free nodes.
    pub free_nodes: usize,
    /// Free control points.
    pub free_control_points: usize,
    /// Exact (square Ω) or Guyan (fewer nodes than control points).
    pub kind: &'static str,
}

/// The fit of each derivation.
#[derive(Clone, Debug, Serialize)]
#[serde(untagged)]
pub enum FitDetail {
    /// The paper's eq. (15), every reading.
    Paper(FitReport),
    /// The modal fit.
    Modal(ModalFitReport),
    /// The excitation-aware fit.
    Excitation(ExcitationReport),
    /// The exact reduction.
    Reduction(ReductionReport),
}

/// The model a derivation yields.
#[derive(Clone, Debug)]
pub enum DerivedModel {
    /// A lattice of nodes and elements (every derivation but the reduction).
    Lattice(SpringLattice),
    /// The node-space reduction (the `reduction` derivation: a linear model, not an MSM).
    Reduction(NodeReduction),
}

/// Result of a derivation.
#[derive(Clone, Debug)]
pub struct Derivation {
    /// The derived model.
    pub model: DerivedModel,
    /// The fit; its kind is the derivation's ([`Derivation::method`]).
    pub fit: FitDetail,
    /// The masses.
    pub mass: MassReport,
    /// The derived parameters with their stability and validation.
    pub derived: ParameterSet,
    /// The scene's own `[msm]` parameters, evaluated the same way (the paper's derivation).
    pub given: Option<ParameterSet>,
    /// The MSM run with the scene's own parameters.
    pub given_trajectory: Option<Trajectory>,
    /// The validation under an impulse on one off-centre free control point, which the
    /// model was not derived for.
    pub second_excitation: Validation,
    /// Lowest frequencies of both models, side by side.
    pub frequencies: Vec<FrequencyRow>,
    /// The regime the model may be used in.
    pub regime: Regime,
    /// Probe parameters `(u, v)` (those of the probe nodes), the centre first.
    pub probes: Vec<(f64, f64)>,
    /// Lattice node of each probe.
    pub probe_nodes: Vec<usize>,
    /// The D-NURBS reference run.
    pub dnurbs_trajectory: Trajectory,
    /// The derived MSM run.
    pub msm_trajectory: Trajectory,
    /// Initial node velocities `Ω ṗ(0)` (eq. 18), per node.
    pub node_velocities: Vec<[f64; 3]>,
    /// Angular frequencies of both linearized models.
    pub spectrum: Spectrum,
    /// Every sign of a bad model (docs/math.md §8.7).
    pub warnings: Vec<String>,
}

impl Derivation {
    /// Which derivation this is.
    pub fn method(&self) -> Method {
        match &self.fit {
            FitDetail::Paper(_) => Method::Paper,
            FitDetail::Modal(_) => Method::Modal,
            FitDetail::Excitation(_) => Method::Excitation,
            FitDetail::Reduction(_) => Method::Reduction,
        }
    }

    /// The derived lattice (`None` for the reduction).
    pub fn lattice(&self) -> Option<&SpringLattice> {
        match &self.model {
            DerivedModel::Lattice(l) => Some(l),
            DerivedModel::Reduction(_) => None,
        }
    }

    /// The node-space reduction (the `reduction` derivation only).
    pub fn reduction(&self) -> Option<&NodeReduction> {
        match &self.model {
            DerivedModel::Reduction(r) => Some(r),
            DerivedModel::Lattice(_) => None,
        }
    }

    /// The paper's fit report (the paper's derivation only).
    pub fn paper_fit(&self) -> Option<&FitReport> {
        match &self.fit {
            FitDetail::Paper(f) => Some(f),
            _ => None,
        }
    }
}

/// The four readings of eq. (15) plus the trust-region check.
#[derive(Clone, Debug, Serialize)]
pub struct FitReport {
    /// Classes fitted.
    pub classes: Vec<Class>,
    /// Every dof, unconstrained (the literal equation).
    pub all_dofs: FitResult,
    /// Free dofs only, unconstrained.
    pub free_dofs: FitResult,
    /// Every dof, `k ≥ 0`.
    pub all_dofs_nonnegative: FitResult,
    /// Free dofs only, `k ≥ 0`.
    pub free_dofs_nonnegative: FitResult,
    /// The trust-region solution for the selected reading and its agreement with the closed form.
    pub trust_region: TrustRegionReport,
    /// The reading used for the derived MSM, in words.
    pub selected_reading: String,
    /// The constants used for the derived MSM.
    pub selected: FitResult,
}

/// The trust-region solve of the selected reading.
#[derive(Clone, Debug, Serialize)]
pub struct TrustRegionReport {
    /// Its constants.
    pub result: FitResult,
    /// Iterations.
    pub iterations: usize,
    /// Largest relative difference to the closed form.
    pub max_relative_difference_to_closed_form: f64,
}

/// What the excitation-aware fit reports.
#[derive(Clone, Debug, Serialize)]
pub struct ExcitationReport {
    /// The classes refined (each element's constant is the modal fit's times its class's
    /// scale).
    pub classes: Vec<Class>,
    /// The mean element constant of each class.
    pub constants: Constants,
    /// The same of the modal fit it started from.
    pub modal_constants: Constants,
    /// The D-NURBS modes weighted (1 = lowest) and their shares of the motion.
    pub modes: Vec<(usize, f64)>,
    /// Weighted residual norm at the start and at the end.
    pub residual: (f64, f64),
    /// Levenberg–Marquardt iterations taken.
    pub iterations: usize,
    /// The calibration factor of the masses.
    pub mass_scale: f64,
    /// Explicit step limit `2/ω_max` of the modal fit and of this one.
    pub dt_critical: (f64, f64),
}

/// For `skip_serializing_if`: a count that is zero is left out of the report.
fn is_zero(n: &usize) -> bool {
    *n == 0
}
