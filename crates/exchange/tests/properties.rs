//! Property tests: write → read gives the same doubles bit for bit and write → read → write
//! the same text, for random valid curves and surfaces in all three formats; and no reader
//! panics on arbitrary or mutated input.

mod common;

use common::{same_bits, sample_curves, sample_surfaces};
use nurbspring_exchange::{Shape, geomdl, iges, obj};
use nurbspring_geom::{KnotVector, NurbsCurve, NurbsSurface};
use proptest::prelude::*;

/// Any finite double, including −0.0, subnormals and magnitudes near the limits.
fn finite() -> impl Strategy<Value = f64> {
    prop_oneof![
        3 => -1e3..1e3f64,
        1 => prop::num::f64::NORMAL | prop::num::f64::SUBNORMAL | prop::num::f64::ZERO,
    ]
}

fn weight() -> impl Strategy<Value = f64> {
    prop_oneof![
        3 => 0.05..20.0f64,
        1 => prop::num::f64::POSITIVE | prop::num::f64::NORMAL | prop::num::f64::SUBNORMAL,
    ]
}

/// A valid knot vector of degree `p` with `n` basis functions: sorted random values (unclamped
/// in general), or a clamped one with repeated interior knots.
fn knots(p: usize, n: usize) -> impl Strategy<Value = KnotVector> {
    let m = n + p + 1;
    prop_oneof![
        prop::collection::vec(finite(), m).prop_map(move |mut k| {
            k.sort_by(f64::total_cmp);
            k
        }),
        (
            finite(),
            1e-3..1e6f64,
            prop::collection::vec(0u8..6, n - p - 1)
        )
            .prop_map(move |(a, len, ints)| {
                let mut inner: Vec<f64> = ints
                    .iter()
                    .map(|&i| a + len * (f64::from(i) + 1.0) / 7.0)
                    .collect();
                inner.sort_by(f64::total_cmp);
                let mut k = vec![a; p + 1];
                k.extend(inner);
                k.extend(std::iter::repeat_n(a + len, p + 1));
                k
            }),
    ]
    .prop_filter_map("valid knot vector", move |k| KnotVector::try_new(k, p).ok())
}

fn curve() -> impl Strategy<Value = NurbsCurve> {
    (1usize..=4, 0usize..=5)
        .prop_flat_map(|(p, extra)| {
            let n = p + 1 + extra;
            (
                knots(p, n),
                prop::collection::vec([finite(), finite(), finite()], n),
                prop::collection::vec(weight(), n),
            )
        })
        .prop_map(|(k, pts, w)| NurbsCurve::try_new(k, pts, w).unwrap())
}

fn surface() -> impl Strategy<Value = NurbsSurface> {
    (1usize..=3, 1usize..=3, 0usize..=3, 0usize..=3)
        .prop_flat_map(|(p, q, eu, ev)| {
            let (nu, nv) = (p + 1 + eu, q + 1 + ev);
            (
                knots(p, nu),
                knots(q, nv),
                prop::collection::vec([finite(), finite(), finite()], nu * nv),
                prop::collection::vec(weight(), nu * nv),
            )
        })
        .prop_map(|(ku, kv, pts, w)| NurbsSurface::try_new(ku, kv, pts, w).unwrap())
}

fn shapes() -> impl Strategy<Value = Vec<Shape>> {
    prop::collection::vec(
        prop_oneof![
            curve().prop_map(Shape::Curve),
            surface().prop_map(Shape::Surface)
        ],
        1..4,
    )
}

fn cases() -> u32 {
    std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(128)
}

fn all_same(a: &[Shape], b: &[Shape]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| same_bits(x, y))
}

proptest! {
    // 128 cases each unless PROPTEST_CASES says otherwise (for longer fuzzing runs).
    #![proptest_config(ProptestConfig { cases: cases(), ..ProptestConfig::default() })]

    #[test]
    fn geomdl_round_trips_bit_for_bit(curves in prop::collection::vec(curve(), 1..4), surfaces in prop::collection::vec(surface(), 1..3)) {
        for shapes in [curves.into_iter().map(Shape::Curve).collect::<Vec<_>>(), surfaces.into_iter().map(Shape::Surface).collect()] {
            let text = geomdl::write(&shapes).unwrap();
            let back = geomdl::read(&text).unwrap();
            prop_assert!(all_same(&shapes, &back));
            prop_assert_eq!(geomdl::write(&back).unwrap(), text);
        }
    }

    #[test]
    fn iges_round_trips_bit_for_bit(shapes in shapes()) {
        let text = iges::write(&shapes);
        prop_assert!(text.lines().all(|l| l.len() == 80));
        let back = iges::read(&text).unwrap();
        prop_assert!(all_same(&shapes, &back.shapes));
        prop_assert!(back.skipped.is_empty() && back.notes.is_empty());
        prop_assert_eq!(iges::write(&back.shapes), text);
    }

    #[test]
    fn obj_round_trips_bit_for_bit(shapes in shapes()) {
        let text = obj::write(&shapes);
        let back = obj::read(&text).unwrap();
        prop_assert!(all_same(&shapes, &back));
        prop_assert_eq!(obj::write(&back), text);
    }

    /// Arbitrary text: every reader returns (an error, mostly) without panicking.
    #[test]
    fn arbitrary_text_never_panics(s in ".{0,400}", t in "[0-9 .,;:/HEDPSGT+\\-\n]{0,600}") {
        for x in [&s, &t] {
            let _ = geomdl::read(x);
            let _ = iges::read(x);
            let _ = obj::read(x);
        }
    }

    /// Valid files with random edits: no panic, and an `Ok` holds valid shapes.
    #[test]
    fn mutated_files_never_panic(
        which in 0usize..4,
        edits in prop::collection::vec((any::<prop::sample::Index>(), 0u8..5, prop::sample::select(
            "0123456789.,;-+EDHPSGT /\n{}[]\":ve#\\".chars().collect::<Vec<_>>())), 1..6),
    ) {
        let mut shapes = sample_curves();
        shapes.extend(sample_surfaces());
        let text = match which {
            0 => iges::write(&shapes),
            1 => geomdl::write(&shapes[..2]).unwrap(),
            2 => geomdl::write(&shapes[2..]).unwrap(),
            _ => obj::write(&shapes),
        };
        let mut chars: Vec<char> = text.chars().collect();
        for (at, kind, c) in edits {
            if chars.is_empty() {
                break;
            }
            let i = at.index(chars.len());
            match kind {
                0 => chars[i] = c,
                1 => { chars.remove(i); }
                2 => chars.insert(i, c),
                3 => { let end = (i + 1 + at.index(90)).min(chars.len()); chars.drain(i..end); }
                _ => { let end = (i + 80).min(chars.len()); let copy: Vec<char> = chars[i..end].to_vec(); chars.splice(i..i, copy); }
            }
        }
        let s: String = chars.into_iter().collect();
        if let Ok(r) = iges::read(&s) {
            prop_assert_eq!(r.shapes.len(), r.entities.len());
            for shape in &r.shapes {
                match shape {
                    Shape::Curve(c) => prop_assert!(c.weights().iter().all(|w| *w > 0.0)),
                    Shape::Surface(s) => prop_assert!(s.weights().iter().all(|w| *w > 0.0)),
                }
            }
        }
        let _ = geomdl::read(&s);
        let _ = obj::read(&s);
    }
}
