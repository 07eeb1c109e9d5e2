//! geomdl's JSON exchange format (NURBS-Python `geomdl.exchange.export_json` / `import_json`,
//! geomdl 5.x).
//!
//! ```text
//! {"shape": {"type": "curve" | "surface", "count": n, "data": [
//!     {"type": "spline", "rational": true, "dimension": 3,
//!      "degree": p, "knotvector": [...],                                  (curves)
//!      "degree_u": p, "degree_v": q, "knotvector_u": [...], "knotvector_v": [...],
//!      "size_u": n_u, "size_v": n_v,                                      (surfaces)
//!      "control_points": {"points": [[x, y, z], ...], "weights": [w, ...]}}, ...]}}
//! ```
//!
//! The conventions, as geomdl 5.4's `_exchange.py` and `NURBS.py` implement them:
//!
//! - **Points are not weighted.** `control_points.points` holds the Cartesian points `P_i`
//!   (geomdl's `ctrlpts`, which divides its internal `P_i·w_i` by `w_i`), `weights` the `w_i`.
//!   Without `weights` every weight is 1 (geomdl's `BSpline` objects export no weights).
//! - **Surface order is nurbspring's.** geomdl's flat index is `v + size_v · u` (its evaluator
//!   reads `ctrlpts[idx_v + l + size_v * (idx_u + k)]`): all v for the first u, then the next u,
//!   which is nurbspring's `k = i · n_v + j` with `i` along u. No reordering is needed.
//! - **2-D points** (`dimension` 2, points `[x, y]`) are read with `z = 0`. The writer always
//!   writes three coordinates and `"dimension": 3`. A `dimension` key that disagrees with the
//!   points is an error.
//! - **Knot vectors are kept as written.** geomdl normalizes every knot vector to `[0, 1]` when it
//!   sets one (`normalize_kv=True`, rounding to 18 decimals), so its own exports always have
//!   domains in `[0, 1]`. A file whose knots span `[a, b]` describes the same shape in geomdl and
//!   here, but geomdl's parameter `t` is nurbspring's `a + t (b − a)`.
//! - geomdl ignores `count`, `rational`, `delta`, `name` and `id` on reading; so does this reader.
//!   A `volume` shape, or a surface with `trims`, is refused rather than half read.

use std::path::Path;

use nurbspring_geom::{KnotVector, NurbsCurve, NurbsSurface};
use serde_json::{Map, Value};

use crate::fmt::shortest;
use crate::{ExchangeError, Location, Shape, fsio};

/// Reads every shape of a geomdl JSON document (curves or surfaces, in file order).
///
/// ```
/// let json = r#"{"shape": {"type": "curve", "count": 1, "data": [{
///     "degree": 1, "knotvector": [0.0, 0.0, 1.0, 1.0],
///     "control_points": {"points": [[0.0, 0.0], [2.0, 1.0]]}}]}}"#;
/// let shapes = nurbspring_exchange::geomdl::read(json).unwrap();
/// let c = shapes[0].as_curve().unwrap();
/// assert_eq!(c.point(0.5).unwrap(), [1.0, 0.5, 0.0]);
/// assert_eq!(c.weights(), [1.0, 1.0]);
/// ```
pub fn read(text: &str) -> Result<Vec<Shape>, ExchangeError> {
    let root: Value = serde_json::from_str(text).map_err(|e| {
        let message = e.to_string();
        let detail = match message.rfind(" at line ") {
            Some(i) => message[..i].to_string(),
            None => message,
        };
        ExchangeError::malformed(
            Location::Line {
                line: e.line(),
                column: e.column(),
            },
            format!("invalid JSON: {detail}"),
        )
    })?;
    let root = object(&root, "")?;
    let shape = object(key(root, "", "shape")?, "shape")?;
    let kind = key(shape, "shape", "type")?;
    let kind = kind.as_str().ok_or_else(|| {
        ExchangeError::malformed(
            at("shape.type"),
            format!(
                "expected the string \"curve\" or \"surface\", found {}",
                describe(kind)
            ),
        )
    })?;
    let data = key(shape, "shape", "data")?;
    let data = data.as_array().ok_or_else(|| {
        ExchangeError::malformed(
            at("shape.data"),
            format!("expected an array of shapes, found {}", describe(data)),
        )
    })?;
    let mut shapes = Vec::with_capacity(data.len());
    for (i, item) in data.iter().enumerate() {
        let path = format!("shape.data[{i}]");
        let obj = object(item, &path)?;
        shapes.push(match kind {
            "curve" => Shape::Curve(read_curve(obj, &path)?),
            "surface" => Shape::Surface(read_surface(obj, &path)?),
            "volume" => {
                return Err(ExchangeError::Unsupported {
                    at: at("shape.type"),
                    detail: "geomdl volumes (trivariate NURBS) have no nurbspring type".into(),
                });
            }
            other => {
                return Err(ExchangeError::malformed(
                    at("shape.type"),
                    format!("unknown shape type {other:?}; geomdl writes \"curve\" or \"surface\""),
                ));
            }
        });
    }
    Ok(shapes)
}

/// Writes shapes as a geomdl JSON document (4-space indentation like geomdl's `export_json`).
///
/// geomdl's format holds one kind of shape per document: all curves or all surfaces; mixing them,
/// or writing nothing, is an [`ExchangeError::Unwritable`].
pub fn write(shapes: &[Shape]) -> Result<String, ExchangeError> {
    let kind = match shapes.first() {
        None => {
            return Err(ExchangeError::Unwritable {
                detail: "geomdl JSON needs at least one shape (its \"type\" is that of the shapes)"
                    .into(),
            });
        }
        Some(Shape::Curve(_)) => "curve",
        Some(Shape::Surface(_)) => "surface",
    };
    if let Some(i) = shapes
        .iter()
        .position(|s| matches!(s, Shape::Curve(_)) != (kind == "curve"))
    {
        return Err(ExchangeError::Unwritable {
            detail: format!(
                "shape {i} is a {} but shape 0 is a {kind}; a geomdl JSON document holds only \
                 curves or only surfaces",
                if kind == "curve" { "surface" } else { "curve" }
            ),
        });
    }
    let mut out = String::new();
    out.push_str("{\n    \"shape\": {\n");
    out.push_str(&format!("        \"type\": \"{kind}\",\n"));
    out.push_str(&format!("        \"count\": {},\n", shapes.len()));
    out.push_str("        \"data\": [\n");
    for (n, shape) in shapes.iter().enumerate() {
        const I: &str = "                ";
        out.push_str("            {\n");
        out.push_str(&format!("{I}\"type\": \"spline\",\n"));
        out.push_str(&format!("{I}\"rational\": true,\n"));
        out.push_str(&format!("{I}\"dimension\": 3,\n"));
        let (points, weights) = match shape {
            Shape::Curve(c) => {
                let k = c.basis().knots();
                out.push_str(&format!("{I}\"degree\": {},\n", k.degree()));
                out.push_str(&format!("{I}\"knotvector\": {},\n", list(k.knots())));
                (c.control_points(), c.weights())
            }
            Shape::Surface(s) => {
                let (ku, kv) = (s.basis_u().knots(), s.basis_v().knots());
                out.push_str(&format!("{I}\"degree_u\": {},\n", ku.degree()));
                out.push_str(&format!("{I}\"degree_v\": {},\n", kv.degree()));
                out.push_str(&format!("{I}\"knotvector_u\": {},\n", list(ku.knots())));
                out.push_str(&format!("{I}\"knotvector_v\": {},\n", list(kv.knots())));
                out.push_str(&format!("{I}\"size_u\": {},\n", s.n_u()));
                out.push_str(&format!("{I}\"size_v\": {},\n", s.n_v()));
                (s.control_points(), s.weights())
            }
        };
        out.push_str(&format!("{I}\"control_points\": {{\n"));
        out.push_str(&format!("{I}    \"points\": [\n"));
        for (i, p) in points.iter().enumerate() {
            let sep = if i + 1 < points.len() { "," } else { "" };
            out.push_str(&format!("{I}        {}{sep}\n", list(p)));
        }
        out.push_str(&format!("{I}    ],\n"));
        out.push_str(&format!("{I}    \"weights\": {}\n", list(weights)));
        out.push_str(&format!("{I}}}\n"));
        let sep = if n + 1 < shapes.len() { "," } else { "" };
        out.push_str(&format!("            }}{sep}\n"));
    }
    out.push_str("        ]\n    }\n}\n");
    Ok(out)
}

/// Reads a geomdl JSON file (a regular file of at most [`crate::MAX_FILE_BYTES`]).
pub fn read_file(path: impl AsRef<Path>) -> Result<Vec<Shape>, ExchangeError> {
    read(&fsio::read_text(path.as_ref())?)
}

/// Writes shapes to a geomdl JSON file (see [`write()`]).
pub fn write_file(path: impl AsRef<Path>, shapes: &[Shape]) -> Result<(), ExchangeError> {
    fsio::write_text(path.as_ref(), &write(shapes)?)
}

fn list(values: &[f64]) -> String {
    let items: Vec<String> = values.iter().map(|&x| shortest(x)).collect();
    format!("[{}]", items.join(", "))
}

fn at(path: &str) -> Location {
    Location::Json {
        path: if path.is_empty() {
            "the document root".into()
        } else {
            path.into()
        },
    }
}

fn join(path: &str, key: &str) -> String {
    if path.is_empty() {
        key.to_string()
    } else {
        format!("{path}.{key}")
    }
}

fn describe(v: &Value) -> String {
    match v {
        Value::Null => "null".into(),
        Value::Bool(b) => format!("the boolean {b}"),
        Value::Number(n) => format!("the number {n}"),
        Value::String(s) if s.chars().count() > 40 => "a string".into(),
        Value::String(s) => format!("the string {s:?}"),
        Value::Array(a) => format!("an array of {} items", a.len()),
        Value::Object(_) => "an object".into(),
    }
}

fn object<'a>(v: &'a Value, path: &str) -> Result<&'a Map<String, Value>, ExchangeError> {
    v.as_object().ok_or_else(|| {
        ExchangeError::malformed(
            at(path),
            format!("expected an object, found {}", describe(v)),
        )
    })
}

fn key<'a>(
    obj: &'a Map<String, Value>,
    path: &str,
    name: &str,
) -> Result<&'a Value, ExchangeError> {
    obj.get(name).ok_or_else(|| ExchangeError::MissingEntity {
        at: at(path),
        detail: format!("the required key \"{name}\" is absent"),
    })
}

fn count(obj: &Map<String, Value>, path: &str, name: &str) -> Result<usize, ExchangeError> {
    let v = key(obj, path, name)?;
    v.as_u64()
        .and_then(|n| usize::try_from(n).ok())
        .ok_or_else(|| {
            ExchangeError::malformed(
                at(&join(path, name)),
                format!("expected a non-negative integer, found {}", describe(v)),
            )
        })
}

fn number(v: &Value, path: &str) -> Result<f64, ExchangeError> {
    let x = v.as_f64().ok_or_else(|| {
        ExchangeError::malformed(
            at(path),
            format!("expected a number, found {}", describe(v)),
        )
    })?;
    if x.is_finite() {
        Ok(x)
    } else {
        Err(ExchangeError::NonFinite {
            at: at(path),
            what: "the value".into(),
            text: v.to_string(),
        })
    }
}

fn numbers(obj: &Map<String, Value>, path: &str, name: &str) -> Result<Vec<f64>, ExchangeError> {
    let v = key(obj, path, name)?;
    let p = join(path, name);
    let a = v.as_array().ok_or_else(|| {
        ExchangeError::malformed(
            at(&p),
            format!("expected an array of numbers, found {}", describe(v)),
        )
    })?;
    a.iter()
        .enumerate()
        .map(|(i, x)| number(x, &format!("{p}[{i}]")))
        .collect()
}

/// Control points (2-D or 3-D, unweighted) and weights (default 1).
fn control_points(
    obj: &Map<String, Value>,
    path: &str,
) -> Result<(Vec<[f64; 3]>, Vec<f64>), ExchangeError> {
    let cp_path = join(path, "control_points");
    let cp = object(key(obj, path, "control_points")?, &cp_path)?;
    let pts_path = join(&cp_path, "points");
    let pts = key(cp, &cp_path, "points")?;
    let pts = pts.as_array().ok_or_else(|| {
        ExchangeError::malformed(
            at(&pts_path),
            format!("expected an array of points, found {}", describe(pts)),
        )
    })?;
    let declared = match obj.get("dimension") {
        None => None,
        Some(d) => Some(d.as_u64().ok_or_else(|| {
            ExchangeError::malformed(
                at(&join(path, "dimension")),
                format!("expected 2 or 3, found {}", describe(d)),
            )
        })?),
    };
    let mut dim = None;
    let mut points = Vec::with_capacity(pts.len());
    for (i, p) in pts.iter().enumerate() {
        let pp = format!("{pts_path}[{i}]");
        let coords = p.as_array().ok_or_else(|| {
            ExchangeError::malformed(
                at(&pp),
                format!(
                    "expected a point [x, y, z] or [x, y], found {}",
                    describe(p)
                ),
            )
        })?;
        let d = coords.len();
        if d != 2 && d != 3 {
            return Err(ExchangeError::malformed(
                at(&pp),
                format!("a point has 2 or 3 coordinates, this one has {d}"),
            ));
        }
        match dim {
            None => dim = Some(d),
            Some(d0) if d0 != d => {
                return Err(ExchangeError::malformed(
                    at(&pp),
                    format!("this point has {d} coordinates but point 0 has {d0}"),
                ));
            }
            _ => {}
        }
        let mut xyz = [0.0; 3];
        for (c, v) in coords.iter().enumerate() {
            xyz[c] = number(v, &format!("{pp}[{c}]"))?;
        }
        points.push(xyz);
    }
    if let (Some(declared), Some(d)) = (declared, dim)
        && declared != d as u64
    {
        return Err(ExchangeError::malformed(
            at(&join(path, "dimension")),
            format!("\"dimension\" is {declared} but the control points have {d} coordinates"),
        ));
    }
    let weights = if cp.contains_key("weights") {
        let w = numbers(cp, &cp_path, "weights")?;
        if w.len() != points.len() {
            return Err(ExchangeError::malformed(
                at(&join(&cp_path, "weights")),
                format!("{} weights for {} control points", w.len(), points.len()),
            ));
        }
        let wp = join(&cp_path, "weights");
        for (i, &value) in w.iter().enumerate() {
            if value <= 0.0 {
                return Err(ExchangeError::InvalidWeight {
                    at: at(&format!("{wp}[{i}]")),
                    index: i,
                    value,
                });
            }
        }
        w
    } else {
        vec![1.0; points.len()]
    };
    Ok((points, weights))
}

fn knot_vector(
    knots: Vec<f64>,
    degree: usize,
    n: usize,
    path: &str,
    what: &str,
) -> Result<KnotVector, ExchangeError> {
    let expected = degree.checked_add(n).and_then(|x| x.checked_add(1));
    if expected != Some(knots.len()) {
        return Err(ExchangeError::KnotCount {
            at: at(path),
            detail: format!(
                "\"{what}\" has {} knots, but degree {degree} with {n} control points needs \
                 degree + control points + 1 = {}",
                knots.len(),
                expected.map_or_else(|| "too many".to_string(), |e| e.to_string())
            ),
        });
    }
    KnotVector::try_new(knots, degree).map_err(|source| ExchangeError::Geometry {
        at: at(&join(path, what)),
        source,
    })
}

fn read_curve(obj: &Map<String, Value>, path: &str) -> Result<NurbsCurve, ExchangeError> {
    let degree = count(obj, path, "degree")?;
    let knots = numbers(obj, path, "knotvector")?;
    let (points, weights) = control_points(obj, path)?;
    let kv = knot_vector(knots, degree, points.len(), path, "knotvector")?;
    NurbsCurve::try_new(kv, points, weights).map_err(|source| ExchangeError::Geometry {
        at: at(path),
        source,
    })
}

fn read_surface(obj: &Map<String, Value>, path: &str) -> Result<NurbsSurface, ExchangeError> {
    if obj.contains_key("trims") {
        return Err(ExchangeError::Unsupported {
            at: at(&join(path, "trims")),
            detail: "trimmed surfaces: nurbspring surfaces have no trimming curves".into(),
        });
    }
    let degree_u = count(obj, path, "degree_u")?;
    let degree_v = count(obj, path, "degree_v")?;
    let size_u = count(obj, path, "size_u")?;
    let size_v = count(obj, path, "size_v")?;
    let knots_u = numbers(obj, path, "knotvector_u")?;
    let knots_v = numbers(obj, path, "knotvector_v")?;
    let (points, weights) = control_points(obj, path)?;
    if size_u.checked_mul(size_v) != Some(points.len()) {
        return Err(ExchangeError::malformed(
            at(&join(path, "control_points.points")),
            format!(
                "{} control points, but size_u × size_v = {size_u} × {size_v}",
                points.len()
            ),
        ));
    }
    let ku = knot_vector(knots_u, degree_u, size_u, path, "knotvector_u")?;
    let kv = knot_vector(knots_v, degree_v, size_v, path, "knotvector_v")?;
    NurbsSurface::try_new(ku, kv, points, weights).map_err(|source| ExchangeError::Geometry {
        at: at(path),
        source,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn doc(item: &str) -> String {
        format!(r#"{{"shape": {{"type": "surface", "count": 1, "data": [{item}]}}}}"#)
    }

    #[test]
    fn errors_name_the_json_path() {
        let ok = r#"{"degree_u": 1, "degree_v": 1, "size_u": 2, "size_v": 2,
            "knotvector_u": [0, 0, 1, 1], "knotvector_v": [0, 0, 1, 1],
            "control_points": {"points": [[0,0,0],[0,1,0],[1,0,0],[1,1,1]],
                               "weights": [1, 1, 1, 2]}}"#;
        let s = read(&doc(ok)).unwrap();
        assert_eq!(
            s[0].as_surface().unwrap().point(1.0, 1.0).unwrap(),
            [1., 1., 1.]
        );
        let e = read(&doc(&ok.replace("[1, 1, 1, 2]", "[1, 1, 0, 2]")))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("shape.data[0].control_points.weights[2]") && e.contains("weight 2 is 0"),
            "{e}"
        );
        let e = read(&doc(&ok.replace(
            "\"knotvector_v\": [0, 0, 1, 1]",
            "\"knotvector_v\": [0, 1, 1]",
        )))
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("inconsistent knot count") && e.contains("knotvector_v"),
            "{e}"
        );
        let e = read(&doc(&ok.replace("\"size_v\": 2", "\"size_v\": 3")))
            .unwrap_err()
            .to_string();
        assert!(e.contains("size_u × size_v = 2 × 3"), "{e}");
        let e = read(&doc(&ok.replace("\"degree_u\": 1,", "")))
            .unwrap_err()
            .to_string();
        assert!(e.contains("\"degree_u\" is absent"), "{e}");
        let e = read("{\"shape\": [1,\n 2").unwrap_err().to_string();
        assert!(
            e.starts_with("line 2, column 2: malformed record: invalid JSON"),
            "{e}"
        );
        let e = read(&doc(&ok.replace("[1,1,1]]", "[1,1]]")))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("points[3]") && e.contains("2 coordinates but point 0 has 3"),
            "{e}"
        );
    }

    #[test]
    fn mixed_or_empty_shape_lists_are_unwritable() {
        assert!(matches!(write(&[]), Err(ExchangeError::Unwritable { .. })));
    }
}
