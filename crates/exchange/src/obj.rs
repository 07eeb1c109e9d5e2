//! Wavefront OBJ free-form geometry (OBJ 3.0: "Specifying free-form curves/surfaces").
//!
//! ```text
//! v 1.0 0.0 0.0 1.0            control points, `v x y z w` (w: the weight, not multiplied in)
//! v 1.0 1.0 0.0 0.7071067811865476
//! v 0.0 1.0 0.0 1.0
//! cstype rat bspline           `bspline` when every weight of the shape is 1 (then `v x y z`)
//! deg 2                        `deg p q` for surfaces
//! curv 0.0 1.0 1 2 3           parameter range, then 1-based vertex references
//! parm u 0.0 0.0 0.0 1.0 1.0 1.0
//! end
//! ```
//!
//! Surfaces are `surf s0 s1 t0 t1 v…` with `parm u` and `parm v` knot lines; their control
//! vertices are listed with the u index fastest (row `j` of the v direction after row `j − 1`),
//! so OBJ position `j n_u + i` is nurbspring's `k = i n_v + j`. Points are Cartesian: OBJ's
//! rational basis is `Σ N_i w_i P_i / Σ N_i w_i` with `P_i = (x, y, z)`.
//!
//! The reader reads what [`write()`] writes and the same statements from other writers: comments,
//! `\` continuation lines, `v/vt/vn` references, negative (relative) vertex indices. Polygonal
//! statements (`f`, `l`, `p`, `vt`, `vn`), grouping and display attributes are ignored. Bezier,
//! Cardinal, Taylor and basis-matrix curves, 2-D curves (`curv2`), trimming (`trim`, `hole`,
//! `scrv`, `sp`) and parameter ranges other than the knot domain are refused with
//! [`ExchangeError::Unsupported`].

use std::path::Path;

use nurbspring_geom::{KnotVector, NurbsCurve, NurbsSurface};

use crate::fmt::shortest;
use crate::{ExchangeError, Location, Shape, fsio};

/// Writes shapes as OBJ free-form curves and surfaces, each with its own control vertices.
///
/// ```
/// use nurbspring_exchange::{Shape, obj};
/// use nurbspring_geom::{KnotVector, NurbsCurve};
/// let k = KnotVector::try_new(vec![0., 0., 1., 2., 2.], 1).unwrap();
/// let c = NurbsCurve::try_new(k, vec![[0., 0., 0.], [1., 0., 0.], [1., 1., 0.]], vec![1.0; 3]).unwrap();
/// let text = obj::write(&[Shape::Curve(c)]);
/// assert!(text.contains("cstype bspline\ndeg 1\ncurv 0.0 2.0 1 2 3\nparm u 0.0 0.0 1.0 2.0 2.0\nend\n"));
/// ```
pub fn write(shapes: &[Shape]) -> String {
    let mut out = String::from("# nurbspring-exchange: OBJ free-form geometry\n");
    let mut next = 1usize;
    for shape in shapes {
        let (points, weights) = match shape {
            Shape::Curve(c) => (c.control_points(), c.weights()),
            Shape::Surface(s) => (s.control_points(), s.weights()),
        };
        let rational = weights.iter().any(|&w| w != 1.0);
        let vertex = |out: &mut String, k: usize| {
            let p = points[k];
            out.push_str(&format!(
                "v {} {} {}",
                shortest(p[0]),
                shortest(p[1]),
                shortest(p[2])
            ));
            if rational {
                out.push_str(&format!(" {}", shortest(weights[k])));
            }
            out.push('\n');
        };
        let cstype = if rational {
            "cstype rat bspline\n"
        } else {
            "cstype bspline\n"
        };
        match shape {
            Shape::Curve(c) => {
                for k in 0..points.len() {
                    vertex(&mut out, k);
                }
                let kv = c.basis().knots();
                let (a, b) = kv.domain();
                out.push_str(cstype);
                out.push_str(&format!("deg {}\n", kv.degree()));
                out.push_str(&format!("curv {} {}", shortest(a), shortest(b)));
                for r in next..next + points.len() {
                    out.push_str(&format!(" {r}"));
                }
                out.push('\n');
                out.push_str(&format!("parm u {}\nend\n", list(kv.knots())));
            }
            Shape::Surface(s) => {
                let (nu, nv) = (s.n_u(), s.n_v());
                // u index fastest.
                for j in 0..nv {
                    for i in 0..nu {
                        vertex(&mut out, i * nv + j);
                    }
                }
                let (ku, kv) = (s.basis_u().knots(), s.basis_v().knots());
                let ((u0, u1), (v0, v1)) = s.domain();
                out.push_str(cstype);
                out.push_str(&format!("deg {} {}\n", ku.degree(), kv.degree()));
                out.push_str(&format!(
                    "surf {} {} {} {}",
                    shortest(u0),
                    shortest(u1),
                    shortest(v0),
                    shortest(v1)
                ));
                for r in next..next + points.len() {
                    out.push_str(&format!(" {r}"));
                }
                out.push('\n');
                out.push_str(&format!("parm u {}\n", list(ku.knots())));
                out.push_str(&format!("parm v {}\nend\n", list(kv.knots())));
            }
        }
        next += points.len();
    }
    out
}

/// Reads the free-form B-spline curves and surfaces of an OBJ file, in file order.
pub fn read(text: &str) -> Result<Vec<Shape>, ExchangeError> {
    let mut r = ObjReader::default();
    let mut pending = String::new();
    let mut pending_line = 0;
    for (i, raw) in text.split('\n').enumerate() {
        let raw = raw.strip_suffix('\r').unwrap_or(raw);
        let content = raw.split('#').next().unwrap_or("");
        if pending.is_empty() {
            pending_line = i + 1;
        }
        if let Some(head) = content.trim_end().strip_suffix('\\') {
            pending.push_str(head);
            pending.push(' ');
            continue;
        }
        pending.push_str(content);
        let statement = std::mem::take(&mut pending);
        r.statement(&statement, pending_line)?;
    }
    if !pending.trim().is_empty() {
        r.statement(&pending, pending_line)?;
    }
    if let Some(e) = &r.element {
        return Err(ExchangeError::malformed(
            line(e.line),
            format!(
                "the {} that starts here has no `end` statement",
                e.keyword()
            ),
        ));
    }
    Ok(r.shapes)
}

/// Reads an OBJ file (a regular file of at most [`crate::MAX_FILE_BYTES`]); see [`read()`].
pub fn read_file(path: impl AsRef<Path>) -> Result<Vec<Shape>, ExchangeError> {
    read(&fsio::read_text(path.as_ref())?)
}

/// Writes shapes to an OBJ file; see [`write()`].
pub fn write_file(path: impl AsRef<Path>, shapes: &[Shape]) -> Result<(), ExchangeError> {
    fsio::write_text(path.as_ref(), &write(shapes))
}

fn list(values: &[f64]) -> String {
    values
        .iter()
        .map(|&x| shortest(x))
        .collect::<Vec<_>>()
        .join(" ")
}

fn line(n: usize) -> Location {
    Location::Line { line: n, column: 0 }
}

#[derive(Clone, Debug)]
struct Element {
    surface: bool,
    line: usize,
    rational: bool,
    degree: (usize, usize),
    range: Vec<f64>,
    refs: Vec<usize>,
    parm_u: Option<Vec<f64>>,
    parm_v: Option<Vec<f64>>,
}

impl Element {
    fn keyword(&self) -> &'static str {
        if self.surface { "surf" } else { "curv" }
    }
}

#[derive(Default)]
struct ObjReader {
    /// `(x, y, z, w)` of every `v`.
    vertices: Vec<[f64; 4]>,
    /// `Some(rational)` after `cstype [rat] bspline`.
    cstype: Option<bool>,
    degree: Option<(usize, Option<usize>)>,
    element: Option<Element>,
    shapes: Vec<Shape>,
}

fn real(token: &str, n: usize, what: &str) -> Result<f64, ExchangeError> {
    let x: f64 = token.parse().map_err(|_| {
        ExchangeError::malformed(line(n), format!("{what} is {token:?}, not a number"))
    })?;
    if x.is_finite() {
        Ok(x)
    } else {
        Err(ExchangeError::NonFinite {
            at: line(n),
            what: what.to_string(),
            text: token.to_string(),
        })
    }
}

impl ObjReader {
    fn statement(&mut self, s: &str, n: usize) -> Result<(), ExchangeError> {
        let mut words = s.split_whitespace();
        let Some(keyword) = words.next() else {
            return Ok(());
        };
        let args: Vec<&str> = words.collect();
        match keyword {
            "v" => {
                if args.len() != 3 && args.len() != 4 {
                    return Err(ExchangeError::malformed(
                        line(n),
                        format!("`v` takes x y z [w], found {} values", args.len()),
                    ));
                }
                let mut v = [0.0, 0.0, 0.0, 1.0];
                for (k, a) in args.iter().enumerate() {
                    v[k] = real(a, n, ["x", "y", "z", "w"][k])?;
                }
                self.vertices.push(v);
            }
            "cstype" => {
                let (rational, kind) = match args.as_slice() {
                    ["rat", kind] => (true, *kind),
                    [kind] => (false, *kind),
                    _ => {
                        return Err(ExchangeError::malformed(
                            line(n),
                            format!("`cstype` takes [rat] type, found {:?}", args.join(" ")),
                        ));
                    }
                };
                match kind {
                    "bspline" => self.cstype = Some(rational),
                    "bezier" | "bmatrix" | "cardinal" | "taylor" => {
                        return Err(ExchangeError::Unsupported {
                            at: line(n),
                            detail: format!("`cstype {kind}`: only B-splines (bspline) are read"),
                        });
                    }
                    other => {
                        return Err(ExchangeError::malformed(
                            line(n),
                            format!("unknown curve/surface type {other:?}"),
                        ));
                    }
                }
            }
            "deg" => {
                let d = |a: &str| -> Result<usize, ExchangeError> {
                    a.parse().map_err(|_| {
                        ExchangeError::malformed(
                            line(n),
                            format!("degree {a:?} is not a whole number"),
                        )
                    })
                };
                self.degree = Some(match args.as_slice() {
                    [p] => (d(p)?, None),
                    [p, q] => (d(p)?, Some(d(q)?)),
                    _ => {
                        return Err(ExchangeError::malformed(
                            line(n),
                            format!("`deg` takes degu [degv], found {} values", args.len()),
                        ));
                    }
                });
            }
            "curv" | "surf" => {
                let surface = keyword == "surf";
                if let Some(e) = &self.element {
                    return Err(ExchangeError::malformed(
                        line(n),
                        format!(
                            "a `{keyword}` inside the {} of line {} (no `end` before it)",
                            e.keyword(),
                            e.line
                        ),
                    ));
                }
                let rational = self.cstype.ok_or_else(|| {
                    ExchangeError::malformed(
                        line(n),
                        format!("`{keyword}` before any `cstype` statement"),
                    )
                })?;
                let degree = match (self.degree, surface) {
                    (Some((p, _)), false) => (p, 0),
                    (Some((p, Some(q))), true) => (p, q),
                    (Some((_, None)), true) => {
                        return Err(ExchangeError::malformed(
                            line(n),
                            "a surface needs two degrees (`deg degu degv`), the last `deg` gives one",
                        ));
                    }
                    (None, _) => {
                        return Err(ExchangeError::malformed(
                            line(n),
                            format!("`{keyword}` before any `deg` statement"),
                        ));
                    }
                };
                let n_range = if surface { 4 } else { 2 };
                if args.len() < n_range + 2 {
                    return Err(ExchangeError::malformed(
                        line(n),
                        format!(
                            "`{keyword}` takes {} and at least two control vertices, found {} values",
                            if surface { "s0 s1 t0 t1" } else { "u0 u1" },
                            args.len()
                        ),
                    ));
                }
                let range = args[..n_range]
                    .iter()
                    .map(|a| real(a, n, "a parameter range value"))
                    .collect::<Result<Vec<_>, _>>()?;
                let refs = args[n_range..]
                    .iter()
                    .map(|a| self.vertex_ref(a, n))
                    .collect::<Result<Vec<_>, _>>()?;
                self.element = Some(Element {
                    surface,
                    line: n,
                    rational,
                    degree,
                    range,
                    refs,
                    parm_u: None,
                    parm_v: None,
                });
            }
            "parm" => {
                let e = self.element.as_mut().ok_or_else(|| {
                    ExchangeError::malformed(line(n), "`parm` outside a `curv` or `surf` element")
                })?;
                let (dir, values) = args.split_first().ok_or_else(|| {
                    ExchangeError::malformed(line(n), "`parm` takes u|v and the knots")
                })?;
                let values = values
                    .iter()
                    .map(|a| real(a, n, "a knot"))
                    .collect::<Result<Vec<_>, _>>()?;
                match (*dir, e.surface) {
                    ("u", _) => e.parm_u = Some(values),
                    ("v", true) => e.parm_v = Some(values),
                    ("v", false) => {
                        return Err(ExchangeError::malformed(
                            line(n),
                            "`parm v` in a curve (curves have u only)",
                        ));
                    }
                    (other, _) => {
                        return Err(ExchangeError::malformed(
                            line(n),
                            format!("`parm {other}`: the direction is u or v"),
                        ));
                    }
                }
            }
            "end" => {
                let e = self.element.take().ok_or_else(|| {
                    ExchangeError::malformed(line(n), "`end` without a `curv` or `surf` element")
                })?;
                let shape = self.finish(e, n)?;
                self.shapes.push(shape);
            }
            "curv2" | "trim" | "hole" | "scrv" | "sp" | "bmat" => {
                return Err(ExchangeError::Unsupported {
                    at: line(n),
                    detail: format!(
                        "`{keyword}`: 2-D curves, trimming loops, special curves/points and basis \
                         matrices are not read"
                    ),
                });
            }
            // Polygonal geometry, grouping, display and rendering attributes.
            "vt" | "vn" | "vp" | "f" | "fo" | "l" | "p" | "g" | "o" | "s" | "mg" | "usemtl"
            | "mtllib" | "usemap" | "maplib" | "bevel" | "c_interp" | "d_interp" | "lod"
            | "shadow_obj" | "trace_obj" | "ctech" | "stech" | "step" | "con" | "call" | "csh"
            | "res" => {}
            other => {
                return Err(ExchangeError::malformed(
                    line(n),
                    format!("unknown statement {other:?}"),
                ));
            }
        }
        Ok(())
    }

    /// A 1-based (or negative, relative) vertex reference `v`, `v/vt`, `v/vt/vn`, `v//vn`.
    fn vertex_ref(&self, token: &str, n: usize) -> Result<usize, ExchangeError> {
        let head = token.split('/').next().unwrap_or("");
        let v: i64 = head.parse().map_err(|_| {
            ExchangeError::malformed(
                line(n),
                format!("vertex reference {token:?} is not an integer"),
            )
        })?;
        let len = self.vertices.len();
        let index = if v > 0 {
            usize::try_from(v - 1).ok().filter(|&i| i < len)
        } else if v < 0 {
            usize::try_from(v.unsigned_abs())
                .ok()
                .and_then(|back| len.checked_sub(back))
        } else {
            None
        };
        index.ok_or_else(|| ExchangeError::MissingEntity {
            at: line(n),
            detail: format!(
                "vertex reference {v} names no vertex ({len} `v` statements so far; references \
                 are 1-based, negative ones count back from the last)"
            ),
        })
    }

    fn finish(&self, e: Element, end_line: usize) -> Result<Shape, ExchangeError> {
        let at = line(e.line);
        let geometry = |source| ExchangeError::Geometry {
            at: line(e.line),
            source,
        };
        let knots = |parm: Option<Vec<f64>>, dir: &str, degree: usize, count: Option<usize>| {
            let k = parm.ok_or_else(|| ExchangeError::MissingEntity {
                at: line(end_line),
                detail: format!(
                    "the {} of line {} ends without a `parm {dir}` knot line",
                    e.keyword(),
                    e.line
                ),
            })?;
            if let Some(count) = count
                && degree.checked_add(count).and_then(|x| x.checked_add(1)) != Some(k.len())
            {
                return Err(ExchangeError::KnotCount {
                    at: line(e.line),
                    detail: format!(
                        "`parm {dir}` has {} knots, but degree {degree} with {count} control \
                         vertices needs {}",
                        k.len(),
                        degree as u128 + count as u128 + 1
                    ),
                });
            }
            if (k.len() as u128) < 2 * (degree as u128 + 1) {
                return Err(ExchangeError::KnotCount {
                    at: line(e.line),
                    detail: format!(
                        "`parm {dir}` has {} knots; degree {degree} needs at least {}",
                        k.len(),
                        2 * (degree as u128 + 1)
                    ),
                });
            }
            KnotVector::try_new(k, degree).map_err(geometry)
        };
        let check_range = |kv: &KnotVector, r: (f64, f64), dir: &str| {
            if kv.domain() != r {
                return Err(ExchangeError::Unsupported {
                    at: line(e.line),
                    detail: format!(
                        "the parameter range [{}, {}] in {dir} differs from the knot domain [{}, \
                         {}]; restricted (trimmed) ranges are not read",
                        r.0,
                        r.1,
                        kv.domain().0,
                        kv.domain().1
                    ),
                });
            }
            Ok(())
        };
        let vertex = |r: usize| self.vertices[r];
        let weight = |r: usize, k: usize| -> Result<f64, ExchangeError> {
            let w = if e.rational { vertex(r)[3] } else { 1.0 };
            if w > 0.0 {
                Ok(w)
            } else {
                Err(ExchangeError::InvalidWeight {
                    at: line(e.line),
                    index: k,
                    value: w,
                })
            }
        };
        if !e.surface {
            let kv = knots(e.parm_u.clone(), "u", e.degree.0, Some(e.refs.len()))?;
            check_range(&kv, (e.range[0], e.range[1]), "u")?;
            let points = e.refs.iter().map(|&r| {
                let v = vertex(r);
                [v[0], v[1], v[2]]
            });
            let weights = e
                .refs
                .iter()
                .enumerate()
                .map(|(k, &r)| weight(r, k))
                .collect::<Result<Vec<_>, _>>()?;
            let c = NurbsCurve::try_new(kv, points.collect(), weights).map_err(geometry)?;
            return Ok(Shape::Curve(c));
        }
        let ku = knots(e.parm_u.clone(), "u", e.degree.0, None)?;
        let kv = knots(e.parm_v.clone(), "v", e.degree.1, None)?;
        let (nu, nv) = (ku.n_basis(), kv.n_basis());
        if nu.checked_mul(nv) != Some(e.refs.len()) {
            return Err(ExchangeError::KnotCount {
                at,
                detail: format!(
                    "{} control vertices, but the knots give {nu} × {nv} (`parm u` has {} knots of \
                     degree {}, `parm v` {} of degree {})",
                    e.refs.len(),
                    ku.knots().len(),
                    e.degree.0,
                    kv.knots().len(),
                    e.degree.1
                ),
            });
        }
        check_range(&ku, (e.range[0], e.range[1]), "u")?;
        check_range(&kv, (e.range[2], e.range[3]), "v")?;
        let mut points = vec![[0.0; 3]; nu * nv];
        let mut weights = vec![0.0; nu * nv];
        for j in 0..nv {
            for i in 0..nu {
                let m = j * nu + i;
                let r = e.refs[m];
                let v = vertex(r);
                points[i * nv + j] = [v[0], v[1], v[2]];
                weights[i * nv + j] = weight(r, m)?;
            }
        }
        let s = NurbsSurface::try_new(ku, kv, points, weights).map_err(geometry)?;
        Ok(Shape::Surface(s))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_references_continuations_and_comments() {
        let text = "v 0 0 0\nv 1 0 0 # x\nv 1 1 0 2\ncstype rat bspline\ndeg 1\n\
                    curv 0 2 -3/1 \\\n -2 -1\nparm u 0 0 1 2 2\nend\n";
        let s = read(text).unwrap();
        let c = s[0].as_curve().unwrap();
        assert_eq!(c.weights(), [1.0, 1.0, 2.0]);
        assert_eq!(c.point(2.0).unwrap(), [1.0, 1.0, 0.0]);
        let e = read("cstype bspline\ndeg 1\ncurv 0 1 1 2\nparm u 0 0 1 1\nend\n")
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("line 3: missing entity: vertex reference 1"),
            "{e}"
        );
        let e = read("v 0 0 0\nv 1 0 0\ncstype bspline\ndeg 1\ncurv 0 1 1 2\nparm u 0 0 1\nend\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("line 5: inconsistent knot count"), "{e}");
        let e = read(
            "v 0 0 0\nv 1 0 0 -1\ncstype rat bspline\ndeg 1\ncurv 0 1 1 2\nparm u 0 0 1 1\nend\n",
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("weight 1 is -1"), "{e}");
        let e = read("cstype bezier\n").unwrap_err().to_string();
        assert!(e.contains("unsupported"), "{e}");
        let e = read("v 0 0 0\nv 1 0 0\ncstype bspline\ndeg 1\ncurv 0 1 1 2\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("no `end`"), "{e}");
    }
}
