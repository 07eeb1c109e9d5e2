//! The flat sheet shared by the scene tests and the `derive` benchmark.

use std::fmt::Write;

/// A flat 1 × 1 bicubic sheet with `n × n` control points at the Greville abscissae of uniform
/// clamped knots, clamped by two rings, struck by a uniform initial velocity, simulated with
/// step `dt` for 20 s: the scene's text.
pub fn sheet_text(n: usize, dt: f64) -> String {
    let p = 3;
    let inner = n - p - 1;
    let mut knots = vec![0.0; p + 1];
    knots.extend((1..=inner).map(|i| i as f64 / (inner + 1) as f64));
    knots.extend(vec![1.0; p + 1]);
    let greville: Vec<f64> = (0..n)
        .map(|i| knots[i + 1..i + p + 1].iter().sum::<f64>() / p as f64)
        .collect();
    let mut s = String::new();
    writeln!(s, "[surface]\ndegree_u = 3\ndegree_v = 3").unwrap();
    writeln!(s, "knots_u = {knots:?}\nknots_v = {knots:?}").unwrap();
    s.push_str("control_points = [\n");
    for x in &greville {
        let row: Vec<String> = greville
            .iter()
            .map(|y| format!("[{x:?}, {y:?}, 0.0]"))
            .collect();
        writeln!(s, "  [{}],", row.join(", ")).unwrap();
    }
    s.push_str("]\n");
    write!(
        s,
        "[material]\nmu = 1.0\nalpha11 = 1.0\nalpha22 = 1.0\nbeta11 = 0.01\nbeta22 = 0.01\n\
         [constraints]\nfixed_rings = 2\n[initial]\nvelocity = [0.0, 0.0, -0.1]\n\
         [simulation]\ndt = {dt:?}\nt_end = 20.0\n"
    )
    .unwrap();
    s
}
