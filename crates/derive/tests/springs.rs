//! The spring derivation of a Kirchhoff–Love shell (docs/math.md §11): the energy-equivalence
//! rules against the plane-stress sheet and the plate, and the derived model's invariants
//! (stress-free at rest, rigid motion, lowest frequency, mass) and its large-motion accuracy
//! on Sze's cantilever; the modal derivation's calibration by class and band.

use nurbspring_derive::{
    InitialConditions, Method, SpringsConfig, TimeSettings, derive_springs, reduce_shell,
    rule_lattice,
};
use nurbspring_dnurbs::Geometry;
use nurbspring_dnurbs::obstacle::{cylinder_sector, rectangle, refined};
use nurbspring_dnurbs::{
    Constraints, DnurbsOptions, Edge, EdgeCondition, EdgeConstraint, EdgeLoad, Loads, PointLoad,
    ShellMaterial,
};
use nurbspring_msm::{FixedNodes, LatticeOptions, ParameterGrid, SpringLattice};
use nurbspring_sim::IntegratorKind;

fn material(poisson: f64) -> ShellMaterial {
    ShellMaterial {
        young: 7.0e7,
        poisson,
        thickness: 0.01,
        density: 1200.0,
        gamma: 0.0,
    }
}

/// A unit square sampled on an 9 × 9 uniform grid (8 × 8 cells, half with each diagonal).
fn square_lattice(shell: &ShellMaterial) -> SpringLattice {
    let options = LatticeOptions {
        grid: ParameterGrid::Uniform {
            nodes_u: 9,
            nodes_v: 9,
        },
        fixed: FixedNodes::Auto,
        ..LatticeOptions::default()
    };
    rule_lattice(&rectangle(1.0, 1.0), shell, &options, &[])
        .unwrap()
        .0
}

fn moved(lattice: &SpringLattice, f: impl Fn([f64; 3]) -> [f64; 3]) -> Vec<f64> {
    lattice.positions.iter().flat_map(|&x| f(x)).collect()
}

#[test]
fn membrane_springs_are_the_plane_stress_sheet_with_poisson_one_third() {
    for nu in [0.0, 0.3, 0.45] {
        let shell = material(nu);
        let lattice = square_lattice(&shell);
        let e_bar = shell.membrane_stiffness();
        // The sheet the rule aims at: modulus Ē, ν = 1/3 (C₁₁₁₁ = Ē, C₁₁₂₂ = C₁₂₁₂ = Ē/3).
        let strains = [
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.7, -0.4, 0.3],
        ];
        for [e11, e22, e12] in strains {
            let s = 1e-6;
            let (e11, e22, e12) = (s * e11, s * e22, s * e12);
            let x = moved(&lattice, |p| {
                [
                    p[0] + e11 * p[0] + e12 * p[1],
                    p[1] + e12 * p[0] + e22 * p[1],
                    0.0,
                ]
            });
            let energy = lattice.elastic_energy(&x);
            let expected = 0.5
                * e_bar
                * (e11 * e11 + e22 * e22 + 2.0 / 3.0 * e11 * e22 + 4.0 / 3.0 * e12 * e12);
            assert!(
                ((energy - expected) / expected).abs() < 1e-5,
                "ν = {nu}, strain ({e11}, {e22}, {e12}): lattice {energy:e}, sheet {expected:e}"
            );
        }
    }
}

#[test]
fn hinges_bend_and_twist_like_the_plate_without_the_coupling() {
    let shell = material(0.3);
    let lattice = square_lattice(&shell);
    let d = shell.bending_stiffness();
    let k = 1e-4;
    // Cylindrical bending along u: the hinges on the 7 interior grid lines u = const carry it
    // (the 8 columns of cells meet there), so the energy is ½ D κ² over 7/8 of the square.
    let x = moved(&lattice, |p| [p[0], p[1], 0.5 * k * p[0] * p[0]]);
    let bend = lattice.elastic_energy(&x);
    let expected = 0.5 * d * k * k * 7.0 / 8.0;
    assert!(
        ((bend - expected) / expected).abs() < 1e-3,
        "bending: {bend:e} against {expected:e}"
    );
    // Pure twist z = τ x y: every cell's diagonal hinge is interior; the plate's D (1 − ν) τ²
    // over the square.
    let x = moved(&lattice, |p| [p[0], p[1], k * p[0] * p[1]]);
    let twist = lattice.elastic_energy(&x);
    let expected = d * (1.0 - 0.3) * k * k;
    assert!(
        ((twist - expected) / expected).abs() < 1e-3,
        "twist: {twist:e} against {expected:e}"
    );
}

fn clamped_plate_config(surface: nurbspring_geom::NurbsSurface) -> SpringsConfig {
    SpringsConfig {
        surface,
        shell: material(0.3),
        loads: Loads {
            point: vec![PointLoad {
                u: 1.0,
                v: 1.0,
                force: [0.0, 0.0, 2.0],
            }],
            ..Loads::default()
        },
        constraints: Constraints {
            edges: vec![EdgeConstraint {
                edge: Edge::U0,
                condition: EdgeCondition::Clamped,
            }],
            ..Constraints::default()
        },
        dnurbs: DnurbsOptions::default(),
        lattice: LatticeOptions {
            grid: ParameterGrid::Greville,
            fixed: FixedNodes::Auto,
            ..LatticeOptions::default()
        },
        initial: InitialConditions::default(),
        time: TimeSettings {
            dt: 0.001,
            t_end: 0.1,
            dnurbs_integrator: IntegratorKind::Newmark,
            msm_integrator: IntegratorKind::Newmark,
        },
        probes: vec![(0.5, 0.5)],
        method: Method::Springs,
    }
}

fn rotate(x: [f64; 3]) -> [f64; 3] {
    // A rotation by 0.7 rad about (1, 2, 2)/3 and a translation.
    let n = [1.0 / 3.0, 2.0 / 3.0, 2.0 / 3.0];
    let (s, c) = 0.7_f64.sin_cos();
    let dot = n[0] * x[0] + n[1] * x[1] + n[2] * x[2];
    let cross = [
        n[1] * x[2] - n[2] * x[1],
        n[2] * x[0] - n[0] * x[2],
        n[0] * x[1] - n[1] * x[0],
    ];
    std::array::from_fn(|k| x[k] * c + cross[k] * s + n[k] * dot * (1.0 - c) + [0.3, -1.2, 2.0][k])
}

/// No force at rest nor after a rigid rotation and translation, to round-off of the largest
/// spring force scale.
fn assert_stress_free_and_rotation_invariant(lattice: &SpringLattice) {
    let scale: f64 = lattice
        .springs
        .iter()
        .map(|s| s.stiffness() * s.rest_length)
        .fold(0.0, f64::max);
    let mut f = vec![0.0; 3 * lattice.n_nodes()];
    lattice.elastic_forces(&lattice.flat_positions(), &mut f);
    let rest = f.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    lattice.elastic_forces(&moved(lattice, rotate), &mut f);
    let rigid = f.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    assert!(rest <= 1e-12 * scale, "at rest: {rest:e} (scale {scale:e})");
    assert!(
        rigid <= 1e-9 * scale,
        "rotated: {rigid:e} (scale {scale:e})"
    );
}

#[test]
fn a_derived_curved_model_is_stress_free_at_rest_and_under_rigid_motion() {
    let surface = refined(&cylinder_sector(0.5, 0.6, 0.9, 2.2), 3, (4, 4)).unwrap();
    let config = clamped_plate_config(surface);
    let d = derive_springs(&config, None, &mut |_| {}).unwrap();
    let lattice = &d.lattice;
    assert_stress_free_and_rotation_invariant(lattice);
    assert!(lattice.hinges.iter().any(|h| h.rest_angle.abs() > 1e-3));
    // The lowest elastic frequency is the shell's; the masses are ρ t × the surface area
    // (the arc r Δθ times the length).
    let first = &d.frequencies[0];
    assert!(first.relative_error.unwrap().abs() < 1e-9, "{first:?}");
    let area = 0.5 * (2.2 - 0.9) * 0.6;
    let mass = config.shell.mass_per_area() * area;
    assert!(
        ((d.total_mass - mass) / mass).abs() < 1e-9,
        "{} against {mass}",
        d.total_mass
    );
}

#[test]
fn sze_cantilever_nodes_follow_the_shell_at_every_load_level() {
    // Sze, Liu and Lo (2004) §3.1: the strip under end shear up to P_max = 4 (the tip moves
    // 67 % of the length); the issue's target is 3 % of the size at every level, measured
    // 0.73 %.
    let mut config = clamped_plate_config(refined(&rectangle(10.0, 1.0), 3, (16, 1)).unwrap());
    config.shell = ShellMaterial {
        young: 1.2e6,
        poisson: 0.0,
        thickness: 0.1,
        density: 500.0,
        gamma: 0.0,
    };
    config.loads = Loads {
        edges: vec![EdgeLoad {
            edge: Edge::U1,
            force: [0.0, 0.0, 4.0],
            moment: 0.0,
        }],
        ..Loads::default()
    };
    config.probes = vec![(1.0, 0.5)];
    let d = derive_springs(&config, None, &mut |_| {}).unwrap();
    let large = d.large_motion.as_ref().unwrap();
    assert!((large.load_factor - 1.0).abs() < 1e-12);
    assert_eq!(large.levels.len(), 4);
    for level in &large.levels {
        assert!(level.max_error < 0.01, "{level:?}");
    }
    assert!(large.largest_displacement.unwrap() > 0.7);
    assert!(d.small_motion.relative_rms < 0.03, "{:?}", d.small_motion);
}

/// The modal derivation of a shell calibrates one scale per class and band: every spring and
/// hinge is in one group, the model stays stress-free at rest and under rigid motion, the
/// masses and the lowest frequency stay exact, and the finer groups fit the shell's modes at
/// least as closely as four class constants do (the free-edge plate, whose hinges miss the
/// plate's coupling term near the free edges).
#[test]
fn the_modal_derivation_of_a_shell_fits_its_modes_by_band() {
    let mut config = clamped_plate_config(refined(&rectangle(0.4, 0.3), 3, (3, 3)).unwrap());
    config.loads = Loads::default();
    let springs = derive_springs(&config, None, &mut |_| {}).unwrap();
    config.method = Method::Modal;
    let d = derive_springs(&config, None, &mut |_| {}).unwrap();
    assert_eq!(d.method, Method::Modal);
    assert!(springs.groups.is_empty());
    let lattice = &d.lattice;
    let grouped: usize = d.groups.iter().map(|g| g.elements).sum();
    assert_eq!(grouped, lattice.springs.len() + lattice.hinges.len());
    assert!(d.groups.len() > 4, "{} groups", d.groups.len());
    assert!(
        d.groups
            .iter()
            .all(|g| g.scale > 0.0 && g.scale.is_finite())
    );
    // The scales vary by band (else the grouping would be the class one).
    let spread = d.groups.iter().map(|g| g.scale).fold(0.0_f64, f64::max)
        / d.groups
            .iter()
            .map(|g| g.scale)
            .fold(f64::INFINITY, f64::min);
    assert!(spread > 1.01, "{spread}");
    assert_stress_free_and_rotation_invariant(lattice);
    assert!(d.frequencies[0].relative_error.unwrap().abs() < 1e-9);
    assert_eq!(d.total_mass, springs.total_mass);
    assert!(
        d.fit_residual <= springs.fit_residual,
        "by band {} against by class {}",
        d.fit_residual,
        springs.fit_residual
    );
}

/// The excitation derivation of a shell fits the modes its loads move most, each row weighted
/// by its share; a shell that nothing excites is refused.
#[test]
fn the_excitation_derivation_of_a_shell_fits_the_excited_modes() {
    let mut config = clamped_plate_config(refined(&rectangle(0.4, 0.3), 3, (3, 3)).unwrap());
    config.method = Method::Excitation;
    config.loads = Loads {
        point: vec![PointLoad {
            u: 1.0,
            v: 1.0,
            force: [0.0, 0.0, 2.0],
        }],
        ..Loads::default()
    };
    // Only the calibration is under test: the loads stay small motion.
    let d = derive_springs(&config, None, &mut |_| {}).unwrap();
    assert_eq!(d.method, Method::Excitation);
    assert!(!d.groups.is_empty());
    let modes = &d.excited_modes;
    assert!(!modes.is_empty() && modes.len() <= 8, "{modes:?}");
    let total: f64 = modes.iter().map(|m| m.share).sum();
    assert!((total - 1.0).abs() < 1e-12, "{total}");
    // A corner load moves the lowest bending mode most.
    let top = modes
        .iter()
        .max_by(|a, b| a.share.total_cmp(&b.share))
        .unwrap();
    assert_eq!(top.mode, 1, "{modes:?}");
    assert!(modes.windows(2).all(|w| w[0].mode < w[1].mode));
    assert!(d.frequencies[0].relative_error.unwrap().abs() < 1e-9);
    config.loads = Loads::default();
    let e = derive_springs(&config, None, &mut |_| {}).unwrap_err();
    assert!(
        matches!(e, nurbspring_derive::DeriveError::NoExcitation),
        "{e}"
    );
}

/// The reduction of a shell onto the Greville lattice is exact: its modes are the shell's (at
/// the nodes), its small motion is the linearized shell's to round-off, and its static
/// deflection under the scene's load is the linear shell's at the nodes. On a coarser uniform
/// lattice it is Guyan's, whose lowest frequency lies above the shell's; a shell its
/// constraints leave free to move (a mechanism) reduces exactly, but not by Guyan's method.
#[test]
fn the_reduction_of_a_shell_is_exact_on_the_greville_lattice() {
    let mut config = clamped_plate_config(refined(&rectangle(0.4, 0.3), 3, (3, 3)).unwrap());
    config.method = Method::Reduction;
    let r = reduce_shell(&config, None).unwrap();
    assert_eq!(r.kind, "exact");
    assert_eq!(3 * r.free_nodes, r.shell_dofs);
    for f in &r.frequencies {
        assert!(f.relative_error.unwrap().abs() < 1e-9, "{f:?}");
        assert!(f.mac.unwrap() > 1.0 - 1e-9, "{f:?}");
    }
    assert!(r.small_motion.relative_rms < 1e-8, "{:?}", r.small_motion);
    let red = &r.reduction;
    let n = 3 * red.free.len();
    assert_eq!((red.stiffness.nrows(), red.stiffness.ncols()), (n, n));
    let asym = (0..n)
        .flat_map(|i| (0..n).map(move |j| (i, j)))
        .map(|(i, j)| (red.stiffness[(i, j)] - red.stiffness[(j, i)]).abs())
        .fold(0.0, f64::max);
    let top = (0..n)
        .map(|i| red.stiffness[(i, i)].abs())
        .fold(0.0, f64::max);
    assert!(asym <= 1e-9 * top, "{asym:e} of {top:e}");
    // K_T u = F_T against the shell's own linear static deflection at the nodes.
    let model = nurbspring_dnurbs::DnurbsModel::kirchhoff_love(
        Geometry::Surface(config.surface.clone()),
        config.shell,
        config.loads.clone(),
        &config.constraints,
        config.dnurbs.clone(),
    )
    .unwrap();
    let p = model.linearized_steady_state().unwrap();
    let omega = Geometry::Surface(config.surface.clone())
        .stacked_jacobian(&red.params, false)
        .unwrap();
    let (mut x, mut x0) = (vec![0.0; omega.nrows()], vec![0.0; omega.nrows()]);
    omega.mul_vec(&p, &mut x);
    omega.mul_vec(model.p0(), &mut x0);
    let f: Vec<f64> = red.loads.iter().flatten().copied().collect();
    let u = nurbspring_linalg::cholesky_solve_dense(&red.stiffness, &f).unwrap();
    let largest = x
        .iter()
        .zip(&x0)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    for (i, &a) in red.free.iter().enumerate() {
        for k in 0..3 {
            let shell = x[3 * a + k] - x0[3 * a + k];
            assert!(
                (u[3 * i + k] - shell).abs() <= 1e-8 * largest,
                "node {a}: {} against {shell}",
                u[3 * i + k]
            );
        }
    }
    // Guyan onto a coarser lattice: the lowest frequency from above.
    config.lattice.grid = ParameterGrid::Uniform {
        nodes_u: 4,
        nodes_v: 4,
    };
    let g = reduce_shell(&config, None).unwrap();
    assert_eq!(g.kind, "guyan");
    let first = g.frequencies[0].relative_error.unwrap();
    assert!(first > -1e-9 && first < 0.05, "{first}");
    // Held at two corners (a mechanism) the exact reduction is a change of coordinates still;
    // Guyan's needs a positive-definite stiffness and is refused.
    config.constraints = Constraints {
        fixed_points: vec![0, 5],
        ..Constraints::default()
    };
    let e = reduce_shell(&config, None).unwrap_err().to_string();
    assert!(e.contains("positive-definite"), "{e}");
    config.lattice.grid = ParameterGrid::Greville;
    let m = reduce_shell(&config, None).unwrap();
    assert_eq!(m.kind, "exact");
    for f in &m.frequencies {
        assert!(f.relative_error.unwrap().abs() < 1e-8, "{f:?}");
    }
}

/// The paper's derivation is refused for a shell, and the spring derivation refuses to stand
/// in for the reduction.
#[test]
fn a_shell_refuses_a_derivation_of_the_tension_plate() {
    let mut config = clamped_plate_config(refined(&rectangle(0.4, 0.3), 3, (1, 1)).unwrap());
    for method in [Method::Paper, Method::Reduction] {
        config.method = method;
        let e = derive_springs(&config, None, &mut |_| {})
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("\"modal\", \"excitation\" or \"springs\""),
            "{e}"
        );
    }
}

/// The lattice's load path on a von Mises truss: two springs k from the fixed nodes (∓1, 0, 0)
/// to an apex at height h = 0.2, two springs k_z = 1 from the apex to fixed nodes at
/// (0, h, ±1) (its only stiffness out of the plane, symmetric), a downward force F on the
/// apex. Its equilibria satisfy `F = R(y) = 2k (L₀ − L) y / L + 2k_z (L_z − 1)(h − y) / L_z` with
/// `L = √(1 + y²)`, `L_z = √(1 + (h − y)²)`, whose largest value on `0 < y < h` is the limit
/// load. Below it every level is reached and is that equilibrium; past it the path keeps the
/// levels it reached and says where it stopped.
#[test]
fn a_lattice_load_path_stops_at_its_limit_point_and_keeps_the_levels_below() {
    let (k, kz, h) = (100.0, 1.0, 0.2);
    let l0 = (1.0_f64 + h * h).sqrt();
    let resistance = |y: f64| {
        let l = (1.0 + y * y).sqrt();
        let lz = (1.0 + (h - y) * (h - y)).sqrt();
        2.0 * k * (l0 - l) * y / l + 2.0 * kz * (lz - 1.0) * (h - y) / lz
    };
    // The limit load: the largest R over y in (0, h), by a fine sampling (R is smooth with one
    // maximum there).
    let limit = (1..10_000)
        .map(|i| resistance(h * i as f64 / 10_000.0))
        .fold(0.0_f64, f64::max);
    let truss = |f: f64| {
        nurbspring_msm::MsmModel::new(
            SpringLattice::from_file(
                &nurbspring_msm::MsmFile::from_json_str(&format!(
                    r#"{{"nodes": [{{"position": [-1, 0, 0], "mass": 1, "fixed": true}},
                                  {{"position": [1, 0, 0], "mass": 1, "fixed": true}},
                                  {{"position": [0, {h}, 1], "mass": 1, "fixed": true}},
                                  {{"position": [0, {h}, -1], "mass": 1, "fixed": true}},
                                  {{"position": [0, {h}, 0], "mass": 1, "force": [0, {}, 0]}}],
                       "springs": [{{"a": 0, "b": 4, "k": {k}}}, {{"a": 1, "b": 4, "k": {k}}},
                                   {{"a": 2, "b": 4, "k": {kz}}}, {{"a": 3, "b": 4, "k": {kz}}}]}}"#,
                    -f
                ))
                .unwrap(),
            )
            .unwrap(),
        )
        .unwrap()
    };
    // Full load at 1.5 × the limit: the levels at 0.3 and 0.6 of it are below the limit.
    let model = truss(1.5 * limit);
    let path = nurbspring_derive::static_path(&model, &[0.3, 0.6, 1.0], &|| false).unwrap();
    assert_eq!(path.states.len(), 2, "{path:?}");
    assert!(
        path.stopped.as_ref().unwrap().contains("buckles"),
        "{path:?}"
    );
    for (q, lambda) in path.states.iter().zip([0.3, 0.6]) {
        let x = model.full_positions(q);
        let y = x[13];
        assert!(x[12].abs() < 1e-9 && x[14].abs() < 1e-9, "{x:?}");
        let f = lambda * 1.5 * limit;
        assert!(
            (resistance(y) - f).abs() <= 1e-6 * limit,
            "{y}: {} against {f}",
            resistance(y)
        );
        // The branch before the limit: the apex still above the plane of the supports.
        assert!(y > 0.0 && y < h);
    }
    // Below the limit every level is reached.
    let below =
        nurbspring_derive::static_path(&truss(0.9 * limit), &[0.5, 1.0], &|| false).unwrap();
    assert_eq!((below.states.len(), below.stopped), (2, None));
}
