//! The linear derivations (docs/math.md §8): `modal` (the default), `excitation` and
//! `reduction`. Each yields a node-space linear model on the lattice's free nodes, judged by
//! its exact modes against the exact D-NURBS motion.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use nurbspring_dnurbs::Integration;
use nurbspring_geom::{area_element, line_element};
use nurbspring_linalg::{DenseMatrix, LuSolver, SparseMatrix, SpdSolver, symmetric_eigen};
use nurbspring_msm::{Class, Constants, SpringLattice, dual_spacing};
use nurbspring_sim::StabilityLimit;

use crate::error::{DeriveError, Input};
use crate::evaluation::{
    DnurbsModes, REGIME_MODES, frequency_table, impulse, initial_speed, matched_modes, node_watch,
    regime, triplicate, unloaded, validation, warnings, with_totals,
};
use crate::excitation::excitation_fit;
use crate::method::LinearMethod;
use crate::modal::{FITTED_MODES, SampledMode, element_priors, modal_fit};
use crate::modal_solution::ModalBasis;
use crate::nodes::NodeMap;
use crate::outcome::{
    Derivation, DerivedModel, FitDetail, MassReport, NodeReduction, ParameterSet,
    ReductionCoordinates, ReductionReport, Spectrum,
};
use crate::pipeline::Judge;
use crate::reference::{run_scalar, scalar_rows};
use crate::scalar::{EnergyOrigin, ScalarSystem};
use crate::setup::{Config, Setup};

/// A load below this fraction of the largest is no load (round-off).
const NO_LOAD: f64 = 1e-12;
/// D-NURBS modes sampled at the nodes for the modal fit to choose from.
const CANDIDATE_MODES: usize = 4 * FITTED_MODES;

/// The area factor of each lattice node: `|c_u × c_v|` (a curve: `|c_u|`) at its `(u, v)`
/// under area integration, 1 under the parameter measure.
fn area_factors(setup: &Setup, config: &Config) -> Result<Vec<f64>, DeriveError> {
    let lattice = setup.lattice();
    let params = lattice
        .params
        .as_ref()
        .ok_or(DeriveError::LatticeWithoutParameters)?;
    if config.dnurbs.integration != Integration::Area {
        return Ok(vec![1.0; params.len()]);
    }
    params
        .iter()
        .map(|&(u, v)| -> Result<f64, DeriveError> {
            Ok(match setup.model().geometry() {
                nurbspring_dnurbs::Geometry::Surface(s) => {
                    let d = s.derivatives(u, v, 1)?;
                    area_element(d.u, d.v)
                }
                nurbspring_dnurbs::Geometry::Curve(c) => line_element(c.derivatives(u, 1)?.u),
            })
        })
        .collect()
}

/// The mass of each node's dual cell in parameter space, `μ τ_u τ_v` times its area factor
/// (a chain: `μ τ_u`).
fn dual_cell_masses(setup: &Setup, config: &Config, area: &[f64]) -> Result<Vec<f64>, DeriveError> {
    let lattice = setup.lattice();
    let (n_u, n_v) = lattice.grid.unwrap_or((lattice.n_nodes(), 1));
    let params = lattice
        .params
        .as_ref()
        .ok_or(DeriveError::LatticeWithoutParameters)?;
    let us: Vec<f64> = (0..n_u).map(|i| params[i * n_v].0).collect();
    let vs: Vec<f64> = (0..n_v).map(|j| params[j].1).collect();
    let (tu, tv) = (dual_spacing(&us), dual_spacing(&vs));
    let mut out = Vec::with_capacity(lattice.n_nodes());
    for i in 0..n_u {
        for j in 0..n_v {
            out.push(config.material.mu * tu[i] * tv[j] * area[i * n_v + j]);
        }
    }
    Ok(out)
}

/// Reference masses of the free nodes: the row sums of `M_T = Ω_ff⁻ᵀ S_M Ω_ff⁻¹` when Ω_ff is
/// square and invertible, the dual-cell masses elsewhere (and where a row sum is not
/// positive). Also `Ω_ff⁻ᵀ` applied to loads, when it exists.
struct Pullback {
    reference: Vec<f64>,
    transposed: Option<LuSolver>,
}

impl Pullback {
    fn new(map: &NodeMap, modes: &DnurbsModes, dual: &[f64]) -> Self {
        let fallback: Vec<f64> = map.free.iter().map(|&a| dual[a]).collect();
        if !map.is_square() {
            return Self {
                reference: fallback,
                transposed: None,
            };
        }
        let (Ok(lu), Ok(lu_t)) = (
            LuSolver::new(&map.omega_ff),
            LuSolver::new(&map.omega_ff.transpose()),
        ) else {
            return Self {
                reference: fallback,
                transposed: None,
            };
        };
        let y = lu.solve(&vec![1.0; map.free.len()]);
        let mut z = vec![0.0; y.len()];
        modes.system.mass.mul_vec(&y, &mut z);
        let rows = lu_t.solve(&z);
        let reference = rows
            .iter()
            .zip(&fallback)
            .map(|(&r, &f)| if r.is_finite() && r > 0.0 { r } else { f })
            .collect();
        Self {
            reference,
            transposed: Some(lu_t),
        }
    }
}

/// The loads of the D-NURBS's free control points other than gravity, carried to the free
/// nodes by `Ω_ff⁻ᵀ` (exact on a Greville lattice); `None` when there are none, a warning
/// when they cannot be carried.
fn node_loads(
    setup: &Setup,
    config: &Config,
    modes: &DnurbsModes,
    pullback: &Pullback,
    warnings: &mut Vec<String>,
) -> Vec<[f64; 3]> {
    let sys = &modes.system;
    let model = setup.model();
    let s_m = scalar_rows(&model.matrices().mass);
    let mut ones = vec![0.0; s_m.nrows()];
    s_m.mul_vec(&vec![1.0; s_m.ncols()], &mut ones);
    let g = config.loads.gravity;
    let other: Vec<[f64; 3]> = sys
        .free
        .iter()
        .zip(&sys.load)
        .map(|(&k, f)| [0, 1, 2].map(|x| f[x] - ones[k] * g[x]))
        .collect();
    let size = |v: &[[f64; 3]]| v.iter().flatten().fold(0.0_f64, |a, x| a.max(x.abs()));
    let scale = size(&sys.load).max(f64::MIN_POSITIVE);
    let n = setup.lattice().n_nodes();
    if size(&other) <= NO_LOAD * scale {
        return Vec::new();
    }
    let Some(lu_t) = &pullback.transposed else {
        warnings.push(
            "loads other than gravity (distributed, point loads, or a rest shape out of equilibrium) are not carried to this lattice: use the Greville grid".to_string(),
        );
        return Vec::new();
    };
    let mut out = vec![[0.0; 3]; n];
    let free = &setup
        .lattice()
        .fixed
        .iter()
        .enumerate()
        .filter(|(_, f)| !**f)
        .map(|(a, _)| a)
        .collect::<Vec<_>>();
    for x in 0..3 {
        let col: Vec<f64> = other.iter().map(|f| f[x]).collect();
        for (i, v) in lu_t.solve(&col).into_iter().enumerate() {
            out[free[i]][x] = v;
        }
    }
    out
}

/// The element classes of `lattice` with the stiffness of each, every element with its own
/// constant, on the free nodes.
fn class_stiffness(lattice: &SpringLattice, free: &[usize]) -> (Vec<Class>, Vec<SparseMatrix>) {
    let classes: Vec<Class> = lattice
        .classes()
        .into_iter()
        .filter(|c| matches!(c, Class::Linear(..)))
        .collect();
    let stiffness = classes
        .iter()
        .map(|&c| {
            let mut only = lattice.clone();
            only.elements.retain(|e| e.class() == c);
            only.linear_matrix(None).submatrix(free, free)
        })
        .collect();
    (classes, stiffness)
}

/// The D-NURBS's static deflection `Ω_ff K⁻¹ f` at the free nodes under its constant load;
/// `None` when nothing is loaded or K is singular (a body free to move).
fn static_deflection(modes: &DnurbsModes, map: &NodeMap) -> Option<Vec<[f64; 3]>> {
    let load = &modes.system.load;
    if load.iter().flatten().all(|&x| x == 0.0) {
        return None;
    }
    let solution = modes.basis.static_solve(load)?;
    let mut out = vec![[0.0; 3]; map.free.len()];
    for x in 0..3 {
        let column: Vec<f64> = solution.iter().map(|u| u[x]).collect();
        for (o, v) in out.iter_mut().zip(map.at_nodes(&column)) {
            o[x] = v;
        }
    }
    Some(out)
}

/// The node forces that make the static deflection of the linear model `L` with masses
/// `masses` under gravity `g` the D-NURBS's, `F = L X − m g` (docs/math.md §8.2), on every
/// lattice node (zero at fixed ones).
fn static_forces(
    l: &SparseMatrix,
    masses: &[f64],
    g: [f64; 3],
    deflection: &[[f64; 3]],
    map: &NodeMap,
    nodes: usize,
) -> Vec<[f64; 3]> {
    let mut out = vec![[0.0; 3]; nodes];
    for x in 0..3 {
        let column: Vec<f64> = deflection.iter().map(|d| d[x]).collect();
        let mut lx = vec![0.0; column.len()];
        l.mul_vec(&column, &mut lx);
        for (i, &a) in map.free.iter().enumerate() {
            out[a][x] = lx[i] - masses[i] * g[x];
        }
    }
    out
}

/// The mean constant of each element class of a lattice whose elements carry their own
/// constants.
fn class_means(lattice: &SpringLattice) -> Constants {
    let mut sums: std::collections::BTreeMap<Class, (f64, usize)> = Default::default();
    for e in &lattice.elements {
        let entry = sums.entry(e.class()).or_insert((0.0, 0));
        entry.0 += e.k;
        entry.1 += 1;
    }
    Constants::from_pairs(sums.into_iter().map(|(c, (s, n))| (c, s / n as f64)))
}

/// The lowest `count` non-rigid D-NURBS modes sampled at the free nodes.
pub(crate) fn sampled_modes(modes: &DnurbsModes, map: &NodeMap, count: usize) -> Vec<SampledMode> {
    (0..modes.basis.len())
        .filter(|&i| modes.basis.omega[i] > 0.0)
        .take(count)
        .map(|i| SampledMode {
            omega: modes.basis.omega[i],
            shape: map.at_nodes(&modes.basis.mode(i)),
        })
        .collect()
}

/// A node-space linear model on the free nodes, with its initial state from the D-NURBS's.
struct NodeModel {
    system: ScalarSystem,
    basis: ModalBasis,
}

fn node_system(
    setup: &Setup,
    map: &NodeMap,
    mass: SparseMatrix,
    stiffness: SparseMatrix,
    load: Vec<[f64; 3]>,
    damping_ratio: f64,
    basis: Option<ModalBasis>,
) -> Result<NodeModel, DeriveError> {
    let nodes = setup.node_state();
    let pick = |v: &[[f64; 3]]| -> Vec<[f64; 3]> {
        map.free
            .iter()
            .map(|&a| v.get(a).copied().unwrap_or([0.0; 3]))
            .collect()
    };
    let displacement = pick(&nodes.displacements);
    let system = ScalarSystem {
        free: map.free.clone(),
        mass,
        stiffness,
        damping_ratio,
        energy: EnergyOrigin::of_load(&load, &displacement),
        load,
        displacement,
        velocity: pick(&nodes.velocities),
    };
    let basis = match basis {
        Some(b) => b,
        None => ModalBasis::new(&system.stiffness, &system.mass)?,
    };
    Ok(NodeModel { system, basis })
}

/// The reduction of `M ẍ + K x = f` (`nc` unknowns) onto the coordinates `y = A x` (`nn ≤ nc`
/// rows of A): `T = K⁻¹ Aᵀ (A K⁻¹ Aᵀ)⁻¹` maps `y` to the `x` of least energy,
/// `K_T = (A K⁻¹ Aᵀ)⁻¹ = Tᵀ K T`, `M_T = Tᵀ M T`, loads `Tᵀ f`. With `nn = nc`, `T = A⁻¹`
/// (computed as such when A is invertible: no K⁻¹, so a body its constraints leave free to
/// move has one too) and the reduction is exact; with fewer it is Guyan's, which needs a
/// positive-definite K. Returns `(K_T, M_T, T)`;
/// `node_of_row` names the lattice node of a row of A in the error of a singular reduction.
pub(crate) fn least_energy_reduction(
    k: &SparseMatrix,
    m: &SparseMatrix,
    a: &SparseMatrix,
    node_of_row: &dyn Fn(usize) -> usize,
) -> Result<(DenseMatrix, DenseMatrix, DenseMatrix), DeriveError> {
    let (nn, nc) = (a.nrows(), a.ncols());
    if nn > nc {
        return Err(DeriveError::TooManyNodes {
            free_nodes: nn,
            control_points: nc,
        });
    }
    // Square and invertible: T = A⁻¹, a change of coordinates that needs no K⁻¹ (so a body
    // its constraints leave free to move has one too).
    let inverse = || -> Option<DenseMatrix> {
        let lu = LuSolver::new(a).ok()?;
        let mut t = DenseMatrix::zeros(nc, nn);
        let mut e = vec![0.0; nn];
        for j in 0..nn {
            e[j] = 1.0;
            let x = lu.solve(&e);
            e[j] = 0.0;
            if x.iter().any(|v| !v.is_finite()) {
                return None;
            }
            for (i, v) in x.into_iter().enumerate() {
                t[(i, j)] = v;
            }
        }
        Some(t)
    };
    if nn == nc
        && let Some(t) = inverse()
    {
        let congruence = |k: &SparseMatrix| -> DenseMatrix {
            let mut kt = DenseMatrix::zeros(nc, nn);
            let mut y = vec![0.0; nc];
            for j in 0..nn {
                k.mul_vec(&t.column(j), &mut y);
                for (i, &v) in y.iter().enumerate() {
                    kt[(i, j)] = v;
                }
            }
            t.transpose().matmul(&kt)
        };
        return Ok((congruence(k), congruence(m), t));
    }
    let solver = SpdSolver::new(k).map_err(|e| DeriveError::InvalidInput {
        input: Input::Material,
        value: "K".into(),
        reason: format!(
            "the reduction needs a positive-definite stiffness on the free control points (none \
             when the constraints leave the body free to move): {e}"
        ),
    })?;
    let a_t = a.transpose();
    // Y = K⁻¹ Aᵀ, column by column.
    let mut y = DenseMatrix::zeros(nc, nn);
    for j in 0..nn {
        let mut col = vec![0.0; nc];
        let (cp, ri, v) = (a_t.col_ptr(), a_t.row_idx(), a_t.values());
        for k in cp[j]..cp[j + 1] {
            col[ri[k]] = v[k];
        }
        let x = solver.solve(&col);
        for i in 0..nc {
            y[(i, j)] = x[i];
        }
    }
    let s = a.to_dense().matmul(&y);
    let eig = symmetric_eigen(&s)?;
    let top = eig.values.last().copied().unwrap_or(0.0);
    if let Some((i, &l)) = eig
        .values
        .iter()
        .enumerate()
        .find(|(_, l)| **l <= 1e-13 * top)
    {
        let v = eig.vectors.column(i);
        let mut worst: Vec<usize> = (0..nn)
            .filter(|&r| v[r].abs() > 0.1)
            .map(node_of_row)
            .collect();
        worst.dedup();
        return Err(DeriveError::InvalidInput {
            input: Input::Grid,
            value: format!("eigenvalue {l:e} of A K⁻¹ Aᵀ"),
            reason: format!(
                "the reduction is singular: the nodes {worst:?} do not determine the surface"
            ),
        });
    }
    let k_t = DenseMatrix::from_fn(nn, nn, |a, b| {
        (0..nn)
            .map(|i| eig.vectors[(a, i)] * eig.vectors[(b, i)] / eig.values[i])
            .sum()
    });
    let t = y.matmul(&k_t);
    let m_t = t.transpose().matmul(&m.to_dense()).matmul(&t);
    Ok((k_t, m_t, t))
}

/// The exact reduction of the D-NURBS onto the free nodes ([`least_energy_reduction`] with
/// `A = Ω_ff`, on the scalar system): `(K_T, M_T, F_T)`.
fn reduction(
    map: &NodeMap,
    modes: &DnurbsModes,
) -> Result<(DenseMatrix, DenseMatrix, Vec<[f64; 3]>), DeriveError> {
    let sys = &modes.system;
    let (k_t, m_t, t) =
        least_energy_reduction(&sys.stiffness, &sys.mass, &map.omega_ff, &|a| map.free[a])?;
    let (nn, nc) = (t.ncols(), t.nrows());
    let mut f_t = vec![[0.0; 3]; nn];
    for a in 0..nn {
        for i in 0..nc {
            for x in 0..3 {
                f_t[a][x] += t[(i, a)] * sys.load[i][x];
            }
        }
    }
    Ok((k_t, m_t, f_t))
}

pub(crate) fn symmetric_sparse(a: &DenseMatrix) -> SparseMatrix {
    let sym = DenseMatrix::from_fn(a.nrows(), a.ncols(), |i, j| 0.5 * (a[(i, j)] + a[(j, i)]));
    SparseMatrix::from_dense(&sym, 0.0)
}

/// Derives a linear node model of the D-NURBS by `method` (modal, excitation or reduction)
/// and validates it by exact modes; `cancel` stops between steps.
pub(crate) fn derive_linear(
    config: &Config,
    method: LinearMethod,
    cancel: Option<Arc<AtomicBool>>,
) -> Result<(Derivation, Setup), DeriveError> {
    let setup = Setup::new(config)?;
    let modes = DnurbsModes::new(&setup, method.method().name())?;
    let map = NodeMap::new(&setup, &modes)?;
    let area = area_factors(&setup, config)?;
    let dual = dual_cell_masses(&setup, config, &area)?;
    let pullback = Pullback::new(&map, &modes, &dual);
    let mut warn = Vec::new();
    // A fitted model holds the D-NURBS's static deflection (its node forces are made for it);
    // otherwise, and for the reduction, the loads are carried by `Ω_ff⁻ᵀ`.
    let deflection = if method.is_fitted() {
        static_deflection(&modes, &map)
    } else {
        None
    };
    let forces = if deflection.is_some() {
        Vec::new()
    } else {
        node_loads(&setup, config, &modes, &pullback, &mut warn)
    };
    let cancelled = || cancel.as_ref().is_some_and(|c| c.load(Ordering::Relaxed));
    let ratio = modes.system.damping_ratio;
    let g = config.loads.gravity;
    let free_forces = |masses: &[f64], forces: &[[f64; 3]]| -> Vec<[f64; 3]> {
        map.free
            .iter()
            .zip(masses)
            .map(|(&a, &m)| {
                let f = forces.get(a).copied().unwrap_or([0.0; 3]);
                [0, 1, 2].map(|x| m * g[x] + f[x])
            })
            .collect()
    };
    let (model, fit, node, rule) = match method {
        LinearMethod::Modal | LinearMethod::Excitation => {
            let priors =
                element_priors(setup.lattice(), config.material.stiffness_by_slot(), &area);
            let candidates = sampled_modes(&modes, &map, CANDIDATE_MODES);
            let modal = modal_fit(
                setup.lattice(),
                &map.free,
                &priors,
                &candidates,
                &pullback.reference,
            )?;
            // The fitted lattice: every element with its own constant, those left at 0 gone.
            let mut lattice = setup.lattice().clone();
            for (e, &k) in lattice.elements.iter_mut().zip(&modal.constants) {
                e.k = k;
            }
            lattice.elements.retain(|e| e.k > 0.0);
            let (masses, fit, basis) = if method == LinearMethod::Excitation {
                let (classes, stiffness) = class_stiffness(&lattice, &map.free);
                let e = excitation_fit(
                    &modes,
                    &map,
                    &classes,
                    &stiffness,
                    &modal,
                    &pullback.reference,
                )?;
                warn.extend(e.warnings.iter().cloned());
                for el in &mut lattice.elements {
                    el.k *= e.scales.value(el.class());
                }
                (e.masses.clone(), FitDetail::Excitation(e.report), None)
            } else {
                // The fit's own modes are the model's: L and the masses are the same.
                (
                    modal.masses.clone(),
                    FitDetail::Modal(modal.report),
                    Some(modal.basis),
                )
            };
            let mut all = dual.clone();
            for (i, &a) in map.free.iter().enumerate() {
                all[a] = masses[i];
            }
            lattice.damping = all.iter().map(|m| ratio * m).collect();
            lattice.masses = all;
            let l = lattice.linear_matrix(None).submatrix(&map.free, &map.free);
            lattice.forces = match &deflection {
                Some(x) => static_forces(&l, &masses, g, x, &map, lattice.n_nodes()),
                None => forces.clone(),
            };
            let node = node_system(
                &setup,
                &map,
                SparseMatrix::from_diagonal(&masses),
                l,
                free_forces(&masses, &lattice.forces),
                ratio,
                basis,
            )?;
            let rule = "one mass per free node, fitted with the element constants to the D-NURBS modes the lattice resolves near the reference masses (row sums of M_T), then scaled so that the lowest frequency matches".to_string();
            (DerivedModel::Lattice(lattice), fit, node, rule)
        }
        LinearMethod::Reduction => {
            let (k_t, m_t, f_t) = reduction(&map, &modes)?;
            let guyan = !map.is_square();
            let node = node_system(
                &setup,
                &map,
                symmetric_sparse(&m_t),
                symmetric_sparse(&k_t),
                f_t.clone(),
                ratio,
                None,
            )?;
            let lattice = setup.lattice();
            let reduction = NodeReduction {
                positions: lattice.positions.clone(),
                params: lattice.params.clone().unwrap_or_default(),
                free: map.free.clone(),
                stiffness: k_t,
                mass: m_t,
                damping_ratio: ratio,
                loads: f_t,
                guyan,
                coordinates: ReductionCoordinates::Scalar,
            };
            let fit = FitDetail::Reduction(ReductionReport {
                free_nodes: map.free.len(),
                free_control_points: modes.system.n(),
                kind: if guyan { "guyan" } else { "exact" },
            });
            let rule = "the node-space mass matrix M_T of the reduction (its row sums are listed as node masses)".to_string();
            (DerivedModel::Reduction(reduction), fit, node, rule)
        }
    };
    if cancelled() {
        return Err(DeriveError::Cancelled);
    }
    // Validation by exact modes (Newmark when damped).
    let judge = Judge::new(&setup, config, Some(modes))?;
    let modes = judge.modes().ok_or(DeriveError::LatticeWithoutParameters)?;
    let reference = judge.reference()?;
    let positions = &setup.lattice().positions;
    let watch = node_watch(setup.probe_nodes(), &map.free, positions);
    let (msm_trajectory, _) =
        run_scalar(&node.system, &node.basis, &watch, &judge.times, judge.dt)?;
    let validation_main = validation(
        &setup,
        &reference.0,
        reference.1,
        &msm_trajectory,
        reference.1.name().to_string(),
        1,
        judge.horizon,
        judge.dt,
    );
    if cancelled() {
        return Err(DeriveError::Cancelled);
    }
    // The second excitation.
    let kick = impulse(&setup, initial_speed(setup.dnurbs_initial()))?;
    let kick_reference = judge.impulse_reference(&kick)?;
    let kick_nodes = setup.omega().node_state(setup.model(), &kick);
    let kick_velocity: Vec<[f64; 3]> = map.free.iter().map(|&a| kick_nodes.velocities[a]).collect();
    let kick_system = unloaded(&node.system, vec![[0.0; 3]; map.free.len()], kick_velocity);
    let (kick_run, _) = run_scalar(&kick_system, &node.basis, &watch, &judge.times, judge.dt)?;
    let second_excitation = validation(
        &setup,
        &kick_reference.0,
        kick_reference.1,
        &kick_run,
        kick_reference.1.name().to_string(),
        1,
        judge.horizon,
        judge.dt,
    );
    let frequencies = frequency_table(&modes.basis, &map.omega_ff, &node.basis);
    let regime = regime(
        &setup,
        &reference.0,
        &matched_modes(&modes.basis, &map.omega_ff, &node.basis, REGIME_MODES),
    );
    let spectrum = Spectrum {
        dnurbs: triplicate(&modes.basis.omega),
        msm: triplicate(&node.basis.omega),
    };
    // Masses: the lattice's, or the reduction's row sums of M_T on the free nodes.
    let node_masses: Vec<f64> = match &model {
        DerivedModel::Lattice(l) => l.masses.clone(),
        DerivedModel::Reduction(_) => {
            let mut all = dual.clone();
            let sums = {
                let mut y = vec![0.0; map.free.len()];
                node.system.mass.mul_vec(&vec![1.0; map.free.len()], &mut y);
                y
            };
            for (i, &a) in map.free.iter().enumerate() {
                all[a] = sums[i];
            }
            all
        }
    };
    let fixed = &setup.lattice().fixed;
    let free_masses: Vec<f64> = map.free.iter().map(|&a| node_masses[a]).collect();
    let mean = free_masses.iter().sum::<f64>() / free_masses.len() as f64;
    let mass = with_totals(
        MassReport {
            selected: mean,
            rule,
            ..MassReport::default()
        },
        setup.model(),
        &node_masses,
        fixed,
    );
    let omega_max = node.basis.omega_max()?;
    let limit = StabilityLimit::from_omega_max(omega_max);
    let derived = ParameterSet {
        constants: match &model {
            DerivedModel::Lattice(l) => class_means(l),
            DerivedModel::Reduction(_) => Constants::new(),
        },
        m: mean,
        omega_max,
        dt_critical: limit.dt_critical,
        dt_exceeds_explicit_limit: config.time.dt >= limit.dt_critical,
        relative_residual_all_dofs: None,
        relative_residual_free_dofs: None,
        validation: validation_main,
        explicit_run: None,
    };
    warn.extend(warnings(
        method.method(),
        &derived.validation,
        &second_excitation,
        &frequencies,
        &mass,
        &[],
        &regime,
    ));
    let derivation = Derivation {
        model,
        fit,
        mass,
        derived,
        given: None,
        given_trajectory: None,
        second_excitation,
        frequencies,
        regime,
        probes: setup.probes().to_vec(),
        probe_nodes: setup.probe_nodes().to_vec(),
        dnurbs_trajectory: reference.0,
        msm_trajectory,
        node_velocities: setup.node_velocities().to_vec(),
        spectrum,
        warnings: warn,
    };
    Ok((derivation, setup))
}
