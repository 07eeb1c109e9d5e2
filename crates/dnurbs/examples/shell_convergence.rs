//! The h- and p-convergence table of the shell benchmarks in docs/shell.md:
//! `cargo run --release -p nurbspring-dnurbs --example shell_convergence`.

use nurbspring_dnurbs::obstacle::{self, Benchmark};
use nurbspring_dnurbs::{DnurbsError, PathSettings};

fn linear(b: &Benchmark) -> Result<f64, DnurbsError> {
    b.displacement(&b.model.linearized_steady_state()?)
}

fn nonlinear(b: &Benchmark, levels: usize) -> Result<f64, DnurbsError> {
    let settings = PathSettings {
        levels,
        ..PathSettings::default()
    };
    let path = b
        .model
        .equilibrium_path(&settings, &|| false, &mut |_| {})?;
    b.displacement(&path.levels.last().expect("a level").p)
}

fn row(name: &str, degree: usize, spans: &str, value: f64, reference: f64) {
    println!(
        "| {name} | {degree} | {spans} | {value:.6e} | {reference:.6e} | {:+.3} % |",
        100.0 * (value - reference) / reference
    );
}

fn main() -> Result<(), DnurbsError> {
    println!("| problem | degree | spans | nurbspring | reference | difference |");
    println!("|---|---|---|---|---|---|");
    for degree in [2, 3, 4] {
        for spans in [4, 8, 16, 32] {
            let b = obstacle::scordelis_lo(degree, spans)?;
            row(
                "Scordelis–Lo roof (linear)",
                degree,
                &format!("{spans}²"),
                linear(&b)?,
                b.reference,
            );
        }
    }
    for degree in [2, 3, 4] {
        for spans in [4, 8, 16, 32] {
            let b = obstacle::pinched_cylinder(degree, spans)?;
            row(
                "pinched cylinder (linear)",
                degree,
                &format!("{spans}²"),
                linear(&b)?,
                b.reference,
            );
        }
    }
    for degree in [2, 3, 4] {
        for spans in [4, 8, 16, 32] {
            let b = obstacle::hemisphere(degree, spans, 1.0)?;
            row(
                "pinched hemisphere, 18° hole (linear)",
                degree,
                &format!("{spans}²"),
                linear(&b)?,
                b.reference,
            );
        }
    }
    for (degree, spans) in [(2, 8), (3, 8), (3, 16), (4, 16)] {
        let b = obstacle::sze_cantilever(degree, spans)?;
        row(
            "Sze cantilever, w at P_max",
            degree,
            &format!("{spans} × 1"),
            nonlinear(&b, 4)?,
            b.reference,
        );
    }
    for (degree, spans) in [(2, (6, 48)), (3, (6, 48)), (3, (8, 64))] {
        let b = obstacle::slit_annular_plate(degree, spans)?;
        let label = format!("{} × {}", spans.0, spans.1);
        row(
            "Sze slit annular plate, w_B at P_max",
            degree,
            &label,
            nonlinear(&b, 8)?,
            b.reference,
        );
    }
    Ok(())
}
