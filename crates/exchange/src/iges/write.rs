//! Writing IGES files.

use nurbspring_geom::{NurbsCurve, NurbsSurface};

use crate::Shape;
use crate::fmt::iges_real;

/// Global-section values of a written file.
#[derive(Clone, Debug, PartialEq)]
pub struct WriteOptions {
    /// Global 3 and 12: product identification.
    pub product_id: String,
    /// Global 4: file name.
    pub file_name: String,
    /// Global 21: author.
    pub author: String,
    /// Global 22: organization.
    pub organization: String,
    /// Global 14: units flag (2 = millimetres; see [`super::Global::units_flag`]).
    pub units_flag: i64,
    /// Global 15: units name (`MM`, `IN`, `M`, …).
    pub units_name: String,
    /// Global 13: model space scale.
    pub model_scale: f64,
    /// Global 18 and 25: date and time, `YYYYMMDD.HHNNSS`. Fixed by default so that a file's
    /// bytes depend on its shapes only.
    pub timestamp: String,
    /// Lines of the Start section (free text; longer lines continue on the next record).
    pub start: Vec<String>,
}

impl Default for WriteOptions {
    fn default() -> Self {
        WriteOptions {
            product_id: "nurbspring".into(),
            file_name: String::new(),
            author: String::new(),
            organization: String::new(),
            units_flag: 2,
            units_name: "MM".into(),
            model_scale: 1.0,
            timestamp: "20000101.000000".into(),
            start: vec![
                "nurbspring-exchange: rational B-spline curves (126) and surfaces (128)".into(),
            ],
        }
    }
}

/// Writes shapes as an IGES 5.3 file with [`WriteOptions::default`]: one independent entity 126
/// per curve and 128 per surface, in order.
///
/// ```
/// use nurbspring_exchange::{Shape, iges};
/// use nurbspring_geom::{KnotVector, NurbsSurface};
/// let k = KnotVector::try_new(vec![0., 0., 1., 1.], 1).unwrap();
/// let s = NurbsSurface::try_new(k.clone(), k,
///     vec![[0., 0., 0.], [0., 1., 0.], [1., 0., 0.], [1., 1., 1.]], vec![1.0, 1.0, 1.0, 2.0]).unwrap();
/// let text = iges::write(&[Shape::Surface(s.clone())]);
/// assert!(text.lines().nth(4).unwrap().starts_with("     128       1"));
/// assert_eq!(iges::read(&text).unwrap().shapes, [Shape::Surface(s)]);
/// ```
pub fn write(shapes: &[Shape]) -> String {
    write_with(shapes, &WriteOptions::default())
}

/// Writes shapes as an IGES 5.3 file with the given Global-section values.
pub fn write_with(shapes: &[Shape], options: &WriteOptions) -> String {
    let mut out = String::new();
    // Start section.
    // Start section: each line of text in pieces of 72 columns.
    let mut start_lines: Vec<String> = Vec::new();
    for l in &options.start {
        let chars: Vec<char> = sanitize(l).chars().collect();
        if chars.is_empty() {
            start_lines.push(String::new());
        }
        start_lines.extend(chars.chunks(72).map(|c| c.iter().collect::<String>()));
    }
    if start_lines.is_empty() {
        start_lines.push(String::new());
    }
    for (i, l) in start_lines.iter().enumerate() {
        out.push_str(&format!("{l:<72}S{:07}\n", i + 1));
    }
    // Global section.
    let max_coordinate = shapes
        .iter()
        .flat_map(|s| match s {
            Shape::Curve(c) => c.control_points(),
            Shape::Surface(s) => s.control_points(),
        })
        .flat_map(|p| p.iter().map(|x| x.abs()))
        .fold(0.0_f64, f64::max);
    let global = vec![
        hollerith(","),
        hollerith(";"),
        hollerith(&options.product_id),
        hollerith(&options.file_name),
        hollerith("nurbspring"),
        hollerith("nurbspring-exchange"),
        "32".into(),
        "308".into(),
        "15".into(),
        "308".into(),
        "15".into(),
        hollerith(&options.product_id),
        iges_real(options.model_scale),
        options.units_flag.to_string(),
        hollerith(&options.units_name),
        "1".into(),
        iges_real(0.01),
        hollerith(&options.timestamp),
        iges_real(1e-7),
        iges_real(max_coordinate),
        hollerith(&options.author),
        hollerith(&options.organization),
        "11".into(),
        "0".into(),
        hollerith(&options.timestamp),
    ];
    let global_lines = pack(&global, 72);
    for (i, l) in global_lines.iter().enumerate() {
        out.push_str(&format!("{l:<72}G{:07}\n", i + 1));
    }
    // Parameter data first (the Directory Entries need its line numbers).
    let mut directory = String::new();
    let mut parameter = String::new();
    let mut p_line = 1;
    for (e, shape) in shapes.iter().enumerate() {
        let de = 2 * e + 1;
        let (entity_type, params) = match shape {
            Shape::Curve(c) => (126, curve_params(c)),
            Shape::Surface(s) => (128, surface_params(s)),
        };
        let lines = pack(&params, 64);
        for (i, l) in lines.iter().enumerate() {
            parameter.push_str(&format!("{l:<64} {de:07}P{:07}\n", p_line + i));
        }
        directory.push_str(&format!(
            "{entity_type:>8}{p_line:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}D{de:07}\n",
            0, 0, 0, 0, 0, 0, "00000000"
        ));
        directory.push_str(&format!(
            "{entity_type:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}D{:07}\n",
            0,
            0,
            lines.len(),
            0,
            "",
            "",
            "",
            0,
            de + 1
        ));
        p_line += lines.len();
    }
    out.push_str(&directory);
    out.push_str(&parameter);
    let tail = format!(
        "S{:>7}G{:>7}D{:>7}P{:>7}",
        start_lines.len(),
        global_lines.len(),
        2 * shapes.len(),
        p_line - 1
    );
    out.push_str(&format!("{tail:<72}T{:07}\n", 1));
    out
}

/// Printable ASCII only: IGES files are ASCII and a line break would break the record layout.
fn sanitize(s: &str) -> String {
    s.chars()
        .map(|c| {
            if c.is_ascii_graphic() || c == ' ' {
                c
            } else {
                '?'
            }
        })
        .collect()
}

fn hollerith(s: &str) -> String {
    let s = sanitize(s);
    if s.is_empty() {
        String::new()
    } else {
        format!("{}H{s}", s.len())
    }
}

/// Free-format parameters `a,b,…;` packed into lines of `width` columns. Numbers never split;
/// a Hollerith string longer than a line continues on the next.
fn pack(params: &[String], width: usize) -> Vec<String> {
    let mut lines = Vec::new();
    let mut line = String::new();
    for (i, p) in params.iter().enumerate() {
        let delim = if i + 1 == params.len() { ';' } else { ',' };
        let token = format!("{p}{delim}");
        if line.len() + token.len() <= width {
            line.push_str(&token);
            continue;
        }
        if token.len() <= width {
            lines.push(std::mem::take(&mut line));
            line = token;
            continue;
        }
        // A long string: fill the line, continue on the next ones.
        for c in token.chars() {
            if line.len() == width {
                lines.push(std::mem::take(&mut line));
            }
            line.push(c);
        }
    }
    if !line.is_empty() || lines.is_empty() {
        lines.push(line);
    }
    lines
}

fn reals<'a>(out: &mut Vec<String>, values: impl IntoIterator<Item = &'a f64>) {
    out.extend(values.into_iter().map(|&x| iges_real(x)));
}

/// The unit normal of the plane through all `points`, if they are coplanar (to 1e-12 of their
/// extent). Collinear points lie in many planes: one is chosen.
fn plane_normal(points: &[[f64; 3]]) -> Option<[f64; 3]> {
    let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let p0 = *points.first()?;
    let far = points
        .iter()
        .map(|&p| sub(p, p0))
        .max_by(|a, b| dot(*a, *a).total_cmp(&dot(*b, *b)))?;
    let extent = dot(far, far).sqrt();
    if !extent.is_finite() {
        return None;
    }
    if extent == 0.0 {
        return Some([0.0, 0.0, 1.0]);
    }
    let d = far.map(|x| x / extent);
    let n = points
        .iter()
        .map(|&p| cross(d, sub(p, p0)))
        .max_by(|a, b| dot(*a, *a).total_cmp(&dot(*b, *b)))?;
    let len = dot(n, n).sqrt();
    let n = if len <= 1e-12 * extent {
        // Collinear: any normal of the line.
        let a = if d[0].abs() < 0.9 {
            [1.0, 0.0, 0.0]
        } else {
            [0.0, 1.0, 0.0]
        };
        let n = cross(d, a);
        let l = dot(n, n).sqrt();
        n.map(|x| x / l)
    } else {
        n.map(|x| x / len)
    };
    points
        .iter()
        .all(|&p| dot(n, sub(p, p0)).abs() <= 1e-12 * extent)
        .then_some(n)
}

fn curve_params(c: &NurbsCurve) -> Vec<String> {
    let k = c.basis().knots();
    let pts = c.control_points();
    let w = c.weights();
    let normal = plane_normal(pts);
    let closed = pts.first() == pts.last();
    let polynomial = w.iter().all(|&x| x == w[0]);
    let mut out = vec![
        "126".to_string(),
        (pts.len() - 1).to_string(),
        k.degree().to_string(),
        u8::from(normal.is_some()).to_string(),
        u8::from(closed).to_string(),
        u8::from(polynomial).to_string(),
        "0".into(),
    ];
    reals(&mut out, k.knots());
    reals(&mut out, w);
    reals(&mut out, pts.iter().flatten());
    let (a, b) = k.domain();
    reals(&mut out, &[a, b]);
    reals(&mut out, &normal.unwrap_or([0.0; 3]));
    out
}

fn surface_params(s: &NurbsSurface) -> Vec<String> {
    let (ku, kv) = (s.basis_u().knots(), s.basis_v().knots());
    let (nu, nv) = (s.n_u(), s.n_v());
    let pts = s.control_points();
    let w = s.weights();
    let closed_u = (0..nv).all(|j| pts[j] == pts[(nu - 1) * nv + j]);
    let closed_v = (0..nu).all(|i| pts[i * nv] == pts[i * nv + nv - 1]);
    let polynomial = w.iter().all(|&x| x == w[0]);
    let mut out = vec![
        "128".to_string(),
        (nu - 1).to_string(),
        (nv - 1).to_string(),
        ku.degree().to_string(),
        kv.degree().to_string(),
        u8::from(closed_u).to_string(),
        u8::from(closed_v).to_string(),
        u8::from(polynomial).to_string(),
        "0".into(),
        "0".into(),
    ];
    reals(&mut out, ku.knots());
    reals(&mut out, kv.knots());
    // IGES order: first (u) index fastest.
    let order: Vec<usize> = (0..nv)
        .flat_map(|j| (0..nu).map(move |i| i * nv + j))
        .collect();
    reals(&mut out, order.iter().map(|&k| &w[k]));
    reals(&mut out, order.iter().flat_map(|&k| pts[k].iter()));
    let ((u0, u1), (v0, v1)) = s.domain();
    reals(&mut out, &[u0, u1, v0, v1]);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn packing_keeps_numbers_whole_and_splits_long_strings() {
        let p: Vec<String> = (0..30).map(|i| format!("{i}.5")).collect();
        let lines = pack(&p, 64);
        assert!(lines.iter().all(|l| l.len() <= 64));
        assert_eq!(lines.concat(), p.join(",") + ";");
        let long = vec![hollerith(&"x".repeat(100)), "1".into()];
        let lines = pack(&long, 72);
        assert_eq!(lines.len(), 2);
        assert_eq!(lines.concat(), format!("100H{},1;", "x".repeat(100)));
    }

    #[test]
    fn planarity() {
        assert_eq!(
            plane_normal(&[[0., 0., 2.], [1., 0., 2.], [1., 1., 2.], [5., -3., 2.]]),
            Some([0.0, 0.0, 1.0])
        );
        assert!(plane_normal(&[[0., 0., 0.], [1., 0., 0.], [0., 1., 0.], [0., 0., 1.]]).is_none());
        assert!(plane_normal(&[[0., 0., 0.], [1., 1., 1.]]).is_some());
    }
}
