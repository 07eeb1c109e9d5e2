//! The geometry sections: knot vectors, control nets and weights of `[surface]` and `[curve]`, checked and built.

use super::*;

/// Checks the number of knots against degree and control points; returns false on a problem.
pub(super) fn check_knot_count(
    p: &mut Problems,
    key: &str,
    knots: &[f64],
    degree: usize,
    n: usize,
    along: &str,
) -> bool {
    let needed = n.checked_add(degree).and_then(|x| x.checked_add(1));
    if knots.is_empty() {
        p.push(key, "[]", "the knot vector is empty");
        return false;
    }
    if needed != Some(knots.len()) {
        let needed = needed.map_or("more than can be stored".to_string(), |x| x.to_string());
        p.push(
            key,
            fmt_list(knots),
            format!(
                "{} knots given, but {n} control points{along} with degree {degree} need {needed} \
                 (control points + degree + 1)",
                knots.len()
            ),
        );
        return false;
    }
    true
}

/// A control point `[x, y, z]` at `key`: three finite numbers.
pub(super) fn control_point(p: &mut Problems, key: &str, q: &[f64]) -> Option<[f64; 3]> {
    if q.len() != 3 {
        p.push(
            key,
            fmt_list(q),
            format!(
                "a control point needs 3 coordinates [x, y, z], got {}",
                q.len()
            ),
        );
        return None;
    }
    for (c, &x) in q.iter().enumerate() {
        p.finite(&format!("{key}[{c}]"), x);
    }
    Some([q[0], q[1], q[2]])
}

/// `[surface]`: shapes, finiteness and weights; `None` when the points cannot be read.
pub(super) fn surface_spec(s: RawSurface, p: &mut Problems) -> Option<SurfaceSpec> {
    let start = p.len();
    for (key, d) in [
        ("surface.degree_u", s.degree_u),
        ("surface.degree_v", s.degree_v),
    ] {
        if d < 1 {
            p.push(key, d.to_string(), "the degree must be at least 1");
        }
    }
    for (key, k) in [
        ("surface.knots_u", &s.knots_u),
        ("surface.knots_v", &s.knots_v),
    ] {
        if k.len() > MAX_ITEMS {
            p.push(
                key,
                format!("{} values", k.len()),
                format!("more than {MAX_ITEMS} knots"),
            );
        }
        for (i, &x) in k.iter().enumerate() {
            p.finite(&format!("{key}[{i}]"), x);
        }
    }
    let n_u = s.control_points.len();
    // The row length most rows have (ties: the one knots_v and degree_v imply, else row
    // 0's), so that one short or long row is the one blamed.
    let implied = s.knots_v.len().checked_sub(s.degree_v + 1);
    let mut lengths: Vec<(usize, usize)> = Vec::new();
    for row in &s.control_points {
        match lengths.iter_mut().find(|(len, _)| *len == row.len()) {
            Some((_, count)) => *count += 1,
            None => lengths.push((row.len(), 1)),
        }
    }
    let most = lengths.iter().map(|&(_, c)| c).max().unwrap_or(0);
    let tied: Vec<usize> = lengths
        .iter()
        .filter(|&&(_, c)| c == most)
        .map(|&(len, _)| len)
        .collect();
    let n_v = match implied {
        Some(len) if tied.contains(&len) => len,
        _ => tied.first().copied().unwrap_or(0),
    };
    let agreeing = lengths
        .iter()
        .find(|&&(len, _)| len == n_v)
        .map_or(0, |&(_, c)| c);
    if n_u == 0 {
        p.push("surface.control_points", "[]", "no control points given");
    } else if n_v == 0 {
        p.push(
            "surface.control_points",
            "[[], …]",
            "the rows of control points are empty",
        );
    }
    if n_u.saturating_mul(n_v) > MAX_ITEMS {
        p.push(
            "surface.control_points",
            format!("{n_u} x {n_v}"),
            format!("more than {MAX_ITEMS} control points"),
        );
        return None;
    }
    let mut points = Vec::with_capacity(n_u);
    for (i, row) in s.control_points.iter().enumerate() {
        if row.len() != n_v {
            p.push(
                format!("surface.control_points[{i}]"),
                format!("{} points", row.len()),
                format!("every row must have {n_v} points, like {agreeing} of the {n_u} rows (rows run along u, points in a row along v)"),
            );
            continue;
        }
        let mut out = Vec::with_capacity(n_v);
        for (j, q) in row.iter().enumerate() {
            if let Some(point) = control_point(p, &format!("surface.control_points[{i}][{j}]"), q) {
                out.push(point);
            }
        }
        points.push(out);
    }
    if let Some(w) = &s.weights {
        if w.len() != n_u {
            p.push(
                "surface.weights",
                format!("{} rows", w.len()),
                format!("the weights must have the shape of control_points: {n_u} rows of {n_v}"),
            );
        }
        for (i, row) in w.iter().enumerate() {
            if row.len() != n_v {
                p.push(
                    format!("surface.weights[{i}]"),
                    format!("{} values", row.len()),
                    format!("every row of weights must have {n_v} values, like control_points"),
                );
            }
            for (j, &x) in row.iter().enumerate() {
                p.positive(&format!("surface.weights[{i}][{j}]"), x, "weights");
            }
        }
    }
    if p.len() == start {
        let ok_u = check_knot_count(
            p,
            "surface.knots_u",
            &s.knots_u,
            s.degree_u,
            n_u,
            " along u",
        );
        let ok_v = check_knot_count(
            p,
            "surface.knots_v",
            &s.knots_v,
            s.degree_v,
            n_v,
            " along v",
        );
        if !(ok_u && ok_v) {
            return None;
        }
    } else {
        return None;
    }
    Some(SurfaceSpec {
        degree_u: s.degree_u,
        degree_v: s.degree_v,
        knots_u: s.knots_u,
        knots_v: s.knots_v,
        control_points: points,
        weights: s.weights,
    })
}

/// `[curve]`: shapes, finiteness and weights.
pub(super) fn curve_spec(c: RawCurve, p: &mut Problems) -> Option<CurveSpec> {
    let start = p.len();
    if c.degree < 1 {
        p.push(
            "curve.degree",
            c.degree.to_string(),
            "the degree must be at least 1",
        );
    }
    if c.knots.len() > MAX_ITEMS {
        p.push(
            "curve.knots",
            format!("{} values", c.knots.len()),
            format!("more than {MAX_ITEMS} knots"),
        );
    }
    for (i, &x) in c.knots.iter().enumerate() {
        p.finite(&format!("curve.knots[{i}]"), x);
    }
    let n = c.control_points.len();
    if n == 0 {
        p.push("curve.control_points", "[]", "no control points given");
    }
    if n > MAX_ITEMS {
        p.push(
            "curve.control_points",
            format!("{n} points"),
            format!("more than {MAX_ITEMS} control points"),
        );
        return None;
    }
    let mut points = Vec::with_capacity(n);
    for (i, q) in c.control_points.iter().enumerate() {
        if let Some(point) = control_point(p, &format!("curve.control_points[{i}]"), q) {
            points.push(point);
        }
    }
    if let Some(w) = &c.weights {
        if w.len() != n {
            p.push(
                "curve.weights",
                format!("{} values", w.len()),
                format!("there must be one weight per control point ({n})"),
            );
        }
        for (i, &x) in w.iter().enumerate() {
            p.positive(&format!("curve.weights[{i}]"), x, "weights");
        }
    }
    if p.len() != start || !check_knot_count(p, "curve.knots", &c.knots, c.degree, n, "") {
        return None;
    }
    Some(CurveSpec {
        degree: c.degree,
        knots: c.knots,
        control_points: points,
        weights: c.weights,
    })
}

/// Maps a knot-vector error to the key that caused it.
pub(super) fn knot_problem(
    section: &str,
    knots_key: &str,
    degree_key: &str,
    knots: &[f64],
    e: GeomError,
) -> Problem {
    let k = format!("{section}.{knots_key}");
    match e {
        GeomError::DegreeTooLow { degree } => Problem::new(
            format!("{section}.{degree_key}"),
            degree.to_string(),
            "the degree must be at least 1",
        ),
        GeomError::NonFiniteKnot { index, value } => {
            Problem::new(format!("{k}[{index}]"), format_f64(value), e.to_string())
        }
        GeomError::DecreasingKnots { index, value, .. } => {
            Problem::new(format!("{k}[{index}]"), format_f64(value), e.to_string())
        }
        other => Problem::new(k, fmt_list(knots), other.to_string()),
    }
}

/// Maps a control-net error to the key that caused it (`n_v` = points per row, 1 for curves).
pub(super) fn net_problem(section: &str, n_v: Option<usize>, e: GeomError) -> Problem {
    let at = |index: usize| match n_v {
        Some(n_v) if n_v > 0 => format!("[{}][{}]", index / n_v, index % n_v),
        _ => format!("[{index}]"),
    };
    match e {
        GeomError::InvalidWeight { index, value } => Problem::new(
            format!("{section}.weights{}", at(index)),
            format_f64(value),
            e.to_string(),
        ),
        GeomError::NonFiniteControlPoint { index, value } => Problem::new(
            format!("{section}.control_points{}", at(index)),
            format_f64(value),
            e.to_string(),
        ),
        GeomError::WeightCount { found, .. } => Problem::new(
            format!("{section}.weights"),
            format!("{found} values"),
            e.to_string(),
        ),
        GeomError::ControlPointCount { found, .. } => Problem::new(
            format!("{section}.control_points"),
            format!("{found} points"),
            e.to_string(),
        ),
        other => Problem::new(section.to_string(), "", other.to_string()),
    }
}

/// Builds the surface through `nurbspring-geom`, mapping its errors to key paths.
pub(crate) fn build_surface(s: &SurfaceSpec) -> Result<NurbsSurface, Problem> {
    let ku = KnotVector::try_new(s.knots_u.clone(), s.degree_u)
        .map_err(|e| knot_problem("surface", "knots_u", "degree_u", &s.knots_u, e))?;
    let kv = KnotVector::try_new(s.knots_v.clone(), s.degree_v)
        .map_err(|e| knot_problem("surface", "knots_v", "degree_v", &s.knots_v, e))?;
    if let Some(w) = &s.weights
        && let Some((i, row)) = w.iter().enumerate().find(|(_, r)| r.len() != s.n_v())
    {
        return Err(Problem::new(
            format!("surface.weights[{i}]"),
            format!("{} values", row.len()),
            format!(
                "every row of weights must have {} values, like control_points",
                s.n_v()
            ),
        ));
    }
    if let Some((i, row)) = s
        .control_points
        .iter()
        .enumerate()
        .find(|(_, r)| r.len() != s.n_v())
    {
        return Err(Problem::new(
            format!("surface.control_points[{i}]"),
            format!("{} points", row.len()),
            format!("every row must have {} points, like row 0", s.n_v()),
        ));
    }
    NurbsSurface::try_new(ku, kv, s.flat_control_points(), s.flat_weights())
        .map_err(|e| net_problem("surface", Some(s.n_v()), e))
}

/// Builds the curve through `nurbspring-geom`, mapping its errors to key paths.
pub(crate) fn build_curve(c: &CurveSpec) -> Result<NurbsCurve, Problem> {
    let kv = KnotVector::try_new(c.knots.clone(), c.degree)
        .map_err(|e| knot_problem("curve", "knots", "degree", &c.knots, e))?;
    NurbsCurve::try_new(kv, c.control_points.clone(), c.flat_weights())
        .map_err(|e| net_problem("curve", None, e))
}

pub(super) fn surface_info(s: &SurfaceSpec, p: &mut Problems) -> Option<GeomInfo> {
    match build_surface(s) {
        Ok(surface) => Some(GeomInfo {
            surface: true,
            n_u: s.n_u(),
            n_v: s.n_v(),
            domain_u: surface.basis_u().knots().domain(),
            domain_v: surface.basis_v().knots().domain(),
            geometry: Geometry::Surface(surface),
        }),
        Err(problem) => {
            p.0.push(problem);
            None
        }
    }
}

pub(super) fn curve_info(c: &CurveSpec, p: &mut Problems) -> Option<GeomInfo> {
    match build_curve(c) {
        Ok(curve) => Some(GeomInfo {
            surface: false,
            n_u: c.control_points.len(),
            n_v: 1,
            domain_u: curve.basis().knots().domain(),
            domain_v: (0.0, 0.0),
            geometry: Geometry::Curve(curve),
        }),
        Err(problem) => {
            p.0.push(problem);
            None
        }
    }
}
