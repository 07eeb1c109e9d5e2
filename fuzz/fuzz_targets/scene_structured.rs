//! Structured scenes: valid-looking TOML built from arbitrary sizes, degrees, knots, points,
//! material and options, so most inputs get past parsing into the models.
#![no_main]

use std::fmt::Write;

use arbitrary::Arbitrary;
use libfuzzer_sys::fuzz_target;

#[path = "common.rs"]
mod common;

#[derive(Arbitrary, Debug)]
struct Input {
    curve: bool,
    degree_u: u8,
    degree_v: u8,
    n_u: u8,
    n_v: u8,
    knot_steps_u: Vec<u8>,
    knot_steps_v: Vec<u8>,
    jitter: Vec<i8>,
    weights: Vec<u8>,
    material: [u8; 7],
    fixed_rings: u8,
    velocity_z: i8,
    dt_exp: i8,
    grid: u8,
    nodes: (u8, u8),
    springs: (bool, bool, bool),
    k: [u8; 3],
    mass: u8,
    pre_strain: i8,
    weights_as_dofs: bool,
    area: bool,
    rest_zero: bool,
    gravity: i8,
}

fn knots(steps: &[u8], degree: usize, n: usize) -> Vec<f64> {
    // n + degree + 1 knots: clamped ends, interior increments from the input (0 = repeat).
    let interior = n.saturating_sub(degree + 1);
    let mut inner = Vec::with_capacity(interior);
    let mut x = 0.0;
    for i in 0..interior {
        x += f64::from(steps.get(i).copied().unwrap_or(1) % 4);
        inner.push(x);
    }
    let end = x + 1.0;
    let mut k = vec![0.0; degree + 1];
    k.extend(inner);
    k.extend(std::iter::repeat_n(end, degree + 1));
    k.iter().map(|v| v / end).collect()
}

fn list(v: &[f64]) -> String {
    format!("[{}]", v.iter().map(|x| format!("{x:?}")).collect::<Vec<_>>().join(", "))
}

fn scene(i: &Input) -> String {
    let pu = usize::from(i.degree_u % 4) + 1;
    let pv = usize::from(i.degree_v % 4) + 1;
    let nu = pu + 1 + usize::from(i.n_u % 8);
    let nv = pv + 1 + usize::from(i.n_v % 8);
    let jitter = |k: usize| f64::from(i.jitter.get(k).copied().unwrap_or(0)) / 256.0;
    let weight = |k: usize| f64::from(i.weights.get(k).copied().unwrap_or(128)) / 128.0;
    let m = |k: usize| f64::from(i.material[k]) / 16.0;
    let mut s = String::new();
    if i.curve {
        let _ = writeln!(s, "[curve]\ndegree = {pu}\nknots = {}", list(&knots(&i.knot_steps_u, pu, nu)));
        let pts: Vec<String> = (0..nu).map(|a| format!("[{:?}, 0.0, {:?}]", a as f64, jitter(a))).collect();
        let _ = writeln!(s, "control_points = [{}]", pts.join(", "));
        let w: Vec<f64> = (0..nu).map(weight).collect();
        let _ = writeln!(s, "weights = {}", list(&w));
        let _ = writeln!(s, "[material]\nmu = {:?}\ngamma = {:?}\nalpha11 = {:?}\nbeta11 = {:?}", m(0), m(1), m(2), m(3));
    } else {
        let _ = writeln!(
            s,
            "[surface]\ndegree_u = {pu}\ndegree_v = {pv}\nknots_u = {}\nknots_v = {}",
            list(&knots(&i.knot_steps_u, pu, nu)),
            list(&knots(&i.knot_steps_v, pv, nv))
        );
        let rows: Vec<String> = (0..nu)
            .map(|a| {
                let row: Vec<String> = (0..nv)
                    .map(|b| format!("[{:?}, {:?}, {:?}]", a as f64, b as f64, jitter(a * nv + b)))
                    .collect();
                format!("[{}]", row.join(", "))
            })
            .collect();
        let _ = writeln!(s, "control_points = [{}]", rows.join(", "));
        let wrows: Vec<String> = (0..nu).map(|a| list(&(0..nv).map(|b| weight(a * nv + b)).collect::<Vec<_>>())).collect();
        let _ = writeln!(s, "weights = [{}]", wrows.join(", "));
        let _ = writeln!(
            s,
            "[material]\nmu = {:?}\ngamma = {:?}\nalpha11 = {:?}\nalpha22 = {:?}\nbeta11 = {:?}\nbeta12 = {:?}\nbeta22 = {:?}",
            m(0), m(1), m(2), m(3), m(4), m(5), m(6)
        );
        let grid = ["knots", "uniform", "greville"][usize::from(i.grid % 3)];
        let _ = writeln!(
            s,
            "[msm]\ngrid = \"{grid}\"\nnodes_u = {}\nnodes_v = {}\nstructural = {}\nshear = {}\nbending = {}\nk_edge = {:?}\nk_diag = {:?}\nk_bend = {:?}\nmass = {:?}\npre_strain = {:?}",
            2 + i.nodes.0 % 10,
            2 + i.nodes.1 % 10,
            i.springs.0,
            i.springs.1,
            i.springs.2,
            f64::from(i.k[0]) / 8.0,
            f64::from(i.k[1]) / 8.0,
            f64::from(i.k[2]) / 8.0,
            f64::from(i.mass) / 64.0,
            f64::from(i.pre_strain) / 128.0,
        );
    }
    let _ = writeln!(s, "[loads]\ngravity = [0.0, 0.0, {:?}]", f64::from(i.gravity) / 8.0);
    let _ = writeln!(s, "[constraints]\nfixed_rings = {}", i.fixed_rings % 3);
    let _ = writeln!(
        s,
        "[dnurbs]\nweights_as_dofs = {}\nintegrate_over = \"{}\"\nrest_shape = \"{}\"",
        i.weights_as_dofs,
        if i.area { "area" } else { "parameter" },
        if i.rest_zero { "zero" } else { "initial" }
    );
    let _ = writeln!(s, "[initial]\nvelocity = [0.0, 0.0, {:?}]", f64::from(i.velocity_z) / 64.0);
    let _ = writeln!(s, "[simulation]\ndt = {:?}\nt_end = 1.0", 10f64.powi(i32::from(i.dt_exp % 6) - 4));
    s
}

fuzz_target!(|input: Input| {
    let text = scene(&input);
    // `NURBSPRING_FUZZ_PRINT=1 …/scene_structured ARTIFACT` prints the scene of a finding, to
    // turn it into a test of the main suite.
    if std::env::var_os("NURBSPRING_FUZZ_PRINT").is_some() {
        eprintln!("{text}");
    }
    common::run_scene_text(&text);
});
