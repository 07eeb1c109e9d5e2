//! geomdl JSON against real geomdl 5.4.0 output (`tests/data/make_fixtures.py`).

mod common;

use common::{
    blessed, data, dist, f, floats, json, same_bits, sample_curves, sample_surfaces, text,
};
use nurbspring_exchange::{Shape, geomdl};

/// nurbspring reads geomdl's own exports and evaluates the points geomdl evaluates (1e-12).
#[test]
fn reads_geomdl_exports_and_evaluates_like_geomdl() {
    let ev = json("geomdl/evaluations.json");
    let files = ev["files"].as_object().unwrap();
    assert_eq!(files.len(), 3);
    let mut compared = 0;
    for (name, entries) in files {
        let shapes = geomdl::read_file(data(&format!("geomdl/{name}"))).unwrap();
        let entries = entries.as_array().unwrap();
        assert_eq!(shapes.len(), entries.len(), "{name}");
        for (shape, entry) in shapes.iter().zip(entries) {
            let d = &entry["shape"];
            let points = entry["points"].as_array().unwrap();
            match shape {
                Shape::Curve(c) => {
                    assert_eq!(c.basis().degree() as u64, d["degree"].as_u64().unwrap());
                    assert_eq!(c.basis().knots().knots(), floats(&d["knotvector"]));
                    assert_eq!(c.weights(), floats(&d["weights"]));
                    let dim = d["dimension"].as_u64().unwrap() as usize;
                    for (p, q) in c
                        .control_points()
                        .iter()
                        .zip(d["ctrlpts"].as_array().unwrap())
                    {
                        assert!(dist(*p, &floats(q)) <= 1e-15, "{name}: {p:?} vs {q}");
                        if dim == 2 {
                            assert_eq!(p[2], 0.0);
                        }
                    }
                    for row in points {
                        let r = floats(row);
                        let x = c.point(r[0]).unwrap();
                        assert!(
                            dist(x, &r[1..]) <= 1e-12,
                            "{name} t = {}: {x:?} vs {:?}",
                            r[0],
                            &r[1..]
                        );
                        compared += 1;
                    }
                }
                Shape::Surface(s) => {
                    assert_eq!(s.n_u() as u64, d["size_u"].as_u64().unwrap());
                    assert_eq!(s.n_v() as u64, d["size_v"].as_u64().unwrap());
                    assert_eq!(s.basis_u().knots().knots(), floats(&d["knotvector_u"]));
                    assert_eq!(s.basis_v().knots().knots(), floats(&d["knotvector_v"]));
                    assert_eq!(s.weights(), floats(&d["weights"]));
                    for row in points {
                        let r = floats(row);
                        let x = s.point(r[0], r[1]).unwrap();
                        assert!(
                            dist(x, &r[2..]) <= 1e-12,
                            "{name} ({}, {}): {x:?} vs {:?}",
                            r[0],
                            r[1],
                            &r[2..]
                        );
                        compared += 1;
                    }
                }
            }
        }
    }
    assert_eq!(compared, 3 * 13 + 2 * 9 * 7, "points compared");
}

/// The quarter cylinder is exact: every evaluated point is at radius 2.
#[test]
fn the_quarter_cylinder_is_a_cylinder() {
    let shapes = geomdl::read_file(data("geomdl/surfaces.json")).unwrap();
    let s = shapes[0].as_surface().unwrap();
    for u in [0.0, 0.1, 0.37, 0.5, 0.93, 1.0] {
        for v in [0.0, 0.4, 1.0] {
            let p = s.point(u, v).unwrap();
            assert!((p[0].hypot(p[1]) - 2.0).abs() < 1e-14);
            assert!((p[2] - 3.0 * v).abs() < 1e-14);
        }
    }
    let c = geomdl::read_file(data("geomdl/curves_2d.json")).unwrap();
    let p = c[0].as_curve().unwrap().point(0.3).unwrap();
    assert!((p[0].hypot(p[1]) - 3.0).abs() < 1e-14 && p[2] == 0.0);
}

/// write → read gives the same doubles; write → read → write the same text, for geomdl's files.
#[test]
fn write_read_write_is_exact() {
    for name in ["curves.json", "curves_2d.json", "surfaces.json"] {
        let shapes = geomdl::read(&text(&format!("geomdl/{name}"))).unwrap();
        let once = geomdl::write(&shapes).unwrap();
        let back = geomdl::read(&once).unwrap();
        assert!(
            shapes.iter().zip(&back).all(|(a, b)| same_bits(a, b)),
            "{name}"
        );
        assert_eq!(geomdl::write(&back).unwrap(), once, "{name}");
    }
}

/// The files nurbspring writes for geomdl to read (`make_fixtures.py` part 2) are what the
/// writer produces now.
#[test]
fn nurbspring_output_is_blessed() {
    blessed(
        "geomdl/nurbspring_curves.json",
        &geomdl::write(&sample_curves()).unwrap(),
    );
    blessed(
        "geomdl/nurbspring_surfaces.json",
        &geomdl::write(&sample_surfaces()).unwrap(),
    );
}

/// geomdl read nurbspring's files: same weights, points, and geomdl's evaluation (at its
/// normalized parameters t) equals nurbspring's at a + t (b − a), 1e-12.
#[test]
fn geomdl_reads_nurbspring_output() {
    let report = json("geomdl/geomdl_reads_nurbspring.json");
    assert!(report["checked"].as_array().unwrap().len() >= 5);
    let mut compared = 0;
    for (name, shapes) in [
        ("nurbspring_curves.json", sample_curves()),
        ("nurbspring_surfaces.json", sample_surfaces()),
    ] {
        let entries = report["files"][name].as_array().unwrap();
        assert_eq!(entries.len(), shapes.len(), "{name}");
        for (shape, e) in shapes.iter().zip(entries) {
            assert!(f(&e["max_ctrlpt_deviation"]) <= 1e-15);
            let doms: Vec<Vec<f64>> = e["file_domains"]
                .as_array()
                .unwrap()
                .iter()
                .map(floats)
                .collect();
            let map = |t: f64, d: &[f64]| d[0] + t * (d[1] - d[0]);
            for row in e["points"].as_array().unwrap() {
                let r = floats(row);
                match shape {
                    Shape::Curve(c) => {
                        assert_eq!(c.weights(), floats(&e["shape"]["weights"]));
                        assert_eq!(c.domain(), (doms[0][0], doms[0][1]));
                        let u = map(r[0], &doms[0]).clamp(doms[0][0], doms[0][1]);
                        let x = c.point(u).unwrap();
                        assert!(dist(x, &r[1..]) <= 1e-12, "{name}: {x:?} vs {:?}", &r[1..]);
                    }
                    Shape::Surface(s) => {
                        assert_eq!(s.weights(), floats(&e["shape"]["weights"]));
                        let u = map(r[0], &doms[0]).clamp(doms[0][0], doms[0][1]);
                        let v = map(r[1], &doms[1]).clamp(doms[1][0], doms[1][1]);
                        let x = s.point(u, v).unwrap();
                        assert!(dist(x, &r[2..]) <= 1e-12, "{name}: {x:?} vs {:?}", &r[2..]);
                    }
                }
                compared += 1;
            }
        }
    }
    assert!(compared > 100, "{compared}");
}

/// Mixing curves and surfaces in one geomdl document is refused with the reason.
#[test]
fn one_kind_per_document() {
    let mut shapes = sample_curves();
    shapes.extend(sample_surfaces());
    let e = geomdl::write(&shapes).unwrap_err().to_string();
    assert!(
        e.contains("shape 2 is a surface but shape 0 is a curve"),
        "{e}"
    );
}
