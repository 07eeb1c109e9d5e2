//! The calibration of a spring model on the shell's modes (docs/math.md §11.1, §11.3): the
//! groups whose elements share one scale (by class, or by class and band), the shell's lowest
//! modes, the modes the scene's excitation moves (the `excitation` derivation), and the
//! Gauss–Newton fit of the log scales to the log frequency ratios of the modes matched by MAC.

use std::collections::BTreeMap;

use nurbspring_dnurbs::DnurbsModel;
use nurbspring_linalg::{DenseMatrix, SparseMatrix, least_squares};
use nurbspring_msm::{Class, Constants, SpringLattice};

use super::{
    BAND_PULL, BAND_SPRING_MODES, CALIBRATION_ITERATIONS, EXCITATION_CANDIDATES, ExcitedMode,
    GroupScale, RIGID_FREQUENCY, RIGID_MODES, SPRING_MODES, SPRING_PULL, STEP_HALVINGS,
    SpringFrequency, TABLE_SPRING_MODES,
};
use crate::excitation::{EXCITED_MODES, amplitude2};
use crate::modal::Band;
use crate::springs_check;
use crate::{DeriveError, InitialConditions, SpringGroups, match_modes};

/// The calibration's groups: the class of each, its name, and the group of every spring and
/// hinge.
struct Grouping {
    classes: Vec<Class>,
    names: Vec<String>,
    springs: Vec<usize>,
    hinges: Vec<usize>,
}

impl Grouping {
    /// The groups of `lattice`'s springs and hinges: their classes, or their classes and bands
    /// along u and v ([`Band::of`] the lines their nodes span), in order of first appearance.
    fn new(lattice: &SpringLattice, groups: SpringGroups) -> Self {
        let grid = lattice.grid.unwrap_or((lattice.n_nodes(), 1));
        let bands = |nodes: &[usize]| -> Option<(Band, Band)> {
            if groups == SpringGroups::Classes {
                return None;
            }
            let span = |line: &dyn Fn(usize) -> usize| {
                let lines = nodes.iter().map(|&a| line(a));
                (lines.clone().min().unwrap_or(0), lines.max().unwrap_or(0))
            };
            let (ulo, uhi) = span(&|a| a / grid.1);
            let (vlo, vhi) = span(&|a| a % grid.1);
            Some((Band::of(ulo, uhi, grid.0), Band::of(vlo, vhi, grid.1)))
        };
        let mut out = Self {
            classes: Vec::new(),
            names: Vec::new(),
            springs: Vec::new(),
            hinges: Vec::new(),
        };
        let mut index: BTreeMap<(Class, Option<(Band, Band)>), usize> = BTreeMap::new();
        let mut group_of = |class: Class, nodes: &[usize], out: &mut Self| -> usize {
            let key = (class, bands(nodes));
            *index.entry(key).or_insert_with(|| {
                out.classes.push(class);
                out.names.push(match key.1 {
                    None => class.name().to_string(),
                    Some((u, v)) => format!("{}[{},{}]", class.name(), u.name('u'), v.name('v')),
                });
                out.classes.len() - 1
            })
        };
        for s in &lattice.springs {
            let g = group_of(Class::Spring(s.kind), &[s.a, s.b], &mut out);
            out.springs.push(g);
        }
        for h in &lattice.hinges {
            let g = group_of(Class::Hinge(h.kind), &h.nodes, &mut out);
            out.hinges.push(g);
        }
        out
    }

    fn len(&self) -> usize {
        self.classes.len()
    }

    /// The elements of group `g`.
    fn count(&self, g: usize) -> usize {
        self.springs
            .iter()
            .chain(&self.hinges)
            .filter(|&&h| h == g)
            .count()
    }

    /// Group `g`'s share of the elements of its class.
    fn share(&self, g: usize) -> f64 {
        let class: usize = (0..self.len())
            .filter(|&h| self.classes[h] == self.classes[g])
            .map(|h| self.count(h))
            .sum();
        self.count(g) as f64 / class.max(1) as f64
    }

    /// The unit stiffness of each group at `x` on the free coordinates `rows`.
    fn units(&self, lattice: &SpringLattice, x: &[f64], rows: &[usize]) -> Vec<SparseMatrix> {
        (0..self.len())
            .map(|g| {
                let mut only = lattice.clone();
                only.springs = members(&lattice.springs, &self.springs, g);
                only.hinges = members(&lattice.hinges, &self.hinges, g);
                only.unit_stiffness(self.classes[g], x)
                    .submatrix(rows, rows)
            })
            .collect()
    }

    /// Sets the lattice's constants and weights from the group scales `e^σ_g` and the
    /// frequency factor: a group that is a whole class scales its constant; a group of a
    /// class and bands scales its elements' weights (from `weights`, the rule's), and the
    /// class constants are the rule's times the factor.
    fn apply(
        &self,
        lattice: &mut SpringLattice,
        weights: &(Vec<f64>, Vec<f64>),
        sigma: &[f64],
        k0: &[f64],
        factor: f64,
        groups: SpringGroups,
    ) {
        let by_class = groups == SpringGroups::Classes;
        let scale = |g: usize| if by_class { 1.0 } else { sigma[g].exp() };
        for ((s, &g), &w) in lattice
            .springs
            .iter_mut()
            .zip(&self.springs)
            .zip(&weights.0)
        {
            s.weight = w * scale(g);
        }
        for ((h, &g), &w) in lattice.hinges.iter_mut().zip(&self.hinges).zip(&weights.1) {
            h.weight = w * scale(g);
        }
        let constant = |g: usize| factor * k0[g] * if by_class { sigma[g].exp() } else { 1.0 };
        lattice.set_constants(&Constants::from_pairs(
            (0..self.len()).map(|g| (self.classes[g], constant(g))),
        ));
    }

    /// The scale and element count of each group (none for the calibration by class).
    fn report(&self, sigma: &[f64], groups: SpringGroups) -> Vec<GroupScale> {
        if groups == SpringGroups::Classes {
            return Vec::new();
        }
        (0..self.len())
            .map(|g| GroupScale {
                group: self.names[g].clone(),
                elements: self.count(g),
                scale: sigma[g].exp(),
            })
            .collect()
    }
}

/// The shell's lowest modes about rest ([`DnurbsModel::modes`]): the elastic ones, sampled at
/// the free nodes, and the rigid ones (below [`RIGID_FREQUENCY`] of the highest computed: a
/// mechanism of the constraints).
pub(crate) struct ShellModes {
    /// Every mode computed.
    pub modes: nurbspring_dnurbs::Modes,
    /// The elastic ones (indices into `modes`).
    pub elastic: Vec<usize>,
    /// The rigid ones' shapes (reduced, M-orthonormal).
    pub rigid: Vec<Vec<f64>>,
    /// The elastic ones' angular frequencies.
    pub omega: Vec<f64>,
    /// The elastic ones at the free nodes, `A φ`.
    pub sampled: Vec<Vec<f64>>,
    top: f64,
}

impl ShellModes {
    /// The lowest `count` elastic modes (and up to [`RIGID_MODES`] rigid ones); refused when
    /// none is elastic.
    pub(crate) fn new(
        model: &DnurbsModel,
        map: &springs_check::NodeMap,
        count: usize,
    ) -> Result<Self, DeriveError> {
        let modes = model.modes((count + RIGID_MODES).min(model.n_free()))?;
        let top = modes.omega.last().copied().unwrap_or(0.0);
        let is_elastic = |w: f64| w > RIGID_FREQUENCY * top;
        let elastic: Vec<usize> = (0..modes.omega.len())
            .filter(|&j| is_elastic(modes.omega[j]))
            .collect();
        let rigid: Vec<Vec<f64>> = (0..modes.omega.len())
            .filter(|&j| !is_elastic(modes.omega[j]))
            .map(|j| modes.vectors.column(j))
            .collect();
        if elastic.is_empty() {
            return Err(DeriveError::SingularFit {
                detail: "the shell has no elastic mode among its lowest: its constraints leave \
                         it free to move as a rigid body"
                    .into(),
            });
        }
        let omega = elastic.iter().map(|&j| modes.omega[j]).collect();
        let sampled = elastic
            .iter()
            .map(|&j| map.sample_free(&modes.vectors.column(j)))
            .collect();
        Ok(Self {
            modes,
            elastic,
            rigid,
            omega,
            sampled,
            top,
        })
    }

    /// True for a frequency above the rigid ones.
    pub(crate) fn is_elastic(&self, w: f64) -> bool {
        w > RIGID_FREQUENCY * self.top
    }

    /// The lowest [`TABLE_SPRING_MODES`] elastic modes, each with the node-model mode of
    /// largest MAC among `shapes` (angular frequencies `omega`, on the free node coordinates).
    pub(crate) fn table(&self, omega: &[f64], shapes: &[Vec<f64>]) -> Vec<SpringFrequency> {
        let shown = TABLE_SPRING_MODES.min(self.omega.len());
        let matches = match_modes(&self.sampled[..shown], &self.omega[..shown], shapes);
        (0..shown)
            .map(|j| {
                let m = matches[j];
                let w = self.omega[j];
                SpringFrequency {
                    mode: self.elastic[j] + 1,
                    shell: w,
                    msm_mode: m.map(|(i, _)| i + 1),
                    msm: m.map(|(i, _)| omega[i]),
                    mac: m.map(|(_, mac)| mac),
                    relative_error: m.map(|(i, _)| (omega[i] - w) / w),
                }
            })
            .collect()
    }
}

/// The elements of `all` whose group (in `groups`, one per element) is `g`.
fn members<T: Copy>(all: &[T], groups: &[usize], g: usize) -> Vec<T> {
    all.iter()
        .zip(groups)
        .filter(|&(_, &h)| h == g)
        .map(|(e, _)| *e)
        .collect()
}

/// The calibration's rows at one set of group scales.
struct Residuals {
    /// `(∂ ln ω_i / ∂σ, ln(ω_i / ω_j))` of each matched mode.
    rows: Vec<(Vec<f64>, f64)>,
    /// RMS of the log ratios.
    rms: f64,
    /// The fitted mode count times their mean square, plus the squared pulls.
    objective: f64,
}

/// The calibration's outcome.
pub(super) struct Calibration {
    /// The shell's lowest elastic angular frequency (the model's, after the factor).
    pub omega1: f64,
    /// The lowest elastic shell mode (reduced, M-orthonormal).
    pub first_elastic: Vec<f64>,
    /// The shell's rigid (zero-frequency) modes among its lowest.
    pub rigid: Vec<Vec<f64>>,
    /// The factor on every constant that made the lowest frequency the shell's.
    pub factor: f64,
    /// Shell modes fitted.
    pub fitted: usize,
    /// RMS of the log frequency ratios before the factor.
    pub residual: f64,
    /// The frequency table.
    pub table: Vec<SpringFrequency>,
    /// The group scales (calibration by band).
    pub groups: Vec<GroupScale>,
    /// The fitted modes and their shares (the excitation derivation).
    pub excited: Vec<ExcitedMode>,
}

/// Fits the group scales to the shell's lowest modes, makes the lowest frequency exact, and
/// tabulates the lowest modes matched by MAC (module docs).
pub(super) fn calibrate(
    model: &DnurbsModel,
    lattice: &mut SpringLattice,
    map: &springs_check::NodeMap,
    rule: &Constants,
    groups: SpringGroups,
    excitation: Option<&InitialConditions>,
) -> Result<Calibration, DeriveError> {
    let n_free = map.free_rows().len();
    let (fitted_modes, pull_weight) = match groups {
        SpringGroups::Classes => (SPRING_MODES, SPRING_PULL),
        SpringGroups::Bands => (BAND_SPRING_MODES, BAND_PULL),
    };
    let wanted = fitted_modes.min(model.n_free()).min(n_free);
    if wanted == 0 {
        return Err(DeriveError::InvalidInput {
            input: crate::Input::Constraints,
            value: "every node fixed".into(),
            reason: "the spring lattice has no free node".into(),
        });
    }
    let computed = if excitation.is_some() {
        EXCITATION_CANDIDATES.max(wanted)
    } else {
        wanted
    };
    let shell = ShellModes::new(model, map, computed)?;
    let ShellModes {
        modes,
        elastic,
        rigid,
        omega,
        sampled,
        ..
    } = &shell;
    let is_elastic = |w: f64| shell.is_elastic(w);
    let x0 = lattice.flat_positions();
    let grouping = Grouping::new(lattice, groups);
    let units = grouping.units(lattice, &x0, map.free_rows());
    let weights: (Vec<f64>, Vec<f64>) = (
        lattice.springs.iter().map(|s| s.weight).collect(),
        lattice.hinges.iter().map(|h| h.weight).collect(),
    );
    let masses = map.free_masses(lattice);
    // The fitted modes (indices into the elastic ones) and the weight of each one's row.
    let targets: Vec<(usize, f64)> = match excitation {
        None => (0..wanted.min(omega.len())).map(|j| (j, 1.0)).collect(),
        Some(initial) => excited_targets(model, initial, modes, elastic)?,
    };
    let excited: Vec<ExcitedMode> = match excitation {
        None => Vec::new(),
        Some(_) => targets
            .iter()
            .map(|&(j, w)| ExcitedMode {
                mode: elastic[j] + 1,
                omega: omega[j],
                share: w * w / targets.len() as f64,
            })
            .collect(),
    };
    let fitted = targets.len();
    let target_shapes: Vec<Vec<f64>> = targets.iter().map(|&(j, _)| sampled[j].clone()).collect();
    let target_omega: Vec<f64> = targets.iter().map(|&(j, _)| omega[j]).collect();
    let reach = targets.iter().map(|&(j, _)| j + 1).max().unwrap_or(0);
    let n_c = grouping.len();
    let k0: Vec<f64> = grouping
        .classes
        .iter()
        .map(|&c| rule.get(c).unwrap_or(0.0))
        .collect();
    let stiffness = |sigma: &[f64]| -> Result<SparseMatrix, DeriveError> {
        let mut k = SparseMatrix::zeros(masses.len(), masses.len());
        for c in 0..n_c {
            k = SparseMatrix::linear_combination(1.0, &k, k0[c] * sigma[c].exp(), &units[c])?;
        }
        Ok(k)
    };
    let n_modes = rigid.len() + 2 * reach + RIGID_MODES;
    // Each group's pull weighs its share of its class's elements, so that one scale on a
    // whole class costs the same under either grouping.
    let pull: Vec<f64> = (0..n_c)
        .map(|g| (pull_weight * grouping.share(g)).sqrt())
        .collect();
    // Gauss–Newton on the log frequency ratios of the matched modes in the log group scales
    // σ (k_c = k⁰_c e^σ_c), with ∂ ln ω_i / ∂σ_c = k_c ψ_iᵀ G_c ψ_i / (2 ω_i² ψ_iᵀ M ψ_i);
    // a step that does not lower the objective (the mean square of the rows over the fitted
    // modes plus the pulls) is halved, and the calibration ends where halving does not help.
    let residuals = |sigma: &[f64]| -> Result<Residuals, DeriveError> {
        let k = stiffness(sigma)?;
        let (w, shapes) = springs_check::lowest_modes(&k, &masses, n_modes)?;
        let matches = match_modes(&target_shapes, &target_omega, &shapes);
        let mut rows: Vec<(Vec<f64>, f64)> = Vec::new();
        for ((m, &(_, weight)), &target) in matches.iter().zip(&targets).zip(&target_omega) {
            let Some((i, _)) = *m else { continue };
            if !is_elastic(w[i]) {
                continue;
            }
            let psi = &shapes[i];
            let inertia: f64 = psi.iter().zip(&masses).map(|(y, m)| m * y * y).sum();
            let grad = (0..n_c)
                .map(|c| {
                    weight * k0[c] * sigma[c].exp() * units[c].quadratic_form(psi)
                        / (2.0 * w[i] * w[i] * inertia)
                })
                .collect();
            rows.push((grad, weight * (w[i] / target).ln()));
        }
        let mean_square = rows.iter().map(|(_, r)| r * r).sum::<f64>() / rows.len().max(1) as f64;
        let pulled: f64 = sigma.iter().zip(&pull).map(|(s, p)| (p * s).powi(2)).sum();
        Ok(Residuals {
            rms: mean_square.sqrt(),
            objective: fitted as f64 * mean_square + pulled,
            rows,
        })
    };
    let mut sigma = vec![0.0; n_c];
    let mut current = residuals(&sigma)?;
    let mut best = (f64::INFINITY, sigma.clone());
    for _ in 0..CALIBRATION_ITERATIONS {
        let rows = &current.rows;
        if rows.is_empty() {
            break;
        }
        if current.rms < best.0 {
            best = (current.rms, sigma.clone());
        }
        let mut a = DenseMatrix::zeros(rows.len() + n_c, n_c);
        let mut b = vec![0.0; rows.len() + n_c];
        for (r, (grad, res)) in rows.iter().enumerate() {
            for c in 0..n_c {
                a[(r, c)] = grad[c];
            }
            b[r] = -res;
        }
        for c in 0..n_c {
            a[(rows.len() + c, c)] = pull[c];
            b[rows.len() + c] = -pull[c] * sigma[c];
        }
        let step = least_squares(&a, &b)?;
        let largest = step.iter().fold(0.0_f64, |m, d| m.max(d.abs()));
        let mut cut = if largest > 1.0 { 1.0 / largest } else { 1.0 };
        let mut accepted = None;
        for _ in 0..=STEP_HALVINGS {
            let trial: Vec<f64> = sigma.iter().zip(&step).map(|(s, d)| s + cut * d).collect();
            let r = residuals(&trial)?;
            if r.objective < current.objective {
                accepted = Some((trial, r));
                break;
            }
            cut *= 0.5;
        }
        let Some((trial, r)) = accepted else { break };
        sigma = trial;
        current = r;
        if largest < 1e-4 {
            break;
        }
    }
    if !current.rows.is_empty() && current.rms < best.0 {
        best = (current.rms, sigma.clone());
    }
    let (residual, sigma) = best;
    grouping.apply(lattice, &weights, &sigma, &k0, 1.0, groups);
    let k = map.free_stiffness(lattice);
    let (msm_low, _) = springs_check::lowest_modes(&k, &masses, rigid.len() + RIGID_MODES)?;
    let omega1_msm = msm_low.into_iter().find(|&w| is_elastic(w)).unwrap_or(0.0);
    let omega1 = omega[0];
    if omega1_msm.is_nan() || omega1_msm <= 0.0 {
        return Err(DeriveError::SingularFit {
            detail: "the calibrated spring model has no positive lowest frequency (a free \
                     lattice or every class constant zero)"
                .into(),
        });
    }
    let factor = (omega1 / omega1_msm).powi(2);
    grouping.apply(lattice, &weights, &sigma, &k0, factor, groups);
    let k = map.free_stiffness(lattice);
    let (omega_msm, shapes) =
        springs_check::lowest_modes(&k, &masses, rigid.len() + 3 * TABLE_SPRING_MODES)?;
    let table = shell.table(&omega_msm, &shapes);
    Ok(Calibration {
        omega1,
        first_elastic: modes.vectors.column(elastic[0]),
        rigid: rigid.clone(),
        factor,
        fitted,
        residual,
        table,
        groups: grouping.report(&sigma, groups),
        excited,
    })
}

/// The [`EXCITED_MODES`] elastic shell modes of largest share of the motion the scene's initial
/// state and loads excite (docs/math.md §8.4, `a_j² = (φ_jᵀ M u₀ − φ_jᵀ F/ω_j²)² + (φ_jᵀ M v₀/ω_j)²`
/// with the M-orthonormal modes `φ_j` of the shell linearized at rest), as indices into
/// `elastic` with row weights `√(n s_j)`, `s_j` the share among the `n` kept: the rows weigh
/// `n` in all, as `n` unweighted ones do. Refused when nothing is excited.
fn excited_targets(
    model: &DnurbsModel,
    initial: &InitialConditions,
    modes: &nurbspring_dnurbs::Modes,
    elastic: &[usize],
) -> Result<Vec<(usize, f64)>, DeriveError> {
    let rest = model.reduced_coordinates(model.p0());
    let state = initial.state(model);
    let u0: Vec<f64> = state.q.iter().zip(&rest).map(|(a, b)| a - b).collect();
    let m = nurbspring_sim::DynamicModel::mass(model);
    let mut mu = vec![0.0; u0.len()];
    m.mul_vec(&u0, &mut mu);
    let mut mv = vec![0.0; u0.len()];
    m.mul_vec(&state.v, &mut mv);
    let force = model.reduced_force();
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
    let mut shares: Vec<(usize, f64)> = elastic
        .iter()
        .enumerate()
        .map(|(j, &k)| {
            let phi = modes.vectors.column(k);
            let w = modes.omega[k];
            let a2 = amplitude2(dot(&phi, &mu), dot(&phi, &mv), dot(&phi, force), w * w, w);
            (j, a2)
        })
        .collect();
    shares.sort_by(|a, b| b.1.total_cmp(&a.1));
    shares.truncate(EXCITED_MODES);
    let total: f64 = shares.iter().map(|s| s.1).sum();
    if total.is_nan() || total <= 0.0 {
        return Err(DeriveError::NoExcitation);
    }
    let n = shares.len() as f64;
    shares.sort_by_key(|s| s.0);
    Ok(shares
        .into_iter()
        .filter(|s| s.1 > 0.0)
        .map(|(j, a2)| (j, (n * a2 / total).sqrt()))
        .collect())
}
