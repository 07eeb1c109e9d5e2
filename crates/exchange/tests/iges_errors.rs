//! IGES files made by hand: delimiters, Hollerith strings, transformations, wrappers, and every
//! kind of error with its line and section.

mod common;

use common::{same_bits, sample_curves, sample_surfaces};
use nurbspring_exchange::iges::{self, SkipKind};
use nurbspring_exchange::{ExchangeError, Location, Section, Shape};

/// One entity of a hand-made file.
struct Ent {
    ty: u32,
    params: Vec<String>,
    transform: usize,
    form: i64,
}

fn ent(ty: u32, params: &[&str]) -> Ent {
    Ent {
        ty,
        params: params.iter().map(|s| s.to_string()).collect(),
        transform: 0,
        form: 0,
    }
}

/// Packs `tokens` (each followed by `pd`, the last by `rd`) into lines of `width`.
fn pack(tokens: &[String], pd: char, rd: char, width: usize) -> Vec<String> {
    let mut lines = vec![String::new()];
    for (i, t) in tokens.iter().enumerate() {
        let tok = format!("{t}{}", if i + 1 == tokens.len() { rd } else { pd });
        if lines.last().unwrap().len() + tok.len() > width {
            lines.push(String::new());
        }
        lines.last_mut().unwrap().push_str(&tok);
    }
    lines
}

/// An IGES file with the raw Global section text `global` and the given entities.
fn file(global: &str, pd: char, rd: char, entities: &[Ent]) -> String {
    let mut out = format!("{:<72}S{:07}\n", "hand-made", 1);
    let g: Vec<char> = global.chars().collect();
    let g_lines: Vec<String> = g.chunks(72).map(|c| c.iter().collect()).collect();
    for (i, l) in g_lines.iter().enumerate() {
        out.push_str(&format!("{l:<72}G{:07}\n", i + 1));
    }
    let (mut d, mut p, mut pl) = (String::new(), String::new(), 1);
    for (k, e) in entities.iter().enumerate() {
        let de = 2 * k + 1;
        let mut tokens = vec![e.ty.to_string()];
        tokens.extend(e.params.iter().cloned());
        let lines = pack(&tokens, pd, rd, 64);
        for (i, l) in lines.iter().enumerate() {
            p.push_str(&format!("{l:<64} {de:7}P{:07}\n", pl + i));
        }
        d.push_str(&format!(
            "{:>8}{pl:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}D{de:07}\n",
            e.ty, 0, 0, 0, 0, e.transform, 0, "00000000"
        ));
        d.push_str(&format!(
            "{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}D{:07}\n",
            e.ty,
            0,
            0,
            lines.len(),
            e.form,
            "",
            "",
            "",
            0,
            de + 1
        ));
        pl += lines.len();
    }
    out.push_str(&d);
    out.push_str(&p);
    let t = format!(
        "S{:>7}G{:>7}D{:>7}P{:>7}",
        1,
        g_lines.len(),
        2 * entities.len(),
        pl - 1
    );
    out.push_str(&format!("{t:<72}T{:07}\n", 1));
    out
}

const GLOBAL: &str = "1H,,1H;,4Htest,8Htest.igs,,,32,308,15,308,15,,1.0,2,2HMM,1,0.01,15H20240101.000000,1.0E-7,10.0,,,11,0;";

/// A linear curve from (0,0,0) to (1,2,3), weights 1.
fn line126() -> Ent {
    ent(
        126,
        &[
            "1", "1", "0", "0", "1", "0", "0.", "0.", "1.", "1.", "1.", "1.", "0.", "0.", "0.",
            "1.", "2.", "3.", "0.", "1.", "0.", "0.", "0.",
        ],
    )
}

fn err(text: &str) -> ExchangeError {
    iges::read(text).expect_err("the file must be refused")
}

fn at(e: &ExchangeError) -> (usize, Option<Section>) {
    match e.location() {
        Some(Location::Iges { line, section }) => (*line, *section),
        other => panic!("{e}: no IGES location ({other:?})"),
    }
}

#[test]
fn custom_delimiters_and_hollerith_strings() {
    // Parameter delimiter '/', record delimiter '$', strings holding both and the defaults.
    let global = "1H//1H$/11Ha/b$c,d;e f/8Htest.igs/////////1.0/2/2HMM/1/0.01/15H20240101.000000/1.0E-7/10.0/6HA, B/C/3H$/$/11/0$";
    let mut l = line126();
    l.params[5] = "0.0".into(); // first knot written differently, still 0
    let text = file(global, '/', '$', &[l]);
    let r = iges::read(&text).unwrap();
    assert_eq!(r.global.parameter_delimiter, '/');
    assert_eq!(r.global.record_delimiter, '$');
    assert_eq!(r.global.product_id, "a/b$c,d;e f");
    assert_eq!(r.global.author, "A, B/C");
    assert_eq!(r.global.organization, "$/$");
    assert_eq!(r.global.version, 11);
    assert_eq!(
        r.shapes[0].as_curve().unwrap().point(0.5).unwrap(),
        [0.5, 1.0, 1.5]
    );
    // Default delimiters given as empty fields.
    let r = iges::read(&file(",,4Hsome,;", ',', ';', &[line126()])).unwrap();
    assert_eq!(
        (r.global.parameter_delimiter, r.global.record_delimiter),
        (',', ';')
    );
    assert_eq!(r.global.product_id, "some");
}

#[test]
fn transformations_are_applied() {
    // 124: rotate 90° about z, then translate by (10, 0, 0); chained to a second 124 that
    // scales by 2 (applied after).
    let mut m1 = ent(
        124,
        &[
            "0.", "-1.", "0.", "10.", "1.", "0.", "0.", "0.", "0.", "0.", "1.", "0.",
        ],
    );
    m1.transform = 3;
    let m2 = ent(
        124,
        &[
            "2.", "0.", "0.", "0.", "0.", "2.", "0.", "0.", "0.", "0.", "2.", "0.",
        ],
    );
    let mut c = line126();
    c.transform = 1;
    let r = iges::read(&file(GLOBAL, ',', ';', &[m1, m2, c])).unwrap();
    let p = r.shapes[0].as_curve().unwrap().control_points()[1];
    // (1,2,3) → rotate (−2,1,3) → +(10,0,0) (8,1,3) → ×2 (16,2,6).
    assert_eq!(p, [16.0, 2.0, 6.0]);
    assert_eq!(r.entities[0].transforms, [4, 6]);
    assert!(r.skipped.iter().all(|s| s.kind == SkipKind::Transformation));
    assert!(
        r.notes
            .iter()
            .any(|n| n.contains("applied the transformation matrix at line 4"))
    );
    // A transform pointer to something else is an error on the entity's D line.
    let mut c = line126();
    c.transform = 3;
    let e = err(&file(GLOBAL, ',', ';', &[line126(), c]));
    assert_eq!(at(&e), (6, Some(Section::Directory)));
    assert!(
        e.to_string()
            .contains("not to a transformation matrix (124)"),
        "{e}"
    );
}

#[test]
fn wrappers_and_unsupported_geometry() {
    // 144 trimmed surface over a 128 with no trimming (N1 = 0): surface imported, note says so.
    let surf = iges::write(&sample_surfaces()[..1]);
    let r = iges::read(&surf).unwrap();
    let s128: Vec<String> = {
        // Take the written 128's parameters back out of the file (columns 1–64 of P lines).
        let data: String = surf
            .lines()
            .filter(|l| l.as_bytes()[72] == b'P')
            .map(|l| &l[..64])
            .collect();
        data.trim_end()
            .trim_end_matches(';')
            .split(',')
            .skip(1)
            .map(|s| s.trim().to_string())
            .collect()
    };
    let wrapped = file(
        GLOBAL,
        ',',
        ';',
        &[
            ent(144, &["3", "0", "0", "0"]),
            Ent {
                ty: 128,
                params: s128.clone(),
                transform: 0,
                form: 0,
            },
            ent(314, &["50.", "0.", "0.", "5HGREEN"]),
        ],
    );
    let w = iges::read(&wrapped).unwrap();
    assert!(same_bits(&w.shapes[0], &r.shapes[0]));
    assert_eq!(w.entities[0].used_by, [(144, 4)]);
    assert!(
        w.notes[0].contains("its boundary is the surface's own, so nothing is lost"),
        "{:?}",
        w.notes
    );
    assert_eq!(
        w.skipped
            .iter()
            .map(|s| (s.entity_type, s.kind))
            .collect::<Vec<_>>(),
        [(144, SkipKind::Wrapper), (314, SkipKind::NotGeometry)]
    );
    // A 144 over a surface of revolution (120) and nothing else: unsupported, with its type.
    let rev = file(
        GLOBAL,
        ',',
        ';',
        &[
            ent(144, &["3", "0", "0", "0"]),
            ent(120, &["5", "7", "0.", "1."]),
            ent(110, &["0.", "0.", "0.", "1.", "0.", "0."]),
            ent(110, &["0.", "0.", "0.", "0.", "1.", "0."]),
        ],
    );
    let e = err(&rev);
    match &e {
        ExchangeError::UnsupportedEntity {
            entity_type, at, ..
        } => {
            assert_eq!(*entity_type, 120);
            assert_eq!(*at, Location::iges(6, Section::Directory));
        }
        other => panic!("{other}"),
    }
    let m = e.to_string();
    assert!(m.starts_with("line 6 (Directory Entry (D) section): unsupported entity type 120 (surface of revolution)"), "{m}");
    assert!(
        m.contains("refers to entity 120") && m.contains("2 more unsupported geometric entities"),
        "{m}"
    );
    // With a 126 beside it the file reads, and the report lists the 120.
    let mut ents = vec![
        ent(144, &["3", "0", "0", "0"]),
        ent(120, &["5", "7", "0.", "1."]),
        ent(110, &["0.", "0.", "0.", "1.", "0.", "0."]),
        ent(110, &["0.", "0.", "0.", "0.", "1.", "0."]),
    ];
    ents.push(line126());
    let r = iges::read(&file(GLOBAL, ',', ';', &ents)).unwrap();
    assert_eq!(r.shapes.len(), 1);
    let s120 = r.skipped.iter().find(|s| s.entity_type == 120).unwrap();
    assert_eq!(s120.kind, SkipKind::UnsupportedGeometry);
    assert!(
        s120.reason.contains("the surface of entity 144"),
        "{}",
        s120.reason
    );
    // Only a color: no geometry at all.
    let e = err(&file(
        GLOBAL,
        ',',
        ';',
        &[ent(314, &["50.", "0.", "0.", "5HGREEN"])],
    ));
    assert!(matches!(e, ExchangeError::NoGeometry { .. }));
    assert!(
        e.to_string().contains("1 × entity 314 (color definition)"),
        "{e}"
    );
    // A pointer to nowhere.
    let e = err(&file(
        GLOBAL,
        ',',
        ';',
        &[ent(144, &["9", "0", "0", "0"]), line126()],
    ));
    assert!(matches!(e, ExchangeError::MissingEntity { .. }), "{e}");
    assert_eq!(at(&e), (8, Some(Section::Parameter)));
    assert!(e.to_string().contains("no entity starts at D 9"), "{e}");
}

/// The written sample curve file, with `f` applied to its text.
fn mutated(f: impl Fn(&str) -> String) -> String {
    f(&iges::write(&sample_curves()[..1]))
}

#[test]
fn errors_name_line_and_section() {
    let good = iges::write(&sample_curves()[..1]);
    let lines: Vec<&str> = good.lines().collect();
    // Layout: a short line.
    let e = err(&mutated(|t| t.replacen("S0000001\n", "S000001\n", 1)));
    assert!(matches!(e, ExchangeError::ColumnLayout { .. }));
    assert_eq!(at(&e).0, 1);
    assert!(e.to_string().contains("the line has 79 columns"), "{e}");
    // Layout: a wrong section letter.
    let e = err(&mutated(|t| t.replacen("G0000002", "X0000002", 1)));
    assert!(
        e.to_string()
            .starts_with("line 3: wrong column layout: column 73 holds 'X'"),
        "{e}"
    );
    // Layout: a sequence number out of order.
    let e = err(&mutated(|t| t.replacen("D0000002", "D0000003", 1)));
    assert_eq!(at(&e), (6, Some(Section::Directory)));
    // Layout: data in column 65 of a P line.
    let p1 = lines.iter().position(|l| l.as_bytes()[72] == b'P').unwrap();
    let mut bad = lines.clone();
    let fixed = format!("{}x{}", &lines[p1][..64], &lines[p1][65..]);
    bad[p1] = &fixed;
    let e = err(&(bad.join("\n") + "\n"));
    assert_eq!(at(&e), (p1 + 1, Some(Section::Parameter)));
    assert!(e.to_string().contains("column 65"), "{e}");
    // Malformed: a P line pointing back to another entity.
    let wrong = format!("{}{:7}{}", &lines[p1][..65], 3, &lines[p1][72..]);
    let mut bad = lines.clone();
    bad[p1] = &wrong;
    let e = err(&(bad.join("\n") + "\n"));
    assert_eq!(at(&e), (p1 + 1, Some(Section::Parameter)));
    assert!(
        e.to_string().contains("malformed record") && e.to_string().contains("must hold 1"),
        "{e}"
    );
    // Weight ≤ 0, with the line of that weight.
    let e = err(&mutated(|t| {
        t.replacen("0.7071067811865476", "-0.5              ", 1)
    }));
    match &e {
        ExchangeError::InvalidWeight {
            index: 1, value, ..
        } => assert_eq!(*value, -0.5),
        other => panic!("{other}"),
    }
    assert_eq!(at(&e).1, Some(Section::Parameter));
    // Non-finite: a coordinate that overflows.
    let e = err(&mutated(|t| {
        t.replacen("0.7071067811865476", "1E999             ", 1)
    }));
    assert!(matches!(e, ExchangeError::NonFinite { .. }), "{e}");
    assert!(e.to_string().contains("(1E999)"), "{e}");
    // Knot counts: K larger than the numbers that follow.
    let e = err(&mutated(|t| t.replacen("126,6,2,", "126,9,2,", 1)));
    assert!(matches!(e, ExchangeError::KnotCount { .. }), "{e}");
    assert!(e.to_string().contains("K = 9 and M = 2 need"), "{e}");
    // Degree above the control point count.
    let e = err(&mutated(|t| t.replacen("126,6,2,", "126,1,2,", 1)));
    assert!(
        e.to_string()
            .contains("K = 1 gives 2 control points, fewer than degree M + 1 = 3"),
        "{e}"
    );
    // A decreasing knot vector: the geometry crate's message, on the line of the knots.
    let e = err(&mutated(|t| {
        t.replacen(",1.0,1.0,2.0,", ",1.0,0.5,2.0,", 1)
    }));
    assert!(matches!(e, ExchangeError::Geometry { .. }), "{e}");
    assert!(e.to_string().contains("non-decreasing"), "{e}");
    // A number that is not one.
    let e = err(&mutated(|t| t.replacen(",1.75,", ",1.7x,", 1)));
    assert!(e.to_string().contains("\"1.7x\", not a number"), "{e}");
    // Truncated file.
    let cut: String = lines[..lines.len() - 2].join("\n");
    let e = err(&cut);
    assert!(
        e.to_string().contains("without the Terminate (T) line"),
        "{e}"
    );
    // Terminate counts that do not match.
    let e = err(&mutated(|t| t.replacen("D      2", "D      4", 1)));
    assert_eq!(at(&e).1, Some(Section::Terminate));
    // Binary and compressed forms are named.
    let e = err(&mutated(|t| t.replacen("S0000001", "C0000001", 1)));
    assert!(e.to_string().contains("compressed ASCII"), "{e}");
    // Entity type differing between the two DE lines.
    let e = err(&mutated(|t| {
        t.replacen("     126       0", "     128       0", 1)
    }));
    assert_eq!(at(&e), (6, Some(Section::Directory)));
    assert!(
        e.to_string()
            .contains("the entity type is 126 on the first Directory Entry line (line 5) but 128"),
        "{e}"
    );
}

#[test]
fn round_trip_and_crlf() {
    let mut shapes = sample_curves();
    shapes.extend(sample_surfaces());
    let text = iges::write(&shapes);
    let crlf = text.replace('\n', "\r\n");
    let r = iges::read(&crlf).unwrap();
    assert!(shapes.iter().zip(&r.shapes).all(|(a, b)| same_bits(a, b)));
    // Records without line breaks (fixed 80-byte records).
    let flat: String = text.lines().collect();
    let r = iges::read(&flat).unwrap();
    assert_eq!(r.shapes.len(), 4);
    // write → read → write is the same text.
    assert_eq!(iges::write(&r.shapes), text);
    // Every record is 80 columns.
    assert!(text.lines().all(|l| l.len() == 80));
    let planar = iges::read(&text).unwrap();
    assert_eq!(
        planar.entities[0].properties[0], 1,
        "the 270° arc lies in a plane"
    );
    let n = planar.entities[0].normal.unwrap();
    assert!(
        (n[0].abs() - 1.0 / 5f64.sqrt()).abs() < 1e-15
            && (n[2].abs() - 2.0 / 5f64.sqrt()).abs() < 1e-15,
        "{n:?}"
    );
    assert_eq!(planar.entities[1].properties[0], 0);
    assert!(matches!(planar.shapes[2], Shape::Surface(_)));
}
