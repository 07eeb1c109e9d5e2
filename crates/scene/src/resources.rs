//! Resource limits decided before allocation (docs/reliability.md): the memory a command will
//! need and the bytes it will write, estimated from the scene's sizes alone, and refused up
//! front (bad input, naming the key and the estimate) when above the limits.
//!
//! The estimates are upper bounds of the peak, not predictions: each term is the largest
//! structure the command builds (sparse matrices by their stencil, sparse Cholesky factors by
//! a band bound of the fill, dense eigenproblems by their `n²`), times a safety factor
//! calibrated against measured peak resident sizes (docs/reliability.md lists them).

use std::path::Path;

use nurbspring_derive::Method;

use crate::spec::{GeometrySpec, LatticeGrid};
use crate::{Error, Scene};

/// What a command will do with the scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Job {
    /// `check`: validates, builds the models, computes stability limits.
    Check,
    /// `matrices`, `eval`: assembles the D-NURBS (and writes it).
    Assemble,
    /// `modes`, `steady`: factorizes the D-NURBS stiffness.
    Factorize,
    /// `simulate --model dnurbs`, with the run's step and end time when they override the
    /// scene's.
    SimulateDnurbs(Timing),
    /// `simulate --model msm` and `stability`: the scene's lattice.
    SimulateMsm(Timing),
    /// `derive` (and `paper`) with a derivation.
    Derive(Method),
}

/// Step and end time of a run, when flags override the scene's.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Timing {
    /// `--dt`.
    pub dt: Option<f64>,
    /// `--t-end`.
    pub t_end: Option<f64>,
}

/// One term of an estimate.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Part {
    /// What it is ("sparse factor of K").
    pub what: &'static str,
    /// Bytes.
    pub bytes: u64,
}

/// Memory and output of one command on one scene.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Estimate {
    /// Peak memory, bytes (an upper bound).
    pub memory: u64,
    /// Terms of `memory`, largest first.
    pub memory_parts: Vec<Part>,
    /// Bytes written to the output folder.
    pub output: u64,
    /// VTK frames written.
    pub frames: u64,
    /// The scene key that sets the size of the largest term.
    pub size_key: &'static str,
    /// The run asks for more than `MAX_STEPS` steps (refused by the time rule, not here).
    pub too_many_steps: bool,
}

/// The limits a command runs under.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Limits {
    /// Peak memory, bytes.
    pub memory: u64,
    /// Bytes written, in all.
    pub output: u64,
    /// The address space this process may still map under its `RLIMIT_AS` (`ulimit -v`),
    /// when it has one ([`address_space_left`]): no `--max-memory` raises the memory limit
    /// above it, since an allocation beyond it fails (and Rust ends the process on a failed
    /// allocation).
    pub address_space: Option<u64>,
}

/// Default output limit: 16 GiB (and never more than the free space of the output's file
/// system).
pub const DEFAULT_MAX_OUTPUT: u64 = 16 << 30;

/// Safety factor on every memory term: allocator slack, temporaries and copies the terms do
/// not list (docs/reliability.md compares the estimates with measured peaks).
const SAFETY: f64 = 1.5;

/// What every process needs before any model: the binary, the allocator, thread stacks.
const BASE: u64 = 64 << 20;

impl Limits {
    /// The defaults on this machine: 80 % of the memory available to the process (the smaller
    /// of `MemAvailable` and the cgroup's limit), [`DEFAULT_MAX_OUTPUT`].
    pub fn from_system() -> Limits {
        let address_space = address_space_left();
        let memory = (available_memory() as f64 * 0.8) as u64;
        Limits {
            memory: address_space.map_or(memory, |left| memory.min(left)),
            output: DEFAULT_MAX_OUTPUT,
            address_space,
        }
    }

    /// The memory limit after `--max-memory` (never above the address space left).
    pub fn with_memory(self, bytes: u64) -> Limits {
        Limits {
            memory: self.address_space.map_or(bytes, |left| bytes.min(left)),
            ..self
        }
    }
}

/// Address space a worker thread reserves besides what it allocates: its malloc arena (glibc
/// reserves 64 MiB of address space per arena on 64-bit systems) and its stack (2 MiB for
/// Rust's threads), rounded up.
const THREAD_RESERVE: u64 = 72 << 20;

/// The address space this process may still map under its soft `RLIMIT_AS` (`ulimit -v`;
/// read with `getrlimit`), less what it maps now (`VmSize` of /proc/self/status) and the
/// reservations of its worker threads ([`THREAD_RESERVE`] each, for the pool's threads and
/// one more); `None` without a limit.
pub fn address_space_left() -> Option<u64> {
    #[cfg(unix)]
    {
        let limit = rustix::process::getrlimit(rustix::process::Resource::As).current?;
        let mapped = std::fs::read_to_string("/proc/self/status")
            .ok()
            .and_then(|t| {
                t.lines()
                    .find(|l| l.starts_with("VmSize:"))
                    .and_then(|l| l.split_whitespace().nth(1)?.parse::<u64>().ok())
            })
            .map_or(0, |kib| kib * 1024);
        let threads = rayon::current_num_threads() as u64 + 1;
        Some(
            limit
                .saturating_sub(mapped)
                .saturating_sub(threads.saturating_mul(THREAD_RESERVE)),
        )
    }
    #[cfg(not(unix))]
    {
        None
    }
}

/// Memory available to this process: `MemAvailable` from /proc/meminfo, capped by the cgroup
/// (v2 `memory.max` minus `memory.current`) when there is one; 8 GiB where neither can be read.
pub fn available_memory() -> u64 {
    let meminfo = std::fs::read_to_string("/proc/meminfo").ok().and_then(|t| {
        t.lines()
            .find(|l| l.starts_with("MemAvailable:"))
            .and_then(|l| l.split_whitespace().nth(1)?.parse::<u64>().ok())
            .map(|kib| kib * 1024)
    });
    let read = |p: &str| -> Option<u64> { std::fs::read_to_string(p).ok()?.trim().parse().ok() };
    let cgroup = match (
        read("/sys/fs/cgroup/memory.max"),
        read("/sys/fs/cgroup/memory.current"),
    ) {
        (Some(max), Some(cur)) => Some(max.saturating_sub(cur)),
        _ => None,
    };
    match (meminfo, cgroup) {
        (Some(a), Some(b)) => a.min(b),
        (Some(a), None) | (None, Some(a)) => a,
        (None, None) => 8 << 30,
    }
}

/// Free bytes on the file system holding `path` (or its nearest existing ancestor); `None`
/// where it cannot be asked.
pub fn free_space(path: &Path) -> Option<u64> {
    #[cfg(unix)]
    {
        let mut p = path.to_path_buf();
        while !p.exists() {
            if !p.pop() {
                p = std::path::PathBuf::from(".");
                break;
            }
            if p.as_os_str().is_empty() {
                p = std::path::PathBuf::from(".");
            }
        }
        let stat = rustix::fs::statvfs(&p).ok()?;
        Some(stat.f_bavail.saturating_mul(stat.f_frsize))
    }
    #[cfg(not(unix))]
    {
        let _ = path;
        None
    }
}

impl Scene {
    /// What `check` reports of the resources: each job's estimate (memory, output, frames)
    /// and whether it is within `limits`, and the limits.
    pub fn resources_json(&self, limits: &Limits) -> serde_json::Value {
        let (method, _) = self.derivation();
        let mut resources = serde_json::Map::new();
        for (name, job) in [
            ("derive", Job::Derive(method)),
            ("simulate_dnurbs", Job::SimulateDnurbs(Timing::default())),
            ("simulate_msm", Job::SimulateMsm(Timing::default())),
            ("modes_steady", Job::Factorize),
        ] {
            let e = self.estimate(job);
            resources.insert(
                name.to_string(),
                serde_json::json!({
                    "memory_bytes": e.memory,
                    "memory": format_bytes(e.memory),
                    "output_bytes": e.output,
                    "frames": e.frames,
                    "within_limits": e.memory <= limits.memory && e.output <= limits.output,
                }),
            );
        }
        resources.insert(
            "limits".to_string(),
            serde_json::json!({"memory_bytes": limits.memory, "output_bytes": limits.output}),
        );
        serde_json::Value::Object(resources)
    }
}

/// A byte count: digits with an optional unit K, M, G or T (powers of 1024; `B`, `iB` allowed).
pub fn parse_size(s: &str) -> Result<u64, String> {
    let t = s.trim();
    let upper = t.to_ascii_uppercase();
    let body = upper
        .strip_suffix("IB")
        .or_else(|| upper.strip_suffix('B'))
        .unwrap_or(&upper);
    let (digits, shift) = match body.chars().last() {
        Some('K') => (&body[..body.len() - 1], 10),
        Some('M') => (&body[..body.len() - 1], 20),
        Some('G') => (&body[..body.len() - 1], 30),
        Some('T') => (&body[..body.len() - 1], 40),
        _ => (body, 0),
    };
    let x: f64 = digits
        .trim()
        .parse()
        .map_err(|_| format!("{t:?} is not a size (bytes, or a number with K, M, G or T)"))?;
    let bytes = x * (1u64 << shift) as f64;
    if !(bytes.is_finite() && bytes >= 1.0 && bytes < u64::MAX as f64) {
        return Err(format!("{t:?} is not a size between 1 byte and 16 EiB"));
    }
    Ok(bytes as u64)
}

/// Bytes as text: "3.2 GiB", "640 MiB", "12 KiB".
pub fn format_bytes(b: u64) -> String {
    let b = b as f64;
    let units = [("GiB", 30), ("MiB", 20), ("KiB", 10)];
    for (name, shift) in units {
        let unit = (1u64 << shift) as f64;
        if b >= unit {
            return format!("{:.1} {name}", b / unit);
        }
    }
    format!("{b} B")
}

/// Sizes of the scene that set the estimates.
pub(crate) struct Sizes {
    /// Control points along u and v (v = 1 on a curve).
    pub(crate) n_u: f64,
    pub(crate) n_v: f64,
    /// Degrees (q = 0 on a curve).
    pub(crate) p: f64,
    pub(crate) q: f64,
    /// Dofs per control point.
    pub(crate) d: f64,
    /// Non-empty knot spans along u and v (v = 1 on a curve).
    pub(crate) spans_u: f64,
    pub(crate) spans_v: f64,
}

/// Distinct values in a knot vector.
fn distinct(k: &[f64]) -> f64 {
    let mut n = 0.0;
    for (i, x) in k.iter().enumerate() {
        if i == 0 || *x != k[i - 1] {
            n += 1.0;
        }
    }
    n
}

impl Scene {
    pub(crate) fn sizes(&self) -> Sizes {
        let d = if self.dnurbs.weights_as_dofs {
            4.0
        } else {
            3.0
        };
        match &self.geometry {
            GeometrySpec::Surface(s) => Sizes {
                n_u: s.n_u() as f64,
                n_v: s.n_v() as f64,
                p: s.degree_u as f64,
                q: s.degree_v as f64,
                d,
                spans_u: (distinct(&s.knots_u) - 1.0).max(1.0),
                spans_v: (distinct(&s.knots_v) - 1.0).max(1.0),
            },
            GeometrySpec::Curve(c) => Sizes {
                n_u: c.control_points.len() as f64,
                n_v: 1.0,
                p: c.degree as f64,
                q: 0.0,
                d,
                spans_u: (distinct(&c.knots) - 1.0).max(1.0),
                spans_v: 1.0,
            },
        }
    }

    /// Lattice nodes along u and v for `method`'s default grid (or the scene's), from the
    /// scene's numbers alone.
    pub(crate) fn lattice_nodes(&self, method: Method) -> (f64, f64) {
        let grid = self.msm.grid_for(method);
        match (&self.geometry, grid) {
            (GeometrySpec::Surface(s), LatticeGrid::Knots) => {
                (distinct(&s.knots_u), distinct(&s.knots_v))
            }
            (GeometrySpec::Curve(c), LatticeGrid::Knots) => (distinct(&c.knots), 1.0),
            (GeometrySpec::Surface(s), LatticeGrid::Greville) => (s.n_u() as f64, s.n_v() as f64),
            (GeometrySpec::Curve(c), LatticeGrid::Greville) => (c.control_points.len() as f64, 1.0),
            (GeometrySpec::Surface(_), LatticeGrid::Uniform) => {
                (self.msm.nodes_u as f64, self.msm.nodes_v as f64)
            }
            (GeometrySpec::Curve(_), LatticeGrid::Uniform) => (self.msm.nodes_u as f64, 1.0),
        }
    }

    /// The memory and output `job` needs on this scene (see the [module](self) docs).
    pub fn estimate(&self, job: Job) -> Estimate {
        let s = self.sizes();
        let n = s.n_u * s.n_v;
        let dofs = s.d * n;
        // Stencil of one row of the scalar matrices, and the band of a factor (nested
        // dissection keeps the fill below n · band with band ≈ the shorter side times the
        // stencil width).
        let stencil = (2.0 * s.p + 1.0).min(s.n_u) * (2.0 * s.q + 1.0).min(s.n_v);
        // Dofs of a control point coupled in the matrices: all of them with weights as
        // unknowns and in the shell (whose tangent couples x, y and z), one for the tension
        // plate's `S ⊗ I₃` pattern.
        let coupled = if self.dnurbs.weights_as_dofs || self.material.shell().is_some() {
            s.d
        } else {
            1.0
        };
        let nnz = dofs * stencil * coupled;
        // Fill of a sparse Cholesky factor under a fill-reducing ordering: at most a band of the
        // shorter side times the stencil width, and (nested dissection on a 2-D grid) about
        // stencil · log₂ n entries per row; the smaller of the two.
        let band = (s.n_u.min(s.n_v) * (s.p.max(s.q) + 1.0))
            .min(stencil * n.max(2.0).log2())
            .max(stencil);
        let mut parts: Vec<(&'static str, f64, &'static str)> = Vec::new();
        let geometry_key = match self.geometry {
            GeometrySpec::Surface(_) => "surface.control_points",
            GeometrySpec::Curve(_) => "curve.control_points",
        };
        // M, D, K with their assembly triplets, and the element Jacobians.
        parts.push((
            "D-NURBS matrices M, D, K",
            3.0 * 2.0 * 16.0 * nnz,
            geometry_key,
        ));
        let factor = 16.0 * dofs * band * coupled;
        let timing = match job {
            Job::SimulateDnurbs(t) | Job::SimulateMsm(t) => t,
            _ => Timing::default(),
        };
        let dt = timing.dt.unwrap_or(self.simulation.dt);
        let t_end = timing.t_end.unwrap_or(self.simulation.t_end);
        // More than MAX_STEPS is refused by the time rule itself, naming the key or flag.
        let steps = (t_end / dt).ceil().clamp(1.0, nurbspring_sim::MAX_STEPS);
        let too_many_steps = t_end / dt > nurbspring_sim::MAX_STEPS;
        let saves = (steps / self.simulation.save_every.max(1) as f64).ceil() + 1.0;
        let frames = (saves / self.output.frame_every(saves as usize) as f64).ceil();
        let probes = self.simulation.probes.len().max(1) as f64;
        let mut output = 0.0;
        let mut frame_count = 0.0;
        let lattice = |method: Method, parts: &mut Vec<(&'static str, f64, &'static str)>| {
            let (a, b) = self.lattice_nodes(method);
            let nodes = a * b;
            // The lattice with its springs and linear elements, its model and the node map of
            // the D-NURBS state: 3.7 kB a node measured on a 300 × 300 lattice, rounded up.
            parts.push(("mass-spring lattice", 4096.0 * nodes, "msm.grid"));
            // The stability limit's Lanczos basis (at most 64 MiB; linalg).
            parts.push((
                "Lanczos basis of the stability limit",
                (8.0 * 3.0 * nodes * 400.0).min(64.0 * 1024.0 * 1024.0),
                "msm.grid",
            ));
            nodes
        };
        match job {
            Job::Check => {
                lattice(Method::Paper, &mut parts);
            }
            Job::Assemble => {
                output = 3.0 * 40.0 * nnz;
            }
            Job::Factorize => {
                parts.push(("sparse factor of K", factor, geometry_key));
                // Lanczos vectors of the lowest modes.
                parts.push(("eigenvectors", 8.0 * dofs * 200.0, geometry_key));
            }
            Job::SimulateDnurbs(_) => {
                parts.push(("sparse factor of the step matrix", factor, geometry_key));
                // A tessellation frame: the surface at SAMPLES_PER_SPAN points a knot span,
                // points and displacements, 64 bytes a point measured.
                let per_span = crate::export::SAMPLES_PER_SPAN as f64;
                let points = (s.spans_u * per_span + 1.0) * (s.spans_v * per_span + 1.0);
                let frame = 80.0 * points + 4096.0;
                frame_count = frames;
                output = frames * frame + saves * probes * 200.0;
            }
            Job::SimulateMsm(_) => {
                let nodes = lattice(Method::Paper, &mut parts);
                // The implicit integrators' factor of the lattice stiffness (27-node stencil,
                // 3 × 3 blocks), under the same fill bound as above.
                let lattice_dofs = 3.0 * nodes;
                parts.push((
                    "sparse factor of the lattice stiffness",
                    16.0 * lattice_dofs * 27.0 * lattice_dofs.max(2.0).log2(),
                    "msm.grid",
                ));
                // A lattice frame: points, velocities and the springs (375 bytes a node
                // measured with two spring kinds), rounded up.
                let frame = 500.0 * nodes + 4096.0;
                frame_count = frames;
                output = frames * frame + saves * probes * 200.0;
            }
            Job::Derive(method) => {
                parts.push(("sparse factor of K", factor, geometry_key));
                let nodes = lattice(method, &mut parts);
                // Dense eigenproblems of the free scalar system (the exact modal validation
                // of both models; the reduction's dense K_T and M_T; the mass candidates);
                // above DENSE_MODES unknowns the modal and excitation derivations keep the
                // lowest TRUNCATED_MODES of each model instead (shift-invert Lanczos: its
                // basis of 3r + 60 vectors, the modes, the factor of K − σM).
                let scalar = n.max(nodes);
                let truncated = method.linear().is_some_and(|m| m.is_fitted())
                    && scalar > nurbspring_derive::DENSE_MODES as f64;
                if truncated {
                    let r = nurbspring_derive::TRUNCATED_MODES as f64;
                    parts.push((
                        "Lanczos bases of the lowest modes",
                        2.0 * 8.0 * scalar * (4.0 * r + 60.0),
                        geometry_key,
                    ));
                } else {
                    parts.push((
                        "dense eigenproblems",
                        2.0 * 4.0 * 8.0 * scalar * scalar,
                        geometry_key,
                    ));
                }
                output = 64.0 * 1024.0 * 1024.0 + 400.0 * nodes;
            }
        }
        parts.sort_by(|a, b| b.1.total_cmp(&a.1));
        let size_key = parts.first().map_or(geometry_key, |p| p.2);
        let memory = BASE as f64 + SAFETY * parts.iter().map(|p| p.1).sum::<f64>();
        Estimate {
            memory: clamp(memory),
            memory_parts: parts
                .iter()
                .map(|p| Part {
                    what: p.0,
                    bytes: clamp(SAFETY * p.1),
                })
                .collect(),
            output: clamp(output),
            frames: clamp(frame_count),
            size_key,
            too_many_steps,
        }
    }

    /// Refuses (bad input naming the scene key and the estimate) a job whose estimate exceeds
    /// `limits`, or whose output exceeds the free space at `out`.
    pub fn check_resources(
        &self,
        job: Job,
        limits: &Limits,
        out: Option<&Path>,
    ) -> Result<Estimate, Error> {
        let e = self.estimate(job);
        if e.memory > limits.memory {
            let parts: Vec<String> = e
                .memory_parts
                .iter()
                .take(3)
                .map(|p| format!("{} {}", p.what, format_bytes(p.bytes)))
                .collect();
            return Err(Error::Resources {
                path: self.path.clone(),
                key: e.size_key.to_string(),
                message: match limits.address_space {
                    Some(left) if left <= limits.memory => format!(
                        "this model needs an estimated {} of memory ({}), above the {} of address space this process may still map under its limit (ulimit -v, RLIMIT_AS): raise that limit or use a smaller model",
                        format_bytes(e.memory),
                        parts.join(", "),
                        format_bytes(left)
                    ),
                    _ => format!(
                        "this model needs an estimated {} of memory ({}), above the limit of {} (raise it with --max-memory, or use a smaller model)",
                        format_bytes(e.memory),
                        parts.join(", "),
                        format_bytes(limits.memory)
                    ),
                },
            });
        }
        if e.too_many_steps {
            return Ok(e);
        }
        let free = out.and_then(free_space);
        let room = free.map_or(limits.output, |f| f.min(limits.output));
        if e.output > room {
            let why = if free.is_some_and(|f| f < limits.output) {
                format!(
                    "the free space of {} on its disk",
                    format_bytes(free.unwrap_or(0))
                )
            } else {
                format!(
                    "the limit of {} (--max-output)",
                    format_bytes(limits.output)
                )
            };
            return Err(Error::Resources {
                path: self.path.clone(),
                key: if e.frames > 0 {
                    "output.vtk_every".to_string()
                } else {
                    e.size_key.to_string()
                },
                message: format!(
                    "this run would write an estimated {} ({} frames), above {why}; write fewer frames (output.vtk_every, simulation.save_every) or a shorter run",
                    format_bytes(e.output),
                    e.frames
                ),
            });
        }
        Ok(e)
    }
}

/// An `f64` byte count as `u64`, saturating (`u64::MAX` for anything at or above 2⁶⁴).
fn clamp(x: f64) -> u64 {
    if x.is_nan() || x <= 0.0 {
        0
    } else if x >= u64::MAX as f64 {
        u64::MAX
    } else {
        x as u64
    }
}
