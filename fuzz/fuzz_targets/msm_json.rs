//! Structured msm.json files: nodes, springs and linear elements built from arbitrary numbers
//! (including huge, tiny, negative and non-finite ones, repeated nodes and out-of-range
//! indices), through the same reader `simulate msm.json` uses, then a few steps of every MSM
//! integrator and the stability limit. Errors are expected; panics, hangs and aborts are
//! findings.
#![no_main]

use std::fmt::Write;

use arbitrary::Arbitrary;
use libfuzzer_sys::fuzz_target;
use nurbspring_scene::MsmOverrides;
use nurbspring_scene::msm_file::msm_setup_from_text;
use nurbspring_sim::{RunOptions, simulate};

#[derive(Arbitrary, Debug)]
struct Node {
    position: [i16; 3],
    mass_exp: i8,
    fixed: bool,
    damping: u8,
    uv: Option<(u8, u8)>,
}

#[derive(Arbitrary, Debug)]
struct Spring {
    a: u8,
    b: u8,
    kind: u8,
    k_exp: i8,
    rest: Option<i8>,
}

#[derive(Arbitrary, Debug)]
struct Element {
    kind: u8,
    nodes: Vec<u8>,
    k_exp: i8,
    weight_exp: i8,
    coefficients: Vec<i8>,
}

#[derive(Arbitrary, Debug)]
struct Input {
    nodes: Vec<Node>,
    springs: Vec<Spring>,
    elements: Vec<Element>,
    gravity: [i8; 3],
    velocities: Option<Vec<[i8; 3]>>,
    grid: Option<(u8, u8)>,
    dt_exp: i8,
    special: u8,
}

/// A number from an exponent: 10^(e/8), with a few special values the fuzzer can reach.
fn num(e: i8, special: u8) -> String {
    match special % 32 {
        0 => "1e308".into(),
        1 => "-0.0".into(),
        2 => "5e-324".into(),
        3 => "1e31".into(),
        _ => format!("{:e}", 10f64.powf(f64::from(e) / 8.0)),
    }
}

fn text(i: &Input) -> String {
    let mut s = String::from("{\"nodes\": [");
    for (n, node) in i.nodes.iter().take(64).enumerate() {
        if n > 0 {
            s.push(',');
        }
        let p = node.position.map(|x| f64::from(x) / 64.0);
        let _ = write!(
            s,
            "{{\"position\": [{:?}, {:?}, {:?}], \"mass\": {}, \"fixed\": {}, \"damping\": {}",
            p[0],
            p[1],
            p[2],
            num(node.mass_exp, i.special.wrapping_add(n as u8)),
            node.fixed,
            f64::from(node.damping) / 16.0
        );
        if let Some((u, v)) = node.uv {
            let _ = write!(s, ", \"uv\": [{:?}, {:?}]", f64::from(u) / 255.0, f64::from(v) / 255.0);
        }
        s.push('}');
    }
    s.push_str("], \"springs\": [");
    let kinds = ["structural", "shear", "bending", "other"];
    for (n, sp) in i.springs.iter().take(256).enumerate() {
        if n > 0 {
            s.push(',');
        }
        let _ = write!(
            s,
            "{{\"a\": {}, \"b\": {}, \"kind\": \"{}\", \"k\": {}",
            sp.a,
            sp.b,
            kinds[usize::from(sp.kind) % kinds.len()],
            num(sp.k_exp, i.special.wrapping_mul(3).wrapping_add(n as u8))
        );
        if let Some(r) = sp.rest {
            let _ = write!(s, ", \"rest_length\": {:?}", f64::from(r) / 16.0);
        }
        s.push('}');
    }
    s.push(']');
    if !i.elements.is_empty() {
        s.push_str(", \"elements\": [");
        let kinds = ["spring_u", "spring_v", "diagonal", "bend_u", "bend_v", "twist", "nope"];
        for (n, e) in i.elements.iter().take(128).enumerate() {
            if n > 0 {
                s.push(',');
            }
            let nodes: Vec<String> = e.nodes.iter().take(5).map(|a| a.to_string()).collect();
            let coefficients: Vec<String> = e
                .coefficients
                .iter()
                .take(5)
                .map(|c| format!("{:?}", f64::from(*c) / 8.0))
                .collect();
            let _ = write!(
                s,
                "{{\"kind\": \"{}\", \"class\": \"spring_u@interior\", \"nodes\": [{}], \"k\": {}, \"weight\": {}, \"coefficients\": [{}]}}",
                kinds[usize::from(e.kind) % kinds.len()],
                nodes.join(", "),
                num(e.k_exp, i.special.wrapping_add(7 * n as u8)),
                num(e.weight_exp, i.special.wrapping_add(11 * n as u8)),
                coefficients.join(", ")
            );
        }
        s.push(']');
    }
    let g = i.gravity.map(|x| f64::from(x) / 8.0);
    let _ = write!(s, ", \"gravity\": [{:?}, {:?}, {:?}]", g[0], g[1], g[2]);
    if let Some((u, v)) = i.grid {
        let _ = write!(s, ", \"grid\": [{u}, {v}]");
    }
    if let Some(v) = &i.velocities {
        let list: Vec<String> = v
            .iter()
            .take(65)
            .map(|x| format!("[{}, {}, {}]", x[0], x[1], x[2]))
            .collect();
        let _ = write!(s, ", \"initial_velocities\": [{}]", list.join(", "));
    }
    s.push('}');
    s
}

fuzz_target!(|input: Input| {
    let json = text(&input);
    let Ok(setup) = msm_setup_from_text(&json, "fuzz.json".as_ref(), &MsmOverrides::default())
    else {
        return;
    };
    let _ = setup.model.stability();
    let dt = 10f64.powf(f64::from(input.dt_exp.clamp(-64, 8)) / 16.0);
    for kind in nurbspring_msm::MsmModel::INTEGRATORS {
        let mut opts = RunOptions::new(dt, 3.0 * dt, kind);
        opts.force_unstable = true;
        let _ = simulate(
            &setup.model,
            setup.initial.clone(),
            &opts,
            &mut |_: &nurbspring_sim::Sample<'_>| {},
        );
    }
});
