//! The run time of `derive`, estimated from the scene's sizes before anything is built (what
//! `check` prints for the scene's derivation and the paper's).
//!
//! Each derivation's dominant terms are counts of work (dense eigenproblems by `n³`, runs by
//! their node-steps, the shell's Newton iterations by control points and element size) times a
//! cost measured on the development machine (2 cores, AMD EPYC, release build; docs/reliability.md
//! lists the measurements and how far the estimates were from them). It is an order of
//! magnitude: another machine, its load and a run's Newton iterations move it by a factor of a
//! few. An explicit MSM's substeps in the paper's scan depend on the constants the derivation
//! fits, so there the estimate counts one step per Δt and says it is a lower bound.

use nurbspring_derive::{
    DENSE_MODES, LARGE_MOTION_PERIODS, LOAD_LEVELS, MassScan, Method, SCAN_BATCH, STEPS_PER_PERIOD,
    TRUNCATED_MODES,
};

use crate::Scene;
use crate::spec::{GeometrySpec, MassMethod};

/// Seconds of a dense symmetric eigenproblem per `n³` (1089 unknowns: 0.4 s).
const DENSE_EIGEN: f64 = 3.1e-10;
/// Seconds of an implicit MSM step (backward Euler, Newmark) per node, one thread (1089 nodes
/// on a nonlinear flat lattice: 3.5 ms a step).
const IMPLICIT_NODE_STEP: f64 = 3.2e-6;
/// Seconds of an explicit MSM step per node, one thread (1089 nodes: 0.11 ms a step).
const EXPLICIT_NODE_STEP: f64 = 1.0e-7;
/// Seconds of a D-NURBS step per unknown and factor band entry (a solve with a kept factor).
const DNURBS_SOLVE: f64 = 4.0e-9;
/// Seconds of one Newton iteration of the shell per control point and `((p+1)(q+1))³` (the
/// element block times its Gauss points): geometric mean of the Sze cantilever (degree 3,
/// 76 control points, 35.6 s) and the cloth (degree 2, 196 points, 5.1 s).
const SHELL_ITERATION: f64 = 6.4e-8;
/// Newton iterations a step of the springs' large-motion dynamic run takes, about.
const SHELL_ITERATIONS_PER_STEP: f64 = 3.0;
/// Newton iterations of a load level of the static path, about.
const SHELL_ITERATIONS_PER_LEVEL: f64 = 25.0;
/// Share of a whole run a pruned candidate of the paper's scan takes, about (0.06 and 0.15
/// measured on a 33 × 33 lattice with backward and symplectic Euler).
const PRUNED_SHARE: f64 = 0.1;

/// The estimated run time of `derive` with one derivation.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct RuntimeEstimate {
    /// Seconds.
    pub seconds: f64,
    /// The same, rounded for people ("about 3 min").
    pub about: String,
    /// The estimate leaves out a factor the derivation learns only as it runs (the substeps of
    /// an explicit MSM in the paper's scan): the run takes at least this long.
    pub at_least: bool,
    /// The largest term, in words.
    pub dominant: String,
    /// Every term, largest first.
    pub terms: Vec<RuntimeTerm>,
}

/// One term of a [`RuntimeEstimate`].
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct RuntimeTerm {
    /// What it is.
    pub what: String,
    /// Seconds.
    pub seconds: f64,
}

impl Scene {
    /// The estimated run time of `derive` with `method` on this scene.
    pub fn derive_runtime(&self, method: Method) -> RuntimeEstimate {
        let s = self.sizes();
        let (a, b) = self.lattice_nodes(method);
        let nodes = a * b;
        let points = s.n_u * s.n_v;
        let steps = (self.simulation.t_end / self.simulation.dt).ceil().max(1.0);
        let band = (s.n_u.min(s.n_v) * (s.p.max(s.q) + 1.0)).max(1.0);
        let dense = |n: f64| DENSE_EIGEN * n.powi(3);
        // Above DENSE_MODES unknowns the lowest TRUNCATED_MODES come from Lanczos: a factor and
        // a basis of 4r + 60 solves.
        let modes = |n: f64| {
            if n <= DENSE_MODES as f64 {
                dense(n)
            } else {
                DNURBS_SOLVE * n * band * band
                    + DNURBS_SOLVE * n * band * (4.0 * TRUNCATED_MODES as f64 + 60.0)
            }
        };
        let dnurbs_run = DNURBS_SOLVE * steps * points * band;
        let mut at_least = false;
        let shell = self.material.shell().is_some();
        let mut terms: Vec<(f64, String)> = match method {
            // A shell's reduction: dense eigenproblems on the nodes' coordinates (§11.4).
            Method::Reduction if shell => vec![(
                2.0 * dense(3.0 * nodes),
                format!("the reduction's eigenproblems ({} unknowns)", 3.0 * nodes),
            )],
            // A shell's other derivations make a spring model (docs/math.md §11).
            _ if shell && method.takes(true) => {
                let element = ((s.p + 1.0) * (s.q + 1.0)).powi(3);
                let iterations = LOAD_LEVELS as f64 * SHELL_ITERATIONS_PER_LEVEL
                    + LARGE_MOTION_PERIODS * STEPS_PER_PERIOD as f64 * SHELL_ITERATIONS_PER_STEP;
                vec![
                    (
                        iterations * SHELL_ITERATION * points * element,
                        format!(
                            "the shell's large-motion runs (about {iterations:.0} Newton iterations on {points} control points)"
                        ),
                    ),
                    (
                        modes(3.0 * nodes),
                        format!("the spring model's modes ({nodes} nodes)"),
                    ),
                ]
            }
            Method::Modal | Method::Excitation => {
                let n = points.max(nodes);
                let fits = if method == Method::Excitation {
                    2.0
                } else {
                    1.0
                };
                vec![
                    (
                        2.0 * fits * modes(n),
                        format!("the modes of both models ({n} unknowns)"),
                    ),
                    (dnurbs_run, "the D-NURBS run".to_string()),
                ]
            }
            Method::Reduction => vec![
                (
                    2.0 * dense(points),
                    format!("the reduction's eigenproblems ({points} unknowns)"),
                ),
                (dnurbs_run, "the D-NURBS run".to_string()),
            ],
            Method::Paper => {
                let candidates = self.paper_candidates();
                let runs = match self.fit.mass_scan {
                    MassScan::Complete => candidates,
                    MassScan::Pruned => candidates
                        .min(SCAN_BATCH as f64 + PRUNED_SHARE * (candidates - SCAN_BATCH as f64)),
                };
                let integrator = self.simulation.msm_integrator;
                let per_node_step = if integrator.is_explicit() {
                    at_least = true;
                    EXPLICIT_NODE_STEP
                } else {
                    IMPLICIT_NODE_STEP
                };
                let threads = std::thread::available_parallelism()
                    .map_or(1, |n| n.get())
                    .min(SCAN_BATCH) as f64;
                let run = steps * nodes * per_node_step;
                let mut terms = vec![
                    (3.0 * run, "the validation runs of the MSM".to_string()),
                    (dense(points), "the eigenvalues of M".to_string()),
                    (dnurbs_run, "the D-NURBS run".to_string()),
                ];
                if candidates > 0.0 {
                    terms.push((
                        runs * run / threads,
                        format!(
                            "the mass scan: {candidates} candidates ({}), {steps} steps of {nodes} nodes each, {integrator}",
                            match self.fit.mass_scan {
                                MassScan::Pruned =>
                                    format!("about {runs:.0} whole runs when pruned"),
                                MassScan::Complete => "every run whole".to_string(),
                            }
                        ),
                    ));
                }
                terms
            }
            // Refused on a tension plate (no spring model without a shell).
            Method::Springs => Vec::new(),
        };
        terms.sort_by(|x, y| y.0.total_cmp(&x.0));
        let seconds: f64 = terms.iter().map(|t| t.0).sum();
        RuntimeEstimate {
            seconds,
            about: about(seconds, at_least),
            at_least,
            dominant: terms.first().map(|t| t.1.clone()).unwrap_or_default(),
            terms: terms
                .into_iter()
                .map(|(seconds, what)| RuntimeTerm { what, seconds })
                .collect(),
        }
    }

    /// Candidates of the paper's eigenvalue scan: the distinct eigenvalues of M, at most
    /// `fit.max_candidates`; none when the scene fixes the mass. A non-rational net with the same
    /// knots along u and v has `M = S ⊗ S` (times I₃), whose `n(n + 1)/2` products are distinct.
    fn paper_candidates(&self) -> f64 {
        if self.fit.mass == MassMethod::Fixed {
            return 0.0;
        }
        let distinct = match &self.geometry {
            GeometrySpec::Surface(s)
                if s.knots_u == s.knots_v
                    && s.degree_u == s.degree_v
                    && s.weights
                        .as_ref()
                        .is_none_or(|w| w.iter().flatten().all(|&x| x == 1.0)) =>
            {
                let n = s.n_u() as f64;
                n * (n + 1.0) / 2.0
            }
            GeometrySpec::Surface(s) => (s.n_u() * s.n_v()) as f64,
            GeometrySpec::Curve(c) => c.control_points.len() as f64,
        };
        match self.fit.max_candidates {
            0 => distinct,
            n => distinct.min(n as f64),
        }
    }

    /// What `check` reports of the run time of `derive`: the scene's derivation, and the
    /// paper's beside it on a tension-plate scene.
    pub fn runtime_json(&self) -> serde_json::Value {
        let (method, _) = self.derivation();
        let mut map = serde_json::Map::new();
        let mut methods = vec![method];
        if method != Method::Paper && method.takes(false) && self.material.shell().is_none() {
            methods.push(Method::Paper);
        }
        for m in methods {
            map.insert(
                m.name().to_string(),
                serde_json::to_value(self.derive_runtime(m)).unwrap_or_default(),
            );
        }
        serde_json::Value::Object(map)
    }
}

/// "about 40 s", "at least 3 min", "about 2 h".
fn about(seconds: f64, at_least: bool) -> String {
    let words = if at_least { "at least" } else { "about" };
    let (value, unit) = if seconds < 1.0 {
        return if at_least {
            format!("at least {seconds:.2} s")
        } else {
            "under 1 s".to_string()
        };
    } else if seconds < 90.0 {
        (seconds, "s")
    } else if seconds < 5400.0 {
        (seconds / 60.0, "min")
    } else {
        (seconds / 3600.0, "h")
    };
    let rounded = if value < 10.0 {
        format!("{value:.1}")
    } else {
        format!("{value:.0}")
    };
    format!("{words} {rounded} {unit}")
}

#[cfg(test)]
mod tests {
    use super::about;

    #[test]
    fn times_are_rounded_for_people() {
        assert_eq!(about(0.2, false), "under 1 s");
        assert_eq!(about(0.2, true), "at least 0.20 s");
        assert_eq!(about(4.27, false), "about 4.3 s");
        assert_eq!(about(47.4, true), "at least 47 s");
        assert_eq!(about(600.0, false), "about 10 min");
        assert_eq!(about(7200.0, false), "about 2.0 h");
    }
}
