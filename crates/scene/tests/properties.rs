//! Property test over random valid and invalid scenes (the CI counterpart of the fuzz targets
//! in `fuzz/`): parsing, validation, conversion, a few steps of each model and the fit set-up
//! never panic; every refusal is an error with a message.

use nurbspring_scene::{MsmOverrides, Scene};
use nurbspring_sim::{IntegratorKind, RunOptions, Sample, simulate};
use proptest::prelude::*;

#[derive(Debug, Clone)]
struct Params {
    pu: usize,
    pv: usize,
    extra_u: usize,
    extra_v: usize,
    jitter: Vec<f64>,
    weight: f64,
    material: [f64; 4],
    rings: usize,
    vz: f64,
    dt: f64,
    grid: usize,
    pre_strain: f64,
    weights_as_dofs: bool,
    mutation: Option<(usize, String)>,
}

fn params() -> impl Strategy<Value = Params> {
    (
        (1usize..=3, 1usize..=3, 0usize..4, 0usize..4),
        prop::collection::vec(-0.5f64..0.5, 64),
        0.2f64..3.0,
        prop::array::uniform4(0.0f64..2.0),
        (
            0usize..3,
            -1.0f64..1.0,
            prop::sample::select(vec![1e-4, 1e-3, 1e-2, 0.1]),
            0usize..3,
        ),
        (-0.3f64..0.3, any::<bool>()),
        prop::option::of((
            0usize..40,
            prop::sample::select(vec![
                "-1".to_string(),
                "nan".to_string(),
                "inf".to_string(),
                "0".to_string(),
                "\"x\"".to_string(),
                "[]".to_string(),
                "1e400".to_string(),
                "99999999999".to_string(),
            ]),
        )),
    )
        .prop_map(
            |(
                (pu, pv, extra_u, extra_v),
                jitter,
                weight,
                material,
                (rings, vz, dt, grid),
                (pre_strain, wad),
                mutation,
            )| Params {
                pu,
                pv,
                extra_u,
                extra_v,
                jitter,
                weight,
                material,
                rings,
                vz,
                dt,
                grid,
                pre_strain,
                weights_as_dofs: wad,
                mutation,
            },
        )
}

fn clamped(p: usize, n: usize) -> String {
    let interior = n - p - 1;
    let mut k = vec![0.0; p + 1];
    k.extend((1..=interior).map(|i| i as f64 / (interior + 1) as f64));
    k.extend(std::iter::repeat_n(1.0, p + 1));
    format!("{k:?}")
}

fn scene_text(x: &Params) -> String {
    let nu = x.pu + 1 + x.extra_u;
    let nv = x.pv + 1 + x.extra_v;
    let rows: Vec<String> = (0..nu)
        .map(|i| {
            let row: Vec<String> = (0..nv)
                .map(|j| {
                    format!(
                        "[{:?}, {:?}, {:?}]",
                        i as f64,
                        j as f64,
                        x.jitter[(i * nv + j) % 64]
                    )
                })
                .collect();
            format!("[{}]", row.join(", "))
        })
        .collect();
    let wrows: Vec<String> = (0..nu)
        .map(|i| {
            format!(
                "[{}]",
                (0..nv)
                    .map(|j| format!("{:?}", if (i + j) % 2 == 0 { 1.0 } else { x.weight }))
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        })
        .collect();
    let lines = vec![
        "[surface]".to_string(),
        format!("degree_u = {}", x.pu),
        format!("degree_v = {}", x.pv),
        format!("knots_u = {}", clamped(x.pu, nu)),
        format!("knots_v = {}", clamped(x.pv, nv)),
        format!("control_points = [{}]", rows.join(", ")),
        format!("weights = [{}]", wrows.join(", ")),
        "[material]".to_string(),
        format!("mu = {:?}", 0.1 + x.material[0]),
        format!("alpha11 = {:?}", x.material[1]),
        format!("alpha22 = {:?}", x.material[2]),
        format!("beta11 = {:?}", x.material[3]),
        "[constraints]".to_string(),
        format!("fixed_rings = {}", x.rings),
        "[dnurbs]".to_string(),
        format!("weights_as_dofs = {}", x.weights_as_dofs),
        "[initial]".to_string(),
        format!("velocity = [0.0, 0.0, {:?}]", x.vz),
        "[simulation]".to_string(),
        format!("dt = {:?}", x.dt),
        "t_end = 1.0".to_string(),
        "[msm]".to_string(),
        format!("grid = \"{}\"", ["knots", "uniform", "greville"][x.grid]),
        "bending = true".to_string(),
        format!("pre_strain = {:?}", x.pre_strain),
        "[fit]".to_string(),
        "max_candidates = 2".to_string(),
    ];
    let mut lines = lines;
    if let Some((line, value)) = &x.mutation {
        // Replace the value of one `key = value` line: an invalid scene.
        let idx = line % lines.len();
        if let Some(eq) = lines[idx].find(" = ") {
            lines[idx] = format!("{} = {value}", &lines[idx][..eq]);
        }
    }
    lines.join("\n")
}

fn exercise(text: &str) {
    let scene = match Scene::from_str(text, "prop.toml") {
        Ok(s) => s,
        Err(e) => {
            assert!(!e.to_string().is_empty());
            return;
        }
    };
    let model = match scene.build_dnurbs() {
        Ok(m) => m,
        Err(e) => {
            assert!(!e.to_string().is_empty());
            return;
        }
    };
    let dt = scene.simulation.dt;
    let initial = scene.initial_conditions().state(&model);
    for kind in [IntegratorKind::TerzopoulosQin, IntegratorKind::Newmark] {
        let opts = RunOptions::new(dt, 3.0 * dt, kind);
        let _ = model.simulate(initial.clone(), &opts, &mut |_: &Sample<'_>| {});
    }
    match scene.msm_setup(&MsmOverrides::default()) {
        Ok(setup) => {
            for kind in [
                IntegratorKind::SymplecticEuler,
                IntegratorKind::BackwardEuler,
            ] {
                let mut opts = RunOptions::new(dt, 3.0 * dt, kind);
                opts.force_unstable = true;
                let _ = simulate(
                    &setup.model,
                    setup.initial.clone(),
                    &opts,
                    &mut |_: &Sample<'_>| {},
                );
            }
        }
        Err(e) => assert!(!e.to_string().is_empty()),
    }
    if let Ok(config) = scene.derivation_config(Some(nurbspring_derive::Method::Paper))
        && let Ok(setup) = nurbspring_derive::Setup::new(&config)
    {
        let _ = setup.solve(nurbspring_derive::FitDofs::All, false);
        let _ = setup.solve(nurbspring_derive::FitDofs::Free, true);
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    #[test]
    fn random_scenes_never_panic(x in params()) {
        exercise(&scene_text(&x));
    }

    #[test]
    fn random_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..400)) {
        exercise(&String::from_utf8_lossy(&bytes));
    }
}
