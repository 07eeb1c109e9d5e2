//! IGES against Open CASCADE 8.0 (`tests/data/make_iges_fixtures.py`).

mod common;

use common::{blessed, data, dist, f, floats, json, same_bits, sample_curves, sample_surfaces};
use nurbspring_exchange::Shape;
use nurbspring_exchange::iges::{self, ReadReport, SkipKind};
use serde_json::Value;

const OCP_FILES: [&str; 3] = ["ocp_brep.igs", "ocp_faces.igs", "ocp_faces_default.igs"];

/// nurbspring's evaluation of `shape` at OCP's parameters (clamped onto nurbspring's domain
/// when OCP's bound differs from it by rounding), against OCP's point; returns the largest
/// difference.
fn compare(shape: &Shape, entity: &Value) -> f64 {
    let mut worst = 0.0_f64;
    for row in entity["points"].as_array().unwrap() {
        let r = floats(row);
        let (x, expected) = match shape {
            Shape::Curve(c) => {
                let (a, b) = c.domain();
                assert!(
                    r[0] >= a - 1e-12 && r[0] <= b + 1e-12,
                    "{} outside [{a}, {b}]",
                    r[0]
                );
                (c.point(r[0].clamp(a, b)).unwrap(), &r[1..])
            }
            Shape::Surface(s) => {
                let ((u0, u1), (v0, v1)) = s.domain();
                (
                    s.point(r[0].clamp(u0, u1), r[1].clamp(v0, v1)).unwrap(),
                    &r[2..],
                )
            }
        };
        worst = worst.max(dist(x, expected));
    }
    worst
}

fn shape_at(report: &ReadReport, de: u64) -> &Shape {
    let i = report
        .entities
        .iter()
        .position(|e| e.de_pointer as u64 == de)
        .unwrap_or_else(|| panic!("no shape from DE {de}"));
    &report.shapes[i]
}

/// nurbspring reads OCP's files (BRep mode, Faces mode, and OCP's default number format) and
/// evaluates every 126 and 128 where OCP, reading the same file, evaluates it: 1e-12.
#[test]
fn reads_ocp_files_and_evaluates_like_ocp() {
    let points = json("iges/ocp_points.json");
    for name in OCP_FILES {
        let report = iges::read_file(data(&format!("iges/{name}"))).unwrap();
        let file = &points["files"][name];
        let entities = file["entities"].as_array().unwrap();
        assert_eq!(
            report.shapes.len(),
            entities.len(),
            "{name}: one shape per 126/128"
        );
        for e in entities {
            let de = e["de"].as_u64().unwrap();
            let shape = shape_at(&report, de);
            assert_eq!(f(&e["unit_factor"]), 1.0);
            match (shape, e["type"].as_u64().unwrap()) {
                (Shape::Curve(c), 126) => {
                    let d = floats(&e["domain"]);
                    assert!(
                        (c.domain().0 - d[0]).abs() <= 1e-15
                            && (c.domain().1 - d[1]).abs() <= 1e-15
                    );
                }
                (Shape::Surface(s), 128) => {
                    let d: Vec<Vec<f64>> =
                        e["domain"].as_array().unwrap().iter().map(floats).collect();
                    assert_eq!(
                        s.domain(),
                        ((d[0][0], d[0][1]), (d[1][0], d[1][1])),
                        "{name}"
                    );
                }
                _ => panic!("{name}: DE {de} has the wrong kind"),
            }
            let worst = compare(shape, e);
            assert!(worst <= 1e-12, "{name} DE {de}: {worst:e}");
        }
        // The entity types OCP counted are all accounted for: imported or listed as skipped.
        let counted: u64 = file["entity_types"]
            .as_object()
            .unwrap()
            .values()
            .map(|v| v.as_u64().unwrap())
            .sum();
        assert_eq!(
            counted as usize,
            report.shapes.len() + report.skipped.len(),
            "{name}"
        );
        assert_eq!(report.global.units_name, "MM");
        assert_eq!(report.global.unit_in_mm(), Some(1.0));
    }
}

/// What the reader says about OCP's wrappers and topology.
#[test]
fn reports_wrappers_and_skipped_entities() {
    let brep = iges::read_file(data("iges/ocp_brep.igs")).unwrap();
    let kinds = |r: &ReadReport, t: u32| -> Vec<SkipKind> {
        r.skipped
            .iter()
            .filter(|s| s.entity_type == t)
            .map(|s| s.kind)
            .collect()
    };
    assert_eq!(kinds(&brep, 510), [SkipKind::Wrapper]);
    for t in [402, 508, 504, 502] {
        assert_eq!(kinds(&brep, t), [SkipKind::NotGeometry], "{t}");
    }
    assert_eq!(kinds(&brep, 110), [SkipKind::UnsupportedGeometry; 4]);
    assert!(brep.notes.iter().any(|n| n.starts_with(
        "entity 510 (face) at line 8 (D 3): imported its underlying surface, entity 128"
    )));
    let surface = brep.entities.iter().find(|e| e.entity_type == 128).unwrap();
    assert_eq!(surface.used_by, [(510, 8)]);
    assert_eq!(
        (surface.u_range, surface.v_range),
        ((0.1, 1.9), Some((-0.5, 2.5)))
    );
    assert_eq!(surface.status.subordinate, 1);

    let faces = iges::read_file(data("iges/ocp_faces.igs")).unwrap();
    assert_eq!(kinds(&faces, 144), [SkipKind::Wrapper]);
    assert_eq!(kinds(&faces, 142), [SkipKind::NotGeometry]);
    assert_eq!(kinds(&faces, 102), [SkipKind::UnsupportedGeometry; 2]);
    assert!(faces.notes.iter().any(|n| n.contains(
        "entity 144 (trimmed (parametric) surface) at line 8 (D 3): imported its underlying surface"
    )
        && n.contains("untrimmed (its trimming curves are not applied)")));
    let surface = faces
        .entities
        .iter()
        .find(|e| e.entity_type == 128)
        .unwrap();
    assert_eq!(surface.used_by, [(144, 8), (142, 12)]);
}

/// The files OCP printed with 17 digits hold OCP's geometry exactly: nurbspring evaluates OCP's
/// original surface and curves to 1e-12. OCP's default format keeps about 9 digits.
#[test]
fn exact_files_match_the_original_geometry() {
    let points = json("iges/ocp_points.json");
    let original = &points["original"];
    for name in OCP_FILES {
        let report = iges::read_file(data(&format!("iges/{name}"))).unwrap();
        let surface = report
            .shapes
            .iter()
            .find(|s| matches!(s, Shape::Surface(_)))
            .unwrap();
        let mut worst = compare(surface, &original["surface"]);
        // The two free curves are the last two entities (DE 29 and 31).
        for (de, c) in [29, 31]
            .into_iter()
            .zip(original["curves"].as_array().unwrap())
        {
            worst = worst.max(compare(shape_at(&report, de), c));
        }
        if name == "ocp_faces_default.igs" {
            assert!(worst > 1e-12 && worst < 1e-7, "{name}: {worst:e}");
        } else {
            assert!(worst <= 1e-12, "{name}: {worst:e}");
        }
    }
}

/// `nurbspring_written.igs` is what the writer produces now (OCP read it in
/// `make_iges_fixtures.py` part 2).
#[test]
fn nurbspring_iges_is_blessed() {
    let mut shapes = sample_curves();
    shapes.extend(sample_surfaces());
    let text = iges::write(&shapes);
    blessed("iges/nurbspring_written.igs", &text);
    let back = iges::read(&text).unwrap();
    assert!(
        shapes
            .iter()
            .zip(&back.shapes)
            .all(|(a, b)| same_bits(a, b))
    );
    assert!(back.skipped.is_empty() && back.notes.is_empty(), "{back:?}");
}

/// OCP read nurbspring's file: no load fails, faces and edges made, the very same knots,
/// weights and poles (bit for bit), and OCP's evaluation equals nurbspring's to 1e-12.
#[test]
fn ocp_reads_nurbspring_iges() {
    let mut shapes = sample_curves();
    shapes.extend(sample_surfaces());
    let r = json("iges/ocp_reads_nurbspring.json");
    assert_eq!(r["global_check_fails"].as_u64(), Some(0));
    assert_eq!(r["model_check_status"].as_str(), Some("Interface_CheckOK"));
    assert_eq!(r["model_check_fails_empty"].as_bool(), Some(true));
    assert_eq!(r["transfer_roots"]["faces"].as_u64(), Some(2));
    assert!(r["transfer_roots"]["edges"].as_u64().unwrap() >= 2);
    assert_eq!(r["global"]["units_name"].as_str(), Some("MM"));
    let parsed = r["parsed"].as_array().unwrap();
    assert_eq!(parsed.len(), shapes.len());
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    let flat = |v: &Value| -> Vec<f64> { v.as_array().unwrap().iter().flat_map(floats).collect() };
    for (k, (shape, p)) in shapes.iter().zip(parsed).enumerate() {
        assert_eq!(p["de"].as_u64(), Some(2 * k as u64 + 1));
        match shape {
            Shape::Curve(c) => {
                assert_eq!(p["type"].as_u64(), Some(126));
                assert_eq!(bits(&floats(&p["knots"])), bits(c.basis().knots().knots()));
                assert_eq!(bits(&floats(&p["weights"])), bits(c.weights()));
                let pts: Vec<f64> = c.control_points().iter().flatten().copied().collect();
                assert_eq!(bits(&flat(&p["poles"])), bits(&pts));
                let (a, b) = c.domain();
                assert_eq!(floats(&p["range"]), [a, b]);
            }
            Shape::Surface(s) => {
                assert_eq!(p["type"].as_u64(), Some(128));
                assert_eq!(
                    bits(&floats(&p["knots_u"])),
                    bits(s.basis_u().knots().knots())
                );
                assert_eq!(
                    bits(&floats(&p["knots_v"])),
                    bits(s.basis_v().knots().knots())
                );
                assert_eq!(bits(&floats(&p["weights"])), bits(s.weights()));
                let pts: Vec<f64> = s.control_points().iter().flatten().copied().collect();
                assert_eq!(bits(&flat(&p["poles"])), bits(&pts));
            }
        }
    }
    let entities = r["entities"].as_array().unwrap();
    assert_eq!(entities.len(), shapes.len());
    for (shape, e) in shapes.iter().zip(entities) {
        let worst = compare(shape, e);
        assert!(worst <= 1e-12, "DE {}: {worst:e}", e["de"]);
    }
}
