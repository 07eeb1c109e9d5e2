//! The nonlinear static solves timed beside Kratos' Shell3pElement
//! (bench-peers/run_shell.sh, docs/benchmarks.md): builds a benchmark of
//! `nurbspring_dnurbs::obstacle`, follows its equilibrium path, and prints one JSON line with
//! the best of `repeats` wall times of the model building and of the solve, the Newton
//! iterations and the compared displacements at every level.
//!
//! `cargo run --release -p nurbspring-dnurbs --example shell_solve -- scordelis|cantilever|hemisphere [spans] [repeats]`
//! (threads: `RAYON_NUM_THREADS`).

use std::time::Instant;

use nurbspring_dnurbs::obstacle::{self, Benchmark};
use nurbspring_dnurbs::{DnurbsError, PathSettings};

fn build(problem: &str, spans: usize) -> Result<(Benchmark, usize), DnurbsError> {
    Ok(match problem {
        "scordelis" => (obstacle::scordelis_lo_roof(4, spans)?, 10),
        "cantilever" => (obstacle::sze_cantilever(3, spans)?, 20),
        "hemisphere" => (obstacle::hemisphere(4, spans, 200.0)?, 20),
        other => {
            return Err(DnurbsError::InvalidOption {
                name: "problem",
                value: other.to_string(),
                reason: "expected scordelis, cantilever or hemisphere".into(),
            });
        }
    })
}

fn main() -> Result<(), DnurbsError> {
    let args: Vec<String> = std::env::args().collect();
    let problem = args.get(1).map_or("cantilever", String::as_str);
    let spans: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(16);
    let repeats: usize = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(3);
    let (mut best_build, mut best_solve) = (f64::INFINITY, f64::INFINITY);
    let mut report = String::new();
    for _ in 0..repeats.max(1) {
        let t = Instant::now();
        let (bench, levels) = build(problem, spans)?;
        best_build = best_build.min(t.elapsed().as_secs_f64());
        let settings = PathSettings {
            levels,
            ..PathSettings::default()
        };
        let t = Instant::now();
        let path = bench
            .model
            .equilibrium_path(&settings, &|| false, &mut |_| {})?;
        best_solve = best_solve.min(t.elapsed().as_secs_f64());
        let values: Vec<String> = path
            .levels
            .iter()
            .map(|l| Ok(format!("[{}, {}]", l.lambda, bench.displacement(&l.p)?)))
            .collect::<Result<_, DnurbsError>>()?;
        report = format!(
            "\"dofs\": {}, \"increments\": {}, \"iterations\": {}, \"levels\": [{}]",
            bench.model.p0().len(),
            path.increments,
            path.iterations,
            values.join(", ")
        );
    }
    println!(
        "{{\"problem\": \"{problem}\", \"spans\": {spans}, \"build_s\": {best_build}, \"solve_s\": {best_solve}, {report}}}"
    );
    Ok(())
}
