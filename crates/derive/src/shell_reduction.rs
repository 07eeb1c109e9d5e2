//! The `reduction` of a Kirchhoff–Love shell (docs/math.md §11.4): the shell linearized at rest
//! (its tangent `K_T(p₀)`, consistent mass and damping, reduced load) carried exactly onto the
//! free lattice nodes' coordinates by [`least_energy_reduction`] with `A = Ω P`, the map from
//! the shell's reduced coordinates to the nodes. Not a spring model: a linear node-space model
//! with dense `3n × 3n` matrices, the reference a spring model's small motion is judged
//! against. Validated as the spring models are (§11.2): the lowest modes matched by MAC and
//! the small-motion run; a linear model has no large motion of its own, so that run is left
//! out and the report says why.

use std::sync::Arc;
use std::sync::atomic::AtomicBool;

use nurbspring_dnurbs::{DnurbsModel, Geometry};
use nurbspring_linalg::generalized_symmetric_eigen;
use nurbspring_sim::{LinearModel, SystemMatrix};
use serde::Serialize;

use crate::linear::{least_energy_reduction, symmetric_sparse};
use crate::outcome::{NodeReduction, ReductionCoordinates};
use crate::springs::{
    ShellModes, SpringFrequency, SpringsConfig, TABLE_SPRING_MODES, bounding_diagonal,
    refuse_unrepresentable, rule_lattice,
};
use crate::springs_check::{self, Check, SmallMotion};
use crate::{DeriveError, Method};

/// A shell's reduction onto the free lattice nodes and its validation.
#[derive(Clone, Debug, Serialize)]
pub struct ShellReduction {
    /// The node-space model (`reduction.json`).
    #[serde(skip)]
    pub reduction: NodeReduction,
    /// Initial node velocities (the scene's, mapped by Ω).
    #[serde(skip)]
    pub node_velocities: Vec<[f64; 3]>,
    /// The lattice node of each probe.
    pub probe_nodes: Vec<usize>,
    /// The size the motions are measured against: the diagonal of the rest surface's bounding
    /// box [m].
    pub size: f64,
    /// `"exact"` (as many free node coordinates as shell unknowns) or `"guyan"` (fewer).
    pub kind: &'static str,
    /// Free lattice nodes.
    pub free_nodes: usize,
    /// The shell's unknowns (free control-point coordinates).
    pub shell_dofs: usize,
    /// The lowest shell modes and the reduced model's modes matched to them.
    pub frequencies: Vec<SpringFrequency>,
    /// The small-motion run.
    pub small_motion: SmallMotion,
    /// Why there is no large-motion run.
    pub large_motion_skipped: String,
    /// The one-line verdict.
    pub verdict: String,
}

impl ShellReduction {
    /// `"exactly"` or `"by Guyan's method"`, as [`ShellReduction::kind`] says.
    pub fn how(&self) -> &'static str {
        if self.reduction.guyan {
            "by Guyan's method"
        } else {
            "exactly"
        }
    }
}

/// Reduces the shell of a Kirchhoff–Love scene onto its free lattice nodes and validates the
/// reduction (module docs).
pub fn reduce_shell(
    config: &SpringsConfig,
    cancel: Option<Arc<AtomicBool>>,
) -> Result<ShellReduction, DeriveError> {
    if config.method != Method::Reduction {
        return Err(DeriveError::InvalidInput {
            input: crate::Input::Derivation,
            value: format!("\"{}\"", config.method.name()),
            reason: "the shell's reduction is the reduction derivation".into(),
        });
    }
    let geometry = Geometry::Surface(config.surface.clone());
    let model = DnurbsModel::kirchhoff_love(
        geometry.clone(),
        config.shell,
        config.loads.clone(),
        &config.constraints,
        config.dnurbs.clone(),
    )?;
    refuse_unrepresentable(&model, &config.loads)?;
    let (lattice, _) = rule_lattice(
        &config.surface,
        &config.shell,
        &config.lattice,
        model.fixed_points(),
    )?;
    let map = springs_check::NodeMap::new(&geometry, &lattice, &model)?;
    let rows = map.free_rows().to_vec();
    let (k_t, m_t, t) = least_energy_reduction(
        model.reduced_stiffness(),
        model.reduced_mass(),
        map.free_matrix(),
        &|r| rows[r] / 3,
    )?;
    let (n, n_q) = (t.ncols(), t.nrows());
    // Tᵀ f of a reduced shell load.
    let carried = |f: &[f64]| -> Vec<f64> {
        (0..n)
            .map(|a| (0..n_q).map(|i| t[(i, a)] * f[i]).sum())
            .collect()
    };
    let ratio = config.shell.gamma / config.shell.mass_per_area();
    let (k_sparse, m_sparse) = (symmetric_sparse(&k_t), symmetric_sparse(&m_t));
    let damping = (ratio > 0.0).then(|| {
        let mut c = m_sparse.clone();
        c.scale(ratio);
        SystemMatrix::Sparse(c)
    });
    let rest: Vec<f64> = {
        let x = lattice.flat_positions();
        rows.iter().map(|&r| x[r]).collect()
    };
    let node_model = |f: &[f64]| -> Result<LinearModel, DeriveError> {
        Ok(LinearModel {
            mass: SystemMatrix::Sparse(m_sparse.clone()),
            damping: damping.clone(),
            stiffness: k_sparse.clone(),
            rest: rest.clone(),
            force: carried(f),
        })
    };
    // The frequencies: the shell's lowest modes against the reduction's, matched by MAC.
    let shell = ShellModes::new(&model, &map, TABLE_SPRING_MODES)?;
    let eig = generalized_symmetric_eigen(&k_t, &m_t)?;
    let count = (shell.rigid.len() + 3 * TABLE_SPRING_MODES).min(n);
    let omega: Vec<f64> = eig.values[..count]
        .iter()
        .map(|l| l.max(0.0).sqrt())
        .collect();
    let shapes: Vec<Vec<f64>> = (0..count).map(|j| eig.vectors.column(j)).collect();
    let frequencies = shell.table(&omega, &shapes);
    let size = bounding_diagonal(&lattice.positions);
    let probe_nodes: Vec<usize> = config
        .probes
        .iter()
        .map(|&(u, v)| lattice.node_nearest(u, v))
        .collect();
    let check = Check {
        model: &model,
        lattice: &lattice,
        map: &map,
        size,
        omega1: shell.omega[0],
        mechanism: !shell.rigid.is_empty(),
        time: &config.time,
        cancel,
    };
    let first_elastic = shell.modes.vectors.column(shell.elastic[0]);
    let small_motion = check.small_motion(
        &config.initial,
        probe_nodes[0],
        &shell.rigid,
        &first_elastic,
        &node_model,
    )?;
    let loads: Vec<[f64; 3]> = carried(model.reduced_force())
        .chunks(3)
        .map(|c| [c[0], c[1], c[2]])
        .collect();
    let free: Vec<usize> = rows.iter().step_by(3).map(|&r| r / 3).collect();
    let guyan = n < n_q;
    let node_velocities = map.node_velocities(&config.initial.state(&model));
    let mut out = ShellReduction {
        reduction: NodeReduction {
            positions: lattice.positions.clone(),
            params: lattice.params.clone().unwrap_or_default(),
            free: free.clone(),
            stiffness: k_t,
            mass: m_t,
            damping_ratio: ratio,
            loads,
            guyan,
            coordinates: ReductionCoordinates::Xyz,
        },
        node_velocities,
        probe_nodes,
        size,
        kind: if guyan { "guyan" } else { "exact" },
        free_nodes: free.len(),
        shell_dofs: n_q,
        frequencies,
        small_motion,
        large_motion_skipped: "a linear model: under large motion it moves as the shell \
                               linearized at rest, which the springs derivation's large-motion \
                               check measures against the shell itself"
            .into(),
        verdict: String::new(),
    };
    out.verdict = verdict(&out);
    Ok(out)
}

/// The one-line verdict: the reduction reproduces the shell linearized at rest (exact) or its
/// lowest modes (Guyan), in small motion only.
fn verdict(r: &ShellReduction) -> String {
    let worst = r
        .frequencies
        .iter()
        .map(|f| f.relative_error.map_or(f64::INFINITY, f64::abs))
        .fold(0.0, f64::max);
    format!(
        "The shell linearized at rest, reduced {} onto {} free nodes ({} shell unknowns): for \
         small motion only; the lowest {} modes within {:.1e}, small motion: probe error {:.2e} \
         over {:.0} periods",
        r.how(),
        r.free_nodes,
        r.shell_dofs,
        r.frequencies.len(),
        worst,
        r.small_motion.relative_rms,
        r.small_motion.periods
    )
}
