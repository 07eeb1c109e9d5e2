//! Every bad input gives the right error, naming the offending value.

use nurbspring_dnurbs::{
    Constraints, DnurbsError, DnurbsModel, DnurbsOptions, Geometry, LinearConstraint, Loads,
    Material, PointLoad, RationalStepper, assemble,
};
use nurbspring_sim::{IntegratorKind, SimError, make_stepper};

use crate::support;

fn build(
    material: Material,
    loads: Loads,
    constraints: Constraints,
    options: DnurbsOptions,
) -> Result<DnurbsModel, DnurbsError> {
    DnurbsModel::new(
        Geometry::Surface(support::paper_surface()),
        material,
        loads,
        &constraints,
        options,
    )
}

#[test]
fn negative_or_non_finite_material_is_named() {
    let e = build(
        Material {
            mu: -1.0,
            ..support::paper_material()
        },
        Loads::default(),
        support::paper_constraints(),
        DnurbsOptions::default(),
    )
    .unwrap_err();
    assert!(
        matches!(e, DnurbsError::InvalidMaterial { name: "mu", value, .. } if value == -1.0),
        "{e}"
    );
    assert!(e.to_string().contains("mu") && e.to_string().contains("-1"));
    let e = build(
        Material {
            beta12: f64::NAN,
            ..support::paper_material()
        },
        Loads::default(),
        support::paper_constraints(),
        DnurbsOptions::default(),
    )
    .unwrap_err();
    assert!(
        matches!(e, DnurbsError::InvalidMaterial { name: "beta12", .. }),
        "{e}"
    );
    let e = build(
        Material {
            alpha22: -0.5,
            ..support::paper_material()
        },
        Loads::default(),
        support::paper_constraints(),
        DnurbsOptions::default(),
    )
    .unwrap_err();
    assert!(
        matches!(e, DnurbsError::InvalidMaterial { name: "alpha22", value, .. } if value == -0.5),
        "{e}"
    );
    // μ = 0 is refused: the mass matrix would be singular.
    let e = build(
        Material {
            mu: 0.0,
            alpha11: 1.0,
            alpha22: 1.0,
            ..Material::default()
        },
        Loads::default(),
        support::paper_constraints(),
        DnurbsOptions::default(),
    )
    .unwrap_err();
    assert!(
        matches!(e, DnurbsError::InvalidMaterial { name: "mu", value, .. } if value == 0.0),
        "{e}"
    );
}

#[test]
fn missing_control_point_is_named() {
    let c = Constraints {
        fixed_points: vec![0, 35],
        ..Constraints::default()
    };
    let e = build(
        support::paper_material(),
        Loads::default(),
        c,
        DnurbsOptions::default(),
    )
    .unwrap_err();
    assert!(
        matches!(
            e,
            DnurbsError::MissingControlPoint {
                index: 35,
                count: 35
            }
        ),
        "{e}"
    );
    assert!(e.to_string().contains("35"));
}

#[test]
fn non_positive_time_step_is_rejected() {
    let model = support::paper_model(DnurbsOptions::default());
    for dt in [0.0, -0.1, f64::NAN] {
        let s = model.initial_state(&[[0.0; 3]], 0.0);
        let e = RationalStepper::new(&model, s.clone(), dt).err().unwrap();
        assert!(matches!(e, DnurbsError::InvalidTimeStep { .. }), "{e}");
        let e = make_stepper(IntegratorKind::TerzopoulosQin, &model, &s, dt)
            .err()
            .unwrap();
        assert!(matches!(e, SimError::InvalidTimeStep { .. }), "{e}");
    }
}

/// The singular-stiffness error names the first axis along which a rigid translation is
/// left free: a net held only in x (a linear constraint on x of point 0) is free along y;
/// held in x and y, along z; held in all three, no translation is free (the paper's material
/// has bending terms only, so the affine fields still make K singular, reported otherwise).
#[test]
fn free_translation_is_named_by_its_axis() {
    let hold = |axes: &[usize]| Constraints {
        linear: axes
            .iter()
            .map(|&x| LinearConstraint {
                terms: vec![(x, 1.0)],
                rhs: [0.0, 0.0, 2.0][x],
            })
            .collect(),
        ..Constraints::default()
    };
    let error = |axes: &[usize]| {
        build(
            support::paper_material(),
            Loads::default(),
            hold(axes),
            DnurbsOptions::default(),
        )
        .unwrap()
        .steady_state()
        .unwrap_err()
        .to_string()
    };
    let e = error(&[0]);
    assert!(e.contains("translation along y"), "{e}");
    let e = error(&[0, 1]);
    assert!(e.contains("translation along z"), "{e}");
    let e = error(&[0, 1, 2]);
    assert!(!e.contains("translation along"), "{e}");
}

#[test]
fn free_floating_steady_state_is_singular() {
    let loads = Loads {
        gravity: [0.0, 0.0, -9.81],
        ..Loads::default()
    };
    let m = build(
        support::paper_material(),
        loads.clone(),
        Constraints::default(),
        DnurbsOptions::default(),
    )
    .unwrap();
    let e = m.steady_state().unwrap_err();
    assert!(matches!(e, DnurbsError::Singular { .. }), "{e}");
    assert!(e.to_string().contains("free-floating"), "{e}");
    // One fixed corner holds translations but not the bending null space (affine fields).
    let c = Constraints {
        fixed_points: vec![0],
        ..Constraints::default()
    };
    let m = build(
        support::paper_material(),
        loads.clone(),
        c,
        DnurbsOptions::default(),
    )
    .unwrap();
    assert!(matches!(
        m.steady_state(),
        Err(DnurbsError::Singular { .. })
    ));
    // No stiffness at all.
    let m = build(
        Material {
            mu: 1.0,
            ..Material::default()
        },
        loads,
        support::paper_constraints(),
        DnurbsOptions::default(),
    )
    .unwrap();
    assert!(matches!(
        m.steady_state(),
        Err(DnurbsError::Singular { .. })
    ));
}

#[test]
fn bad_loads_are_rejected() {
    let outside = Loads {
        point: vec![PointLoad {
            u: 1.5,
            v: 0.5,
            force: [0.0, 0.0, 1.0],
        }],
        ..Loads::default()
    };
    let e = build(
        support::paper_material(),
        outside,
        support::paper_constraints(),
        DnurbsOptions::default(),
    )
    .unwrap_err();
    assert!(matches!(e, DnurbsError::InvalidLoad { .. }), "{e}");
    assert!(e.to_string().contains("1.5"), "{e}");
    let nan = Loads {
        gravity: [0.0, f64::NAN, 0.0],
        ..Loads::default()
    };
    let e = build(
        support::paper_material(),
        nan,
        support::paper_constraints(),
        DnurbsOptions::default(),
    )
    .unwrap_err();
    assert!(matches!(e, DnurbsError::InvalidLoad { .. }), "{e}");
}

#[test]
fn bad_constraints_are_rejected() {
    let bad_dof = Constraints {
        linear: vec![LinearConstraint {
            terms: vec![(105, 1.0)],
            rhs: 0.0,
        }],
        ..Constraints::default()
    };
    let e = build(
        support::paper_material(),
        Loads::default(),
        bad_dof,
        DnurbsOptions::default(),
    )
    .unwrap_err();
    assert!(matches!(e, DnurbsError::InvalidConstraint { .. }), "{e}");
    assert!(e.to_string().contains("105"), "{e}");
    // Moving a fixed control point is impossible.
    let conflict = Constraints {
        fixed_rings: 2,
        linear: vec![LinearConstraint {
            terms: vec![(2, 1.0)],
            rhs: 5.0,
        }],
        ..Constraints::default()
    };
    let e = build(
        support::paper_material(),
        Loads::default(),
        conflict,
        DnurbsOptions::default(),
    )
    .unwrap_err();
    assert!(matches!(e, DnurbsError::InvalidConstraint { .. }), "{e}");
    // Two contradicting rows on a free dof.
    let free_z = 3 * 17 + 2;
    let inconsistent = Constraints {
        fixed_rings: 2,
        linear: vec![
            LinearConstraint {
                terms: vec![(free_z, 1.0)],
                rhs: 2.0,
            },
            LinearConstraint {
                terms: vec![(free_z, 2.0)],
                rhs: 3.0,
            },
        ],
        ..Constraints::default()
    };
    let e = build(
        support::paper_material(),
        Loads::default(),
        inconsistent,
        DnurbsOptions::default(),
    )
    .unwrap_err();
    assert!(matches!(e, DnurbsError::InvalidConstraint { .. }), "{e}");
    let nan = Constraints {
        linear: vec![LinearConstraint {
            terms: vec![(0, f64::INFINITY)],
            rhs: 0.0,
        }],
        ..Constraints::default()
    };
    assert!(matches!(
        build(
            support::paper_material(),
            Loads::default(),
            nan,
            DnurbsOptions::default()
        ),
        Err(DnurbsError::InvalidConstraint { .. })
    ));
}

#[test]
fn bad_options_and_lengths_are_rejected() {
    let o = DnurbsOptions {
        quadrature_points: Some(0),
        ..DnurbsOptions::default()
    };
    let e = assemble(
        &Geometry::Surface(support::paper_surface()),
        &Material::default(),
        &Loads::default(),
        &o,
    )
    .unwrap_err();
    assert!(
        matches!(
            e,
            DnurbsError::InvalidOption {
                name: "quadrature_points",
                ..
            }
        ),
        "{e}"
    );
    let model = support::paper_model(DnurbsOptions::default());
    let e = model.point(0.5, 0.5, &[0.0; 10]).unwrap_err();
    assert!(
        matches!(
            e,
            DnurbsError::DimensionMismatch {
                expected: 105,
                found: 10,
                ..
            }
        ),
        "{e}"
    );
    assert!(matches!(
        model.point(0.5, 2.0, model.p0()),
        Err(DnurbsError::Geom(_))
    ));
    let mut s = model.initial_state(&[[0.0; 3]], 0.0);
    s.q.pop();
    assert!(matches!(
        RationalStepper::new(&model, s, 0.1),
        Err(DnurbsError::DimensionMismatch { .. })
    ));
    let m = support::paper_model(DnurbsOptions {
        weights_as_dofs: true,
        ..DnurbsOptions::default()
    });
    let s = m.initial_state(&[[0.0; 3]], 0.0);
    let st = RationalStepper::new(&m, s, 0.1).unwrap();
    assert!(matches!(
        st.with_min_weight(0.0),
        Err(DnurbsError::InvalidOption { name: "w_min", .. })
    ));
}
