//! Lattices from surfaces and lists: the paper's lattice (docs/math.md §7), grids, the docs/math.md §5 fixed
//! rule, validation and the JSON form.

mod support;

use nurbspring_msm::{
    Class, Constants, FixedNodes, LatticeOptions, LinearElement, LinearKind, MAX_NODES, MsmError,
    MsmFile, MsmModel, ParameterGrid, Region, Spring, SpringKind, SpringLattice,
};
use nurbspring_sim::DynamicModel;
use support::tolerances::*;
use support::{curved_lattice, curved_surface, paper_fixed_points, paper_surface};

fn paper_lattice(greville: bool) -> SpringLattice {
    let options = LatticeOptions {
        constants: Constants::from_pairs([
            (Class::Spring(SpringKind::Structural), 2.7225),
            (Class::Spring(SpringKind::Shear), 0.8661),
        ]),
        mass: 0.005,
        ..Default::default()
    };
    SpringLattice::from_surface(&paper_surface(greville), &options, &paper_fixed_points()).unwrap()
}

#[test]
fn paper_lattice_builds_with_45_by_45_stiffness() {
    let lattice = paper_lattice(false);
    assert_eq!(lattice.n_nodes(), 15);
    assert_eq!(lattice.grid, Some((5, 3)));
    assert_eq!(lattice.count(Class::Spring(SpringKind::Structural)), 22);
    assert_eq!(lattice.count(Class::Spring(SpringKind::Shear)), 16);
    assert_eq!(
        lattice.classes(),
        vec![
            Class::Spring(SpringKind::Structural),
            Class::Spring(SpringKind::Shear)
        ]
    );
    let params = lattice.params.as_ref().unwrap();
    assert_eq!(params[7], (0.5, 0.5));
    assert_eq!(params[14], (1.0, 1.0));
    // docs/math.md §5 fixed rule: the nodes at (0.25, 0.5), (0.5, 0.5), (0.75, 0.5) see one of the three
    // free control points (2..4, 2) and move; the 12 boundary nodes are fixed.
    let free: Vec<usize> = (0..15).filter(|&a| !lattice.fixed[a]).collect();
    assert_eq!(free, vec![4, 7, 10]);
    let x0 = lattice.flat_positions();
    let k_s = lattice.tangent_stiffness(&x0);
    assert_eq!((k_s.nrows(), k_s.ncols()), (45, 45));
    let model = MsmModel::new(lattice).unwrap();
    assert_eq!(model.n_dofs(), 9);
}

#[test]
fn flat_lattice_at_rest_has_no_out_of_plane_stiffness() {
    for greville in [false, true] {
        let lattice = paper_lattice(greville);
        let x0 = lattice.flat_positions();
        assert!(
            x0.iter().skip(2).step_by(3).all(|&z| z == 2.0),
            "the sheet is flat at z = 2"
        );
        let k = lattice.tangent_stiffness(&x0);
        let mut g = vec![k];
        g.extend(
            lattice
                .classes()
                .into_iter()
                .map(|c| lattice.unit_stiffness(c, &x0)),
        );
        for m in &g {
            // z rows (and, by symmetry, z columns) are exactly zero.
            for (row, col, v) in m.triplets() {
                if row % 3 == 2 || col % 3 == 2 {
                    assert_eq!(v, 0.0, "entry ({row}, {col}) of a flat lattice at rest");
                }
            }
            assert!(m.frobenius_norm() > 0.0);
        }
        // With pre-strain the geometric term gives out-of-plane stiffness.
        let options = LatticeOptions {
            pre_strain: 0.1,
            ..Default::default()
        };
        let tense =
            SpringLattice::from_surface(&paper_surface(greville), &options, &paper_fixed_points())
                .unwrap();
        let k = tense.tangent_stiffness(&x0);
        assert!(k.get(3 * 7 + 2, 3 * 7 + 2) > 0.0);
    }
}

#[test]
fn greville_net_samples_the_affine_sheet() {
    // On the Greville net the paper's surface is c(u, v) = (3u, 5v, 2) (docs/math.md §7).
    let lattice = paper_lattice(true);
    for (x, &(u, v)) in lattice
        .positions
        .iter()
        .zip(lattice.params.as_ref().unwrap())
    {
        let expected = [3.0 * u, 5.0 * v, 2.0];
        for c in 0..3 {
            assert!(
                (x[c] - expected[c]).abs() < AFFINE_SURFACE * 5.0,
                "{x:?} vs {expected:?}"
            );
        }
    }
}

#[test]
fn grids_and_spring_counts() {
    let s = curved_surface();
    let count = |grid: ParameterGrid, structural: bool, shear: bool, bending: bool| {
        let springs = Constants::from_pairs(
            [
                (SpringKind::Structural, structural),
                (SpringKind::Shear, shear),
                (SpringKind::Bend, bending),
            ]
            .into_iter()
            .filter(|(_, on)| *on)
            .map(|(kind, _)| (Class::Spring(kind), 1.0)),
        );
        let o = LatticeOptions {
            grid,
            constants: springs,
            ..Default::default()
        };
        let l = SpringLattice::from_surface(&s, &o, &[]).unwrap();
        (l.grid.unwrap(), l.springs.len())
    };
    let uniform = ParameterGrid::Uniform {
        nodes_u: 6,
        nodes_v: 4,
    };
    // Structural: 6·3 + 5·4 = 38; shear: 2·5·3 = 30; bending: 6·2 + 4·4 = 28.
    assert_eq!(count(uniform.clone(), true, false, false), ((6, 4), 38));
    assert_eq!(count(uniform.clone(), false, true, false), ((6, 4), 30));
    assert_eq!(count(uniform.clone(), false, false, true), ((6, 4), 28));
    assert_eq!(count(uniform, true, true, true), ((6, 4), 96));
    // Knots of a single-span biquadratic: 2 × 2 nodes; Greville: 3 × 3.
    assert_eq!(count(ParameterGrid::Knots, true, true, false), ((2, 2), 6));
    assert_eq!(
        count(ParameterGrid::Greville, true, true, false),
        ((3, 3), 20)
    );
}

#[test]
fn pre_strain_scales_rest_lengths() {
    let plain = curved_lattice(4, 4, 0.0);
    let tense = curved_lattice(4, 4, 0.2);
    let x0 = plain.flat_positions();
    for (s, t) in plain.springs.iter().zip(&tense.springs) {
        assert!((s.rest_length - s.length(&x0)).abs() < 1e-15 * s.rest_length);
        assert!((t.rest_length - 0.8 * s.rest_length).abs() < 1e-15 * s.rest_length);
    }
}

#[test]
fn fixed_nodes_by_list_and_node_nearest() {
    let o = LatticeOptions {
        grid: ParameterGrid::Uniform {
            nodes_u: 5,
            nodes_v: 3,
        },
        fixed: FixedNodes::List(vec![0, 14]),
        ..Default::default()
    };
    let l = SpringLattice::from_surface(&curved_surface(), &o, &[1, 2, 3]).unwrap();
    assert_eq!(l.fixed_nodes(), vec![0, 14]);
    assert_eq!(l.fixed_dofs(), vec![0, 1, 2, 42, 43, 44]);
    assert_eq!(l.node_nearest(0.5, 0.5), 7);
    assert_eq!(l.node_nearest(1.0, 0.0), 12);
    // (0.125, 0) is as far from node 0 at (0, 0) as from node 3 at (0.25, 0), both distances
    // exactly 1/64: ties go to the lower index.
    assert_eq!(l.node_nearest(0.125, 0.0), 0);
    // Without parameters: by grid, then by position.
    let mut by_grid = l.clone();
    by_grid.params = None;
    assert_eq!(by_grid.node_nearest(0.5, 0.5), 7);
    by_grid.grid = None;
    assert_eq!(by_grid.node_nearest(0.0, 1.0), 2);
    let bad = LatticeOptions {
        fixed: FixedNodes::List(vec![15]),
        ..o
    };
    assert!(matches!(
        SpringLattice::from_surface(&curved_surface(), &bad, &[]),
        Err(MsmError::FixedNodeOutside {
            position: 0,
            node: 15,
            n_nodes: 15
        })
    ));
}

#[test]
fn auto_rule_with_all_control_points_fixed_fixes_everything() {
    let o = LatticeOptions {
        grid: ParameterGrid::Uniform {
            nodes_u: 4,
            nodes_v: 4,
        },
        ..Default::default()
    };
    let all: Vec<usize> = (0..9).collect();
    let l = SpringLattice::from_surface(&curved_surface(), &o, &all).unwrap();
    assert!(l.fixed.iter().all(|&f| f));
    // Fixing the first row of control points (i = 0) fixes exactly the nodes at u = 0.
    let l = SpringLattice::from_surface(&curved_surface(), &o, &[0, 1, 2]).unwrap();
    assert_eq!(l.fixed_nodes(), vec![0, 1, 2, 3]);
}

/// On the Greville grid of the control net's size, node a is fixed when control point a is,
/// even an interior one; a uniform grid with the same nodes (3 × 3 at 0, ½, 1 on the
/// biquadratic patch) follows the basis-support rule, under which the middle node sees all
/// nine control points and stays free.
#[test]
fn greville_nodes_follow_their_control_points_and_other_grids_the_support_rule() {
    let fixed_points = [0, 4];
    let greville = LatticeOptions {
        grid: ParameterGrid::Greville,
        ..Default::default()
    };
    let l = SpringLattice::from_surface(&curved_surface(), &greville, &fixed_points).unwrap();
    assert_eq!(l.params.as_ref().unwrap()[4], (0.5, 0.5));
    assert_eq!(l.fixed_nodes(), vec![0, 4]);
    let uniform = LatticeOptions {
        grid: ParameterGrid::Uniform {
            nodes_u: 3,
            nodes_v: 3,
        },
        ..Default::default()
    };
    let l = SpringLattice::from_surface(&curved_surface(), &uniform, &fixed_points).unwrap();
    assert_eq!(l.params.as_ref().unwrap()[4], (0.5, 0.5));
    // Node 0 sits at (0, 0), where only control point 0 has a non-zero basis value.
    assert_eq!(l.fixed_nodes(), vec![0]);
}

fn two_nodes(spring: Spring) -> Result<SpringLattice, MsmError> {
    SpringLattice::from_parts(
        vec![[0.0; 3], [1.0, 0.0, 0.0]],
        vec![1.0; 2],
        vec![0.0; 2],
        vec![false; 2],
        vec![spring],
        [0.0; 3],
    )
}

#[test]
fn validation_errors() {
    let ok = Spring {
        a: 0,
        b: 1,
        kind: SpringKind::Structural,
        k: 1.0,
        rest_length: 1.0,
        weight: 1.0,
        damping: 0.0,
    };
    assert!(two_nodes(ok).is_ok());
    assert!(matches!(
        two_nodes(Spring { b: 0, ..ok }),
        Err(MsmError::ZeroLengthSpring {
            spring: 0,
            a: 0,
            b: 0
        })
    ));
    assert!(matches!(
        two_nodes(Spring { b: 5, ..ok }),
        Err(MsmError::MissingNode {
            of: "spring",
            index: 0,
            node: 5,
            n_nodes: 2
        })
    ));
    assert!(matches!(
        two_nodes(Spring { k: -1.0, ..ok }),
        Err(MsmError::NegativeStiffness { spring: 0, .. })
    ));
    assert!(matches!(
        two_nodes(Spring { k: f64::NAN, ..ok }),
        Err(MsmError::NonFinite { .. })
    ));
    assert!(matches!(
        two_nodes(Spring {
            rest_length: -0.5,
            ..ok
        }),
        Err(MsmError::InvalidParameter { .. })
    ));
    let parts = |positions: Vec<[f64; 3]>, masses: Vec<f64>, damping: Vec<f64>| {
        SpringLattice::from_parts(
            positions,
            masses,
            damping,
            vec![false; 2],
            vec![ok],
            [0.0; 3],
        )
    };
    assert!(matches!(
        parts(
            vec![[0.0; 3], [1.0, 0.0, 0.0]],
            vec![1.0, 0.0],
            vec![0.0; 2]
        ),
        Err(MsmError::NonPositiveMass { node: 1, .. })
    ));
    assert!(matches!(
        parts(
            vec![[0.0; 3], [1.0, 0.0, 0.0]],
            vec![1.0, -2.0],
            vec![0.0; 2]
        ),
        Err(MsmError::NonPositiveMass { node: 1, .. })
    ));
    assert!(matches!(
        parts(
            vec![[0.0; 3], [f64::INFINITY, 0.0, 0.0]],
            vec![1.0; 2],
            vec![0.0; 2]
        ),
        Err(MsmError::NonFinite { index: 1, .. })
    ));
    assert!(matches!(
        parts(vec![[0.0; 3], [1.0, 0.0, 0.0]], vec![1.0; 3], vec![0.0; 2]),
        Err(MsmError::LengthMismatch { .. })
    ));
    assert!(matches!(
        parts(
            vec![[0.0; 3], [1.0, 0.0, 0.0]],
            vec![1.0; 2],
            vec![0.0, -1.0]
        ),
        Err(MsmError::InvalidParameter { .. })
    ));
    // Coincident nodes.
    assert!(matches!(
        parts(vec![[0.0; 3], [0.0; 3]], vec![1.0; 2], vec![0.0; 2]),
        Err(MsmError::ZeroLengthSpring { .. })
    ));
    // Too many nodes: refused before allocating anything.
    let huge = LatticeOptions {
        grid: ParameterGrid::Uniform {
            nodes_u: 100_000,
            nodes_v: 100_001,
        },
        ..Default::default()
    };
    match SpringLattice::from_surface(&curved_surface(), &huge, &[]) {
        Err(MsmError::TooLarge { nodes }) => assert!(nodes > MAX_NODES),
        other => panic!("expected TooLarge, got {other:?}"),
    }
    let overflow = LatticeOptions {
        grid: ParameterGrid::Uniform {
            nodes_u: usize::MAX,
            nodes_v: 3,
        },
        ..Default::default()
    };
    assert!(matches!(
        SpringLattice::from_surface(&curved_surface(), &overflow, &[]),
        Err(MsmError::TooLarge { .. })
    ));
    // Options.
    let s = curved_surface();
    for bad in [
        LatticeOptions {
            pre_strain: 1.0,
            ..Default::default()
        },
        LatticeOptions {
            constants: Constants::from_pairs([(Class::Spring(SpringKind::Shear), -1.0)]),
            ..Default::default()
        },
        LatticeOptions {
            pre_strain: -1.0,
            ..Default::default()
        },
        LatticeOptions {
            damping: f64::NAN,
            ..Default::default()
        },
        LatticeOptions {
            grid: ParameterGrid::Uniform {
                nodes_u: 1,
                nodes_v: 4,
            },
            ..Default::default()
        },
    ] {
        assert!(
            matches!(
                SpringLattice::from_surface(&s, &bad, &[]),
                Err(MsmError::InvalidOption { .. })
            ),
            "{bad:?}"
        );
    }
    let zero_mass = LatticeOptions {
        mass: 0.0,
        ..Default::default()
    };
    assert_eq!(
        zero_mass.validate().unwrap_err().to_string(),
        "mass = 0: the node mass must be positive"
    );
    let no_springs = LatticeOptions {
        constants: Constants::new(),
        ..Default::default()
    };
    assert!(matches!(
        SpringLattice::from_surface(&s, &no_springs, &[]),
        Err(MsmError::NoSprings)
    ));
    // A model re-validates what set_constants / set_mass left unchecked.
    let mut l = curved_lattice(3, 3, 0.0);
    l.set_constants(&Constants::from_pairs([(
        Class::Spring(SpringKind::Shear),
        -0.5,
    )]));
    assert!(matches!(
        MsmModel::new(l.clone()),
        Err(MsmError::NegativeStiffness { .. })
    ));
    l.set_constants(&Constants::from_pairs([(
        Class::Spring(SpringKind::Shear),
        0.5,
    )]));
    l.set_mass(0.0);
    assert!(matches!(
        MsmModel::new(l.clone()),
        Err(MsmError::NonPositiveMass { node: 0, .. })
    ));
    assert!(l.set_masses(vec![1.0; 4]).is_err());
    assert!(l.set_masses(vec![2.0; 9]).is_ok());
    // Messages carry the values.
    let e = two_nodes(Spring { k: -3.5, ..ok }).unwrap_err().to_string();
    assert!(e.contains("-3.5"), "{e}");
}

/// The element rules of `validate` (docs: weight in (0, 1e30], k in [0, 1e30], finite
/// coefficients, 2 to 4 distinct existing nodes), one broken at a time on a valid element.
#[test]
fn element_validation_errors() {
    let base = curved_lattice(3, 3, 0.0);
    let ok = LinearElement {
        kind: LinearKind::BendU,
        region: Region::Interior,
        nodes: vec![0, 3, 6],
        coefficients: vec![1.0, -2.0, 1.0],
        weight: 0.5,
        k: 1.0,
    };
    let check = |element: LinearElement| {
        let mut l = base.clone();
        l.elements.push(element);
        l.validate()
    };
    assert!(check(ok.clone()).is_ok());
    for weight in [0.0, -0.5, f64::INFINITY, f64::NAN, 2e30] {
        assert!(
            matches!(
                check(LinearElement {
                    weight,
                    ..ok.clone()
                }),
                Err(MsmError::InvalidElement { element: 0, .. })
            ),
            "weight {weight}"
        );
    }
    for k in [-1.0, f64::INFINITY, f64::NAN] {
        assert!(
            matches!(
                check(LinearElement { k, ..ok.clone() }),
                Err(MsmError::InvalidElement { element: 0, .. })
            ),
            "k {k}"
        );
    }
    // k = 0 is allowed (a class switched off), the weight must stay positive.
    assert!(
        check(LinearElement {
            k: 0.0,
            ..ok.clone()
        })
        .is_ok()
    );
    let broken = [
        LinearElement {
            coefficients: vec![1.0, f64::NAN, 1.0],
            ..ok.clone()
        },
        LinearElement {
            nodes: vec![0, 3, 3],
            ..ok.clone()
        },
        LinearElement {
            nodes: vec![0],
            coefficients: vec![1.0],
            ..ok.clone()
        },
        LinearElement {
            coefficients: vec![1.0, -1.0],
            ..ok.clone()
        },
    ];
    for element in broken {
        assert!(
            matches!(
                check(element.clone()),
                Err(MsmError::InvalidElement { element: 0, .. })
            ),
            "{element:?}"
        );
    }
    assert!(matches!(
        check(LinearElement {
            nodes: vec![0, 3, 9],
            ..ok
        }),
        Err(MsmError::MissingNode {
            of: "linear element",
            node: 9,
            n_nodes: 9,
            ..
        })
    ));
}

/// Without parameters or a grid, `node_nearest(u, v)` takes the point at fractions (u, v) of
/// the nodes' bounding box and the node nearest to it in the x-y plane. Box [1, 5] × [−1, 1]
/// (nodes on a 3 × 3 grid, listed out of order): (0.2, 0.2) is the point (1.8, −0.6), nearest
/// to (1, −1) (squared distance 0.8, against 1.6 to (3, −1) and 1.0 to (1, 0));
/// (0.9, 0.1) is (4.6, −0.8), nearest to (5, −1); (0.1, 0.9) is (1.4, 0.8), nearest to (1, 1).
#[test]
fn node_nearest_without_parameters_uses_the_bounding_box() {
    let xs = [1.0, 3.0, 5.0];
    let ys = [-1.0, 0.0, 1.0];
    // Node a sits at (xs[a % 3], ys[2 - a / 3]): the top row first.
    let positions: Vec<[f64; 3]> = (0..9).map(|a| [xs[a % 3], ys[2 - a / 3], 0.0]).collect();
    let springs = (0..8)
        .map(|a| Spring {
            a,
            b: a + 1,
            kind: SpringKind::Structural,
            k: 1.0,
            rest_length: 1.0,
            weight: 1.0,
            damping: 0.0,
        })
        .collect();
    let l = SpringLattice::from_parts(
        positions.clone(),
        vec![1.0; 9],
        vec![0.0; 9],
        vec![false; 9],
        springs,
        [0.0; 3],
    )
    .unwrap();
    assert!(l.params.is_none() && l.grid.is_none());
    let at = |x: f64, y: f64| {
        positions
            .iter()
            .position(|p| p[0] == x && p[1] == y)
            .unwrap()
    };
    assert_eq!(l.node_nearest(0.2, 0.2), at(1.0, -1.0));
    assert_eq!(l.node_nearest(0.9, 0.1), at(5.0, -1.0));
    assert_eq!(l.node_nearest(0.1, 0.9), at(1.0, 1.0));
    assert_eq!(l.node_nearest(0.5, 0.5), at(3.0, 0.0));
}

/// A uniform grid of the smallest allowed size, 2 nodes along each direction: the ends of the
/// curved patch's knot vectors [0, 0, 0, 1, 1, 1], so 2 × 2 nodes and 2 + 2 structural springs.
#[test]
fn uniform_grid_of_two_by_two_nodes_is_allowed() {
    let o = LatticeOptions {
        grid: ParameterGrid::Uniform {
            nodes_u: 2,
            nodes_v: 2,
        },
        constants: Constants::from_pairs([(Class::Spring(SpringKind::Structural), 1.0)]),
        ..Default::default()
    };
    let s = curved_surface();
    let (us, vs) = o.grid.parameters(&s).unwrap();
    assert_eq!((us, vs), (vec![0.0, 1.0], vec![0.0, 1.0]));
    let l = SpringLattice::from_surface(&s, &o, &[]).unwrap();
    assert_eq!((l.grid, l.springs.len()), (Some((2, 2)), 4));
}

#[test]
fn json_round_trip() {
    let mut lattice = curved_lattice(4, 3, 0.1);
    lattice.fixed[0] = true;
    lattice.damping[5] = 0.25;
    lattice.masses[2] = 1.0 / 3.0;
    lattice.gravity = [0.0, -1.0 / 7.0, -9.81];
    let text = lattice.to_json_string();
    assert!(text.contains("\"kind\": \"bend\"") && text.contains("\"uv\""));
    let back = SpringLattice::from_json_str(&text).unwrap();
    assert_eq!(back.grid, lattice.grid);
    assert_eq!(back.fixed, lattice.fixed);
    assert_eq!(back.springs.len(), lattice.springs.len());
    let close = |a: f64, b: f64| (a - b).abs() <= JSON_ROUND_TRIP * a.abs().max(b.abs());
    for (a, b) in back
        .positions
        .iter()
        .flatten()
        .zip(lattice.positions.iter().flatten())
    {
        assert!(close(*a, *b));
    }
    for (a, b) in back.springs.iter().zip(&lattice.springs) {
        assert_eq!((a.a, a.b, a.kind), (b.a, b.b, b.kind));
        assert!(close(a.k, b.k) && close(a.rest_length, b.rest_length));
    }
    for (a, b) in back
        .masses
        .iter()
        .zip(&lattice.masses)
        .chain(back.damping.iter().zip(&lattice.damping))
    {
        assert!(close(*a, *b));
    }
    for (a, b) in back
        .params
        .as_ref()
        .unwrap()
        .iter()
        .zip(lattice.params.as_ref().unwrap())
    {
        assert!(close(a.0, b.0) && close(a.1, b.1));
    }
    assert!(
        back.gravity
            .iter()
            .zip(&lattice.gravity)
            .all(|(a, b)| close(*a, *b))
    );
    // The file form itself round-trips through serde.
    let file: MsmFile = serde_json::from_str(&text).unwrap();
    assert_eq!(
        MsmFile::from_json_str(&file.to_json_string())
            .unwrap()
            .nodes
            .len(),
        12
    );
}

/// `initial_velocities`: absent means rest; a list of the right length is kept as written; a
/// wrong length or a non-finite entry is refused, naming the node.
#[test]
fn file_initial_velocities() {
    let two = r#"{"nodes": [{"position": [0,0,0], "mass": 1}, {"position": [1,0,0], "mass": 1}],
                  "springs": [{"a": 0, "b": 1, "k": 1}]"#;
    let file = |tail: &str| MsmFile::from_json_str(&format!("{two}{tail}}}")).unwrap();
    assert_eq!(file("").velocities().unwrap(), vec![[0.0; 3]; 2]);
    let given = file(r#", "initial_velocities": [[0.5, -1, 0], [0, 0, 2.25]]"#);
    assert_eq!(
        given.velocities().unwrap(),
        vec![[0.5, -1.0, 0.0], [0.0, 0.0, 2.25]]
    );
    assert!(matches!(
        file(r#", "initial_velocities": [[0, 0, 0]]"#).velocities(),
        Err(MsmError::LengthMismatch {
            expected: 2,
            found: 1,
            ..
        })
    ));
    let mut infinite = given.clone();
    infinite.initial_velocities.as_mut().unwrap()[1][1] = f64::INFINITY;
    assert!(matches!(
        infinite.velocities(),
        Err(MsmError::NonFinite { index: 1, .. })
    ));
}

/// An element whose class names another kind than its `kind` is refused.
#[test]
fn file_element_class_must_match_its_kind() {
    let lattice = curved_lattice(3, 3, 0.0);
    let mut file = lattice.to_file();
    file.elements.push(nurbspring_msm::ElementRecord {
        kind: nurbspring_msm::LinearKind::BendU,
        class: "bend_u@interior".into(),
        nodes: vec![0, 3, 6],
        k: 1.0,
        weight: 0.5,
        coefficients: vec![1.0, -2.0, 1.0],
    });
    let back = SpringLattice::from_file(&file).unwrap();
    assert_eq!(back.elements.len(), 1);
    file.elements[0].class = "bend_v@interior".into();
    assert!(matches!(
        SpringLattice::from_file(&file),
        Err(MsmError::InvalidElement { element: 0, .. })
    ));
}

#[test]
fn json_errors() {
    let missing =
        r#"{"nodes": [{"position": [0,0,0], "mass": 1}], "springs": [{"a": 0, "b": 3, "k": 1}]}"#;
    assert!(matches!(
        SpringLattice::from_json_str(missing),
        Err(MsmError::MissingNode { node: 3, .. })
    ));
    let unknown = r#"{"nodes": [], "springs": [], "colour": 3}"#;
    assert!(matches!(
        SpringLattice::from_json_str(unknown),
        Err(MsmError::Json { .. })
    ));
    let bad_kind = r#"{"nodes": [{"position": [0,0,0], "mass": 1}, {"position": [1,0,0], "mass": 1}],
                       "springs": [{"a": 0, "b": 1, "k": 1, "kind": "torsion"}]}"#;
    assert!(matches!(
        SpringLattice::from_json_str(bad_kind),
        Err(MsmError::Json { .. })
    ));
    let mixed_uv = r#"{"nodes": [{"position": [0,0,0], "mass": 1, "uv": [0, 0]}, {"position": [1,0,0], "mass": 1}],
                       "springs": []}"#;
    assert!(matches!(
        SpringLattice::from_json_str(mixed_uv),
        Err(MsmError::LengthMismatch { .. })
    ));
}

// ------------------------------------------------------------------ values of small public functions

/// `gravity_forces` is `m_a g + F_a` per node (paper eq. (6)), interleaved; a node without an
/// entry in `forces` gets gravity only.
#[test]
fn gravity_forces_are_mass_times_gravity_plus_node_forces() {
    use nurbspring_msm::{Spring, SpringKind, SpringLattice};
    let spring = |a, b| Spring {
        a,
        b,
        kind: SpringKind::Structural,
        k: 1.0,
        rest_length: 1.0,
        weight: 1.0,
        damping: 0.0,
    };
    let mut lat = SpringLattice::from_parts(
        vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 2.0, 0.0]],
        vec![2.0, 3.0, 0.5],
        vec![0.0; 3],
        vec![false; 3],
        vec![spring(0, 1), spring(1, 2)],
        [0.1, -0.2, -9.81],
    )
    .unwrap();
    lat.forces = vec![[1.0, 0.0, 0.0], [0.0, 0.0, 4.0]];
    let f = lat.gravity_forces();
    let want = [
        2.0 * 0.1 + 1.0,
        2.0 * -0.2,
        2.0 * -9.81,
        3.0 * 0.1,
        3.0 * -0.2,
        3.0 * -9.81 + 4.0,
        0.5 * 0.1,
        0.5 * -0.2,
        0.5 * -9.81,
    ];
    assert_eq!(f.len(), 9);
    for (got, want) in f.iter().zip(want) {
        assert!(
            (got - want).abs() <= 4.0 * f64::EPSILON * want.abs(),
            "{f:?}"
        );
    }
}

/// `spring_lengths` are the Euclidean distances `|x_a − x_b|` at the positions given (a 3-4-5
/// triangle and a 1-2-2 box diagonal, exact in floating point).
#[test]
fn spring_lengths_are_the_distances_at_the_positions_given() {
    use nurbspring_msm::{Spring, SpringKind, SpringLattice};
    let spring = |a, b| Spring {
        a,
        b,
        kind: SpringKind::Shear,
        k: 1.0,
        rest_length: 0.5,
        weight: 1.0,
        damping: 0.0,
    };
    let lat = SpringLattice::from_parts(
        vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        vec![1.0; 3],
        vec![0.0; 3],
        vec![false; 3],
        vec![spring(0, 1), spring(1, 2), spring(0, 2)],
        [0.0; 3],
    )
    .unwrap();
    let x = [0.0, 0.0, 0.0, 3.0, 4.0, 0.0, 1.0, 2.0, -2.0];
    let l = lat.spring_lengths(&x);
    let want = [5.0, 12f64.sqrt(), 3.0];
    assert_eq!(l.len(), 3);
    for (got, want) in l.iter().zip(want) {
        assert!((got - want).abs() <= 2.0 * f64::EPSILON * want, "{l:?}");
    }
}
