//! Classes and their constants. The names of spring kinds, linear-element kinds and classes
//! are a file format (scene keys, JSON reports, `.msm.json`): each parses back to itself, the
//! documented aliases parse to their kind, and anything else is refused.

use nurbspring_msm::{Class, Constants, LinearKind, Region, SpringKind};

#[test]
fn spring_kinds_parse_their_names_and_aliases() {
    for kind in SpringKind::ALL {
        assert_eq!(SpringKind::parse(kind.name()), Some(kind), "{kind}");
    }
    let by_hand = [
        ("structural", SpringKind::Structural),
        ("edge", SpringKind::Structural),
        ("shear", SpringKind::Shear),
        ("diag", SpringKind::Shear),
        ("diagonal", SpringKind::Shear),
        ("bend", SpringKind::Bend),
        ("bending", SpringKind::Bend),
    ];
    for (name, kind) in by_hand {
        assert_eq!(SpringKind::parse(name), Some(kind), "{name}");
    }
    for name in ["", "Shear", "bend ", "twist", "spring_u"] {
        assert_eq!(SpringKind::parse(name), None, "{name:?}");
    }
}

#[test]
fn linear_kinds_and_classes_parse_their_names() {
    let names = [
        "spring_u", "spring_v", "diagonal", "bend_u", "bend_v", "twist", "third_u", "third_v",
    ];
    assert_eq!(LinearKind::ALL.map(LinearKind::name), names);
    for kind in LinearKind::ALL {
        assert_eq!(LinearKind::parse(kind.name()), Some(kind));
    }
    assert_eq!(LinearKind::parse("bend"), None);
    assert_eq!(Region::ALL.map(Region::name), ["interior", "boundary"]);

    let linear = Class::linear(&LinearKind::ALL);
    assert_eq!(linear.len(), 16);
    assert_eq!(
        linear[6],
        Class::Linear(LinearKind::BendU, Region::Interior)
    );
    assert_eq!(
        linear[7],
        Class::Linear(LinearKind::BendU, Region::Boundary)
    );
    for class in Class::SPRINGS.into_iter().chain(linear) {
        assert_eq!(Class::parse(&class.name()), Some(class), "{}", class.name());
    }
    assert_eq!(
        Class::Linear(LinearKind::Twist, Region::Boundary).name(),
        "twist@boundary"
    );
    assert_eq!(
        Class::parse("edge"),
        Some(Class::Spring(SpringKind::Structural))
    );
    for name in [
        "twist",
        "twist@edge",
        "bend@interior",
        "@boundary",
        "shear@interior",
    ] {
        assert_eq!(Class::parse(name), None, "{name:?}");
    }
}

#[test]
fn constants_are_set_replaced_and_removed_by_class() {
    let shear = Class::Spring(SpringKind::Shear);
    let twist = Class::Linear(LinearKind::Twist, Region::Boundary);
    let mut c = Constants::from_pairs([(shear, 2.5), (twist, 0.125)]);
    assert_eq!(
        (c.len(), c.get(shear), c.get(twist)),
        (2, Some(2.5), Some(0.125))
    );
    c.set(shear, 4.0);
    assert_eq!((c.len(), c.value(shear)), (2, 4.0));
    c.remove(shear);
    assert_eq!((c.len(), c.get(shear), c.contains(shear)), (1, None, false));
    assert_eq!(c.classes(), vec![twist]);
    c.remove(shear);
    c.remove(twist);
    assert!(c.is_empty());
}

/// `from_values` pairs `classes[i]` with `values[i]`, so it equals the explicit pairs; a
/// later class of the same name wins, as in `from_pairs`.
#[test]
fn constants_from_values_pair_classes_with_values_by_index() {
    let edge = Class::Spring(SpringKind::Structural);
    let bend = Class::Linear(LinearKind::BendV, Region::Interior);
    let c = Constants::from_values(&[edge, bend], &[2.7, 0.3]);
    assert_eq!(
        (c.len(), c.get(edge), c.get(bend)),
        (2, Some(2.7), Some(0.3))
    );
    assert_eq!(c, Constants::from_pairs([(bend, 0.3), (edge, 2.7)]));
    let twice = Constants::from_values(&[edge, edge], &[1.0, 5.0]);
    assert_eq!((twice.len(), twice.get(edge)), (1, Some(5.0)));
}
