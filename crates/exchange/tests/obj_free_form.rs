//! OBJ free-form: what the writer writes, and that the reader reads it back.

mod common;

use common::{same_bits, sample_curves, sample_surfaces};
use nurbspring_exchange::{Shape, obj};
use nurbspring_geom::{KnotVector, NurbsSurface};

#[test]
fn samples_round_trip() {
    let mut shapes = sample_curves();
    shapes.extend(sample_surfaces());
    let text = obj::write(&shapes);
    assert_eq!(text.matches("cstype rat bspline").count(), 4);
    assert_eq!(text.matches("\nend\n").count(), 4);
    assert!(text.contains(
        "deg 2\ncurv 0.0 3.0 1 2 3 4 5 6 7\nparm u 0.0 0.0 0.0 1.0 1.0 2.0 2.0 3.0 3.0 3.0\nend\n"
    ));
    assert!(text.contains("deg 2 1\nsurf 0.0 2.0 -1.0 3.0 15 16 17 18 19 20\n"));
    let back = obj::read(&text).unwrap();
    assert!(shapes.iter().zip(&back).all(|(a, b)| same_bits(a, b)));
    assert_eq!(obj::write(&back), text);
}

/// Control vertices of a surface are listed with u fastest, and `v x y z w` carries the weight
/// unmultiplied; unit weights give `cstype bspline` and `v x y z`.
#[test]
fn surface_vertex_order_and_weights() {
    let ku = KnotVector::try_new(vec![0., 0., 0., 1., 1., 1.], 2).unwrap();
    let kv = KnotVector::try_new(vec![0., 0., 1., 1.], 1).unwrap();
    // (i, j) → (i, 10 j, 0), i along u (3), j along v (2).
    let pts: Vec<[f64; 3]> = (0..3)
        .flat_map(|i| (0..2).map(move |j| [i as f64, 10.0 * j as f64, 0.0]))
        .collect();
    let plain = NurbsSurface::try_new(ku.clone(), kv.clone(), pts.clone(), vec![1.0; 6]).unwrap();
    let text = obj::write(&[Shape::Surface(plain)]);
    let v: Vec<&str> = text.lines().filter(|l| l.starts_with("v ")).collect();
    assert_eq!(
        v,
        [
            "v 0.0 0.0 0.0",
            "v 1.0 0.0 0.0",
            "v 2.0 0.0 0.0",
            "v 0.0 10.0 0.0",
            "v 1.0 10.0 0.0",
            "v 2.0 10.0 0.0"
        ]
    );
    assert!(text.contains("cstype bspline\ndeg 2 1\n"));
    let w = vec![1.0, 1.0, 0.5, 0.5, 1.0, 1.0];
    let rational = NurbsSurface::try_new(ku, kv, pts, w).unwrap();
    let text = obj::write(&[Shape::Surface(rational.clone())]);
    assert!(text.contains("v 1.0 0.0 0.0 0.5\n"), "{text}");
    let back = obj::read(&text).unwrap();
    assert_eq!(back, [Shape::Surface(rational)]);
}

#[test]
fn restricted_ranges_and_trims_are_refused() {
    let text = obj::write(&sample_curves()[..1]).replace("curv 0.0 3.0", "curv 0.5 3.0");
    let e = obj::read(&text).unwrap_err().to_string();
    assert!(
        e.contains(
            "unsupported: the parameter range [0.5, 3] in u differs from the knot domain [0, 3]"
        ),
        "{e}"
    );
    let text = obj::write(&sample_surfaces()[..1]).replace("end\n", "trim 0.0 1.0 1\nend\n");
    let e = obj::read(&text).unwrap_err().to_string();
    assert!(e.contains("`trim`"), "{e}");
}
