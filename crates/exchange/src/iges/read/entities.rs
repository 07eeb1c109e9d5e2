//! The entities read: 126 (rational B-spline curve) and 128 (rational B-spline surface), their degrees, knots and weights checked.

use super::*;

/// Converts a count parameter pair (upper index K, degree M) and checks `K ≥ M ≥ 1`.
pub(super) fn index_and_degree(
    p: &Params,
    k_param: usize,
    k_name: &str,
    m_param: usize,
    m_name: &str,
) -> Result<(usize, usize), ExchangeError> {
    let k = p.count(k_param, k_name)?;
    let m = p.count(m_param, m_name)?;
    if m < 1 {
        return Err(ExchangeError::KnotCount {
            at: p.at(m_param),
            detail: format!(
                "{} is 0; nurbspring B-splines have degree 1 or more",
                p.what(m_param, m_name)
            ),
        });
    }
    if k < m {
        return Err(ExchangeError::KnotCount {
            at: p.at(k_param),
            detail: format!(
                "{k_name} = {k} gives {} control points, fewer than degree {m_name} + 1 = {} \
                 (N = 1 + {k_name} − {m_name} must be at least 1)",
                k as u128 + 1,
                m as u128 + 1
            ),
        });
    }
    Ok((k, m))
}

/// Checks that the record holds at least `needed` parameters for the counts it declares.
pub(super) fn check_length(
    p: &Params,
    needed: u128,
    detail: impl FnOnce() -> String,
) -> Result<(), ExchangeError> {
    if (p.len() as u128) < needed {
        return Err(ExchangeError::KnotCount {
            at: p.at(p.list.len()),
            detail: format!(
                "{} has {} parameters after its type number, but {} (it ends at this line)",
                p.entry.describe(),
                p.len(),
                detail()
            ),
        });
    }
    Ok(())
}

pub(super) fn knots(
    p: &Params,
    first: usize,
    count: usize,
    name: &str,
) -> Result<Vec<f64>, ExchangeError> {
    (0..count)
        .map(|i| p.real(first + i, &format!("knot {name}({i})")))
        .collect()
}

pub(super) fn weight(p: &Params, k: usize, index: usize, name: &str) -> Result<f64, ExchangeError> {
    let w = p.real(k, name)?;
    if w > 0.0 {
        Ok(w)
    } else {
        Err(ExchangeError::InvalidWeight {
            at: p.at(k),
            index,
            value: w,
        })
    }
}

pub(super) fn knot_vector(
    p: &Params,
    first: usize,
    knots: Vec<f64>,
    degree: usize,
) -> Result<KnotVector, ExchangeError> {
    KnotVector::try_new(knots, degree).map_err(|source| ExchangeError::Geometry {
        at: p.at(first),
        source,
    })
}

pub(super) fn read_126(
    p: &Params,
    info: &mut EntityInfo,
    notes: &mut Vec<String>,
) -> Result<Shape, ExchangeError> {
    let (k, m) = index_and_degree(p, 1, "K", 2, "M")?;
    let props: Vec<i64> = (3..=6)
        .map(|i| p.int(i, &format!("PROP{}", i - 2)))
        .collect::<Result<_, _>>()?;
    let n = k as u128 + 1;
    let n_knots = k as u128 + m as u128 + 2;
    check_length(p, 6 + n_knots + 4 * n, || {
        format!(
            "K = {k} and M = {m} need {} (6 flags, K + M + 2 = {n_knots} knots, K + 1 = {n} \
             weights, 3 (K + 1) = {} coordinates)",
            6 + n_knots + 4 * n,
            3 * n
        )
    })?;
    let (n, n_knots) = (n as usize, n_knots as usize);
    let t0 = 7;
    let kv = knots(p, t0, n_knots, "T")?;
    let w0 = t0 + n_knots;
    let weights: Vec<f64> = (0..n)
        .map(|i| weight(p, w0 + i, i, &format!("weight W({i})")))
        .collect::<Result<_, _>>()?;
    let x0 = w0 + n;
    let mut points = Vec::with_capacity(n);
    for i in 0..n {
        let mut xyz = [0.0; 3];
        for (c, name) in ["X", "Y", "Z"].iter().enumerate() {
            xyz[c] = p.real(x0 + 3 * i + c, &format!("{name}({i})"))?;
        }
        points.push(xyz);
    }
    let r0 = x0 + 3 * n;
    let knots_v = knot_vector(p, t0, kv, m)?;
    let domain = knots_v.domain();
    let range = (
        p.real_or(r0, "V(0)", domain.0)?,
        p.real_or(r0 + 1, "V(1)", domain.1)?,
    );
    if props[0] == 1 {
        info.normal = Some([
            p.real_or(r0 + 2, "XNORM", 0.0)?,
            p.real_or(r0 + 3, "YNORM", 0.0)?,
            p.real_or(r0 + 4, "ZNORM", 0.0)?,
        ]);
    }
    info.properties = props;
    info.u_range = range;
    if range != domain {
        notes.push(format!(
            "{}: its parameter range [{}, {}] differs from its knot domain [{}, {}]; the whole \
             curve is imported (the range is in EntityInfo::u_range)",
            p.entry.describe(),
            range.0,
            range.1,
            domain.0,
            domain.1
        ));
    }
    let curve = NurbsCurve::try_new(knots_v, points, weights).map_err(|source| {
        ExchangeError::Geometry {
            at: p.entry.at(),
            source,
        }
    })?;
    Ok(Shape::Curve(curve))
}

pub(super) fn read_128(
    p: &Params,
    info: &mut EntityInfo,
    notes: &mut Vec<String>,
) -> Result<Shape, ExchangeError> {
    let (k1, m1) = index_and_degree(p, 1, "K1", 3, "M1")?;
    let (k2, m2) = index_and_degree(p, 2, "K2", 4, "M2")?;
    let props: Vec<i64> = (5..=9)
        .map(|i| p.int(i, &format!("PROP{}", i - 4)))
        .collect::<Result<_, _>>()?;
    let (nu, nv) = (k1 as u128 + 1, k2 as u128 + 1);
    let (a, b) = (k1 as u128 + m1 as u128 + 2, k2 as u128 + m2 as u128 + 2);
    // At most (2^63)^2: u128 holds it; the sums saturate rather than overflow.
    let c = nu * nv;
    let needed = c.saturating_mul(4).saturating_add(9 + a + b);
    check_length(p, needed, || {
        format!(
            "K1 = {k1}, K2 = {k2}, M1 = {m1}, M2 = {m2} need {} (9 flags, K1 + M1 + 2 = {a} \
             knots S, K2 + M2 + 2 = {b} knots T, (K1 + 1)(K2 + 1) = {c} weights and 3 × {c} \
             coordinates)",
            needed
        )
    })?;
    let (nu, nv, a, b, c) = (nu as usize, nv as usize, a as usize, b as usize, c as usize);
    let s0 = 10;
    let ks = knots(p, s0, a, "S")?;
    let t0 = s0 + a;
    let kt = knots(p, t0, b, "T")?;
    let w0 = t0 + b;
    let x0 = w0 + c;
    let mut weights = vec![0.0; c];
    let mut points = vec![[0.0; 3]; c];
    // IGES lists (i, j) with i (along u) fastest: position m = j·nu + i.
    for j in 0..nv {
        for i in 0..nu {
            let m = j * nu + i;
            let k = i * nv + j;
            weights[k] = weight(p, w0 + m, m, &format!("weight W({i},{j})"))?;
            for (d, name) in ["X", "Y", "Z"].iter().enumerate() {
                points[k][d] = p.real(x0 + 3 * m + d, &format!("{name}({i},{j})"))?;
            }
        }
    }
    let r0 = x0 + 3 * c;
    let ku = knot_vector(p, s0, ks, m1)?;
    let kv = knot_vector(p, t0, kt, m2)?;
    let (du, dv) = (ku.domain(), kv.domain());
    let ur = (
        p.real_or(r0, "U(0)", du.0)?,
        p.real_or(r0 + 1, "U(1)", du.1)?,
    );
    let vr = (
        p.real_or(r0 + 2, "V(0)", dv.0)?,
        p.real_or(r0 + 3, "V(1)", dv.1)?,
    );
    info.properties = props;
    info.u_range = ur;
    info.v_range = Some(vr);
    if ur != du || vr != dv {
        notes.push(format!(
            "{}: its parameter range [{}, {}] × [{}, {}] differs from its knot domain [{}, {}] × \
             [{}, {}]; the whole surface is imported (the range is in EntityInfo)",
            p.entry.describe(),
            ur.0,
            ur.1,
            vr.0,
            vr.1,
            du.0,
            du.1,
            dv.0,
            dv.1
        ));
    }
    let s = NurbsSurface::try_new(ku, kv, points, weights).map_err(|source| {
        ExchangeError::Geometry {
            at: p.entry.at(),
            source,
        }
    })?;
    Ok(Shape::Surface(s))
}
