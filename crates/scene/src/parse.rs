//! Turning toml's errors into [`SceneError::Parse`]: line and column from the byte span, the
//! table an unknown key appeared in, and the nearest valid key or value.

use std::path::Path;

use super::SceneError;

/// The keys of every table, to name the table an unknown key was found in (serde's message
/// lists the expected keys, which identify the table).
pub(crate) const TABLES: &[(&str, &[&str])] = &[
    (
        "",
        &[
            "surface",
            "curve",
            "material",
            "loads",
            "constraints",
            "dnurbs",
            "initial",
            "simulation",
            "msm",
            "fit",
            "output",
        ],
    ),
    (
        "surface",
        &[
            "file",
            "index",
            "degree_u",
            "degree_v",
            "knots_u",
            "knots_v",
            "control_points",
            "weights",
        ],
    ),
    (
        "curve",
        &[
            "file",
            "index",
            "degree",
            "knots",
            "control_points",
            "weights",
        ],
    ),
    (
        "material",
        &[
            "model",
            "mu",
            "gamma",
            "alpha11",
            "alpha22",
            "beta11",
            "beta12",
            "beta22",
            "young",
            "poisson",
            "thickness",
            "density",
        ],
    ),
    ("loads", &["gravity", "distributed", "point", "edge"]),
    ("loads.point", &["u", "v", "force"]),
    ("loads.edge", &["edge", "force", "moment"]),
    (
        "constraints",
        &[
            "fixed_rings",
            "fixed",
            "fixed_weights",
            "fixed_point_weights",
            "linear",
            "edge",
        ],
    ),
    ("constraints.edge", &["edge", "condition", "hold"]),
    ("constraints.linear", &["terms", "rhs"]),
    (
        "constraints.linear.terms",
        &["point", "component", "coefficient"],
    ),
    (
        "dnurbs",
        &[
            "weights_as_dofs",
            "quadrature_points",
            "integrate_over",
            "rest_shape",
        ],
    ),
    (
        "initial",
        &["velocity", "weight_velocity", "velocities", "displacement"],
    ),
    (
        "simulation",
        &[
            "dt",
            "t_end",
            "dnurbs_integrator",
            "msm_integrator",
            "save_every",
            "probes",
            "rho_infinity",
        ],
    ),
    (
        "msm",
        &[
            "grid",
            "nodes_u",
            "nodes_v",
            "structural",
            "shear",
            "bending",
            "k_edge",
            "k_diag",
            "k_bend",
            "mass",
            "damping",
            "pre_strain",
            "elements",
            "fixed",
        ],
    ),
    (
        "fit",
        &[
            "derivation",
            "dofs",
            "nonnegative",
            "method",
            "mass",
            "max_candidates",
            "mass_scan",
        ],
    ),
    ("output", &["vtk_every"]),
];

/// Optimal-string-alignment distance (Levenshtein with adjacent transpositions).
pub(crate) fn edit_distance(a: &str, b: &str) -> usize {
    let a: Vec<char> = a.chars().collect();
    let b: Vec<char> = b.chars().collect();
    let mut d = vec![vec![0usize; b.len() + 1]; a.len() + 1];
    for (i, row) in d.iter_mut().enumerate() {
        row[0] = i;
    }
    for j in 0..=b.len() {
        d[0][j] = j;
    }
    for i in 1..=a.len() {
        for j in 1..=b.len() {
            let cost = usize::from(a[i - 1] != b[j - 1]);
            d[i][j] = (d[i - 1][j] + 1)
                .min(d[i][j - 1] + 1)
                .min(d[i - 1][j - 1] + cost);
            if i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1] {
                d[i][j] = d[i][j].min(d[i - 2][j - 2] + 1);
            }
        }
    }
    d[a.len()][b.len()]
}

/// The candidate nearest to `word`, if it is close enough to be a plausible misspelling.
pub(crate) fn nearest<'a>(word: &str, candidates: &[&'a str]) -> Option<&'a str> {
    let lower = word.to_ascii_lowercase();
    candidates
        .iter()
        .map(|c| (edit_distance(&lower, c), *c))
        .filter(|&(d, c)| d <= (c.chars().count() / 3).max(2))
        .min_by_key(|&(d, _)| d)
        .map(|(_, c)| c)
}

/// 1-based line and column (in characters) of byte offset `at` in `text`.
pub(crate) fn line_column(text: &str, at: usize) -> (usize, usize) {
    let mut at = at.min(text.len());
    while !text.is_char_boundary(at) {
        at -= 1;
    }
    let before = &text[..at];
    let line = before.matches('\n').count() + 1;
    let line_start = before.rfind('\n').map_or(0, |k| k + 1);
    let column = text[line_start..at].chars().count() + 1;
    (line, column)
}

/// The backticked words of a serde message after `expected`.
fn expected_names(message: &str) -> Vec<String> {
    let Some(pos) = message.find("expected") else {
        return Vec::new();
    };
    message[pos..]
        .split('`')
        .skip(1)
        .step_by(2)
        .map(str::to_string)
        .collect()
}

/// The first backticked word of a message.
fn first_quoted(message: &str) -> Option<String> {
    message.split('`').nth(1).map(str::to_string)
}

/// Drops a `#` comment from a line (ignoring `#` inside quotes).
fn strip_comment(line: &str) -> &str {
    let mut in_string = None;
    for (k, c) in line.char_indices() {
        match (c, in_string) {
            ('"' | '\'', None) => in_string = Some(c),
            (q, Some(open)) if q == open => in_string = None,
            ('#', None) => return &line[..k],
            _ => {}
        }
    }
    line
}

/// Whether a line is a table header `[name]` / `[[name]]` (not a row of an array).
fn is_header(line: &str) -> bool {
    let t = line.trim();
    let Some(inner) = t.strip_prefix('[').and_then(|r| r.strip_suffix(']')) else {
        return false;
    };
    let inner = inner.trim_start_matches('[').trim_end_matches(']');
    inner.chars().any(|c| c.is_ascii_alphabetic() || c == '_')
        && inner
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.' | '"' | ' '))
}

/// The key whose value contains byte offset `at`: the last `key =` before it, searching back
/// to the enclosing table header (`dt = "x"` → `dt`; inside an inline table, its own key).
fn key_before(text: &str, at: usize) -> Option<String> {
    let mut at = at.min(text.len());
    while !text.is_char_boundary(at) {
        at -= 1;
    }
    let mut end = at;
    for _ in 0..10_000 {
        let start = text[..end].rfind('\n').map_or(0, |k| k + 1);
        let line = strip_comment(&text[start..end]);
        let full_end = text[start..].find('\n').map_or(text.len(), |k| start + k);
        if is_header(strip_comment(&text[start..full_end])) {
            return None;
        }
        if let Some(eq) = line.rfind('=') {
            let key: String = line[..eq]
                .trim_end()
                .trim_end_matches('"')
                .chars()
                .rev()
                .take_while(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.'))
                .collect::<Vec<_>>()
                .into_iter()
                .rev()
                .collect();
            if !key.is_empty() {
                return Some(key);
            }
        }
        if start == 0 {
            return None;
        }
        end = start - 1;
    }
    None
}

/// The table header (`[name]` or `[[name]]`) on the line containing byte offset `at`.
fn header_at(text: &str, at: usize) -> Option<String> {
    let at = at.min(text.len());
    let start = text[..at].rfind('\n').map_or(0, |k| k + 1);
    let line = strip_comment(&text[start..]).lines().next()?.trim();
    let name = line.strip_prefix('[')?.trim_start_matches('[');
    let name = name.split(']').next()?.trim();
    (!name.is_empty()).then(|| name.to_string())
}

/// Converts a toml deserialization error into [`SceneError::Parse`].
pub(crate) fn parse_error(path: &Path, text: &str, err: &toml::de::Error) -> SceneError {
    let raw = err.message().trim().to_string();
    let span = err.span();
    let (line, column) = span.as_ref().map_or((0, 0), |s| line_column(text, s.start));
    let mut suggestion = None;
    let message = if raw.starts_with("unknown field") {
        let key = first_quoted(&raw).unwrap_or_default();
        let expected = expected_names(&raw);
        let table = TABLES
            .iter()
            .find(|(_, keys)| {
                keys.len() == expected.len() && keys.iter().all(|k| expected.iter().any(|e| e == k))
            })
            .map(|(name, _)| *name);
        let candidates: Vec<&str> = expected.iter().map(String::as_str).collect();
        suggestion = nearest(&key, &candidates).map(str::to_string);
        let place = match table {
            Some("") => "at the top level (valid sections: surface, curve, material, loads, constraints, dnurbs, initial, simulation, msm, fit, output)".to_string(),
            Some(t) => format!("in [{t}]"),
            None => format!("(valid keys here: {})", expected.join(", ")),
        };
        format!("unknown key `{key}` {place}")
    } else if raw.starts_with("unknown variant") {
        let value = first_quoted(&raw).unwrap_or_default();
        let expected = expected_names(&raw);
        let candidates: Vec<&str> = expected.iter().map(String::as_str).collect();
        suggestion = nearest(&value, &candidates).map(str::to_string);
        let key = span
            .as_ref()
            .and_then(|s| key_before(text, s.start))
            .map(|k| format!(" for key `{k}`"))
            .unwrap_or_default();
        format!(
            "unknown value `{value}`{key} (expected one of: {})",
            expected.join(", ")
        )
    } else if raw.starts_with("missing field") {
        let key = first_quoted(&raw).unwrap_or_default();
        match span.as_ref().and_then(|s| header_at(text, s.start)) {
            Some(table) => format!("missing key `{key}` in [{table}]"),
            None => format!("missing key `{key}`"),
        }
    } else {
        let key = span
            .as_ref()
            .and_then(|s| key_before(text, s.start))
            .filter(|k| !raw.contains(&format!("`{k}`")))
            .map(|k| format!(" (key `{k}`)"))
            .unwrap_or_default();
        format!("{raw}{key}")
    };
    SceneError::Parse {
        path: path.to_path_buf(),
        message,
        line,
        column,
        suggestion,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn distances() {
        assert_eq!(edit_distance("bta11", "beta11"), 1);
        assert_eq!(edit_distance("beta11", "beta11"), 0);
        assert_eq!(edit_distance("mass", "msas"), 1);
        assert_eq!(edit_distance("", "abc"), 3);
        assert_eq!(
            nearest("bta11", &["beta11", "beta12", "mu"]),
            Some("beta11")
        );
        assert_eq!(nearest("kedge", &["k_edge", "k_diag"]), Some("k_edge"));
        assert_eq!(nearest("completely_else", &["mu", "gamma"]), None);
    }

    /// Every entry of [`TABLES`] must match serde's field list exactly, or unknown keys would
    /// not be attributed to their table.
    #[test]
    fn every_table_is_recognized() {
        let base = "[surface]\ndegree_u = 1\ndegree_v = 1\nknots_u = [0, 0, 1, 1]\nknots_v = [0, 0, 1, 1]\ncontrol_points = [[[0, 0, 0], [0, 1, 0]], [[1, 0, 0], [1, 1, 0]]]\n";
        for (table, _) in TABLES {
            let text = match *table {
                "" => format!("zzz_bogus = 1\n{base}"),
                "surface" => format!("{base}zzz_bogus = 1\n"),
                "curve" => "[curve]\ndegree = 1\nzzz_bogus = 1\n".to_string(),
                "loads.point" => format!("{base}[[loads.point]]\nu = 0.5\nzzz_bogus = 1\n"),
                "loads.edge" => format!("{base}[[loads.edge]]\nedge = \"u0\"\nzzz_bogus = 1\n"),
                "constraints.edge" => {
                    format!("{base}[[constraints.edge]]\nedge = \"u0\"\nzzz_bogus = 1\n")
                }
                "constraints.linear" => format!("{base}[[constraints.linear]]\nzzz_bogus = 1\n"),
                "constraints.linear.terms" => format!(
                    "{base}[[constraints.linear]]\nterms = [{{ point = [0, 0], zzz_bogus = 1 }}]\n"
                ),
                t => format!("{base}[{t}]\nzzz_bogus = 1\n"),
            };
            let err = crate::Scene::from_str(&text, "t.toml")
                .unwrap_err()
                .to_string();
            let want = if table.is_empty() {
                "unknown key `zzz_bogus` at the top level".to_string()
            } else {
                format!("unknown key `zzz_bogus` in [{table}]")
            };
            assert!(err.contains(&want), "{table}: {err}");
        }
    }

    #[test]
    fn keys_and_headers() {
        let t = "[a]\nx = 1\n[b.c]\nk = [\n  [1, 2],\n  [3, \"q\"],\n]\n";
        assert_eq!(key_before(t, t.find("\"q").unwrap()), Some("k".into()));
        assert_eq!(key_before(t, t.find("[b.c]").unwrap() + 1), None);
        assert_eq!(key_before(t, t.find('1').unwrap()), Some("x".into()));
        assert_eq!(header_at(t, t.find("[b.c]").unwrap()), Some("b.c".into()));
        assert!(is_header("[[loads.point]]  "));
        assert!(!is_header("  [[0.0, 1.0, 2.0]],"));
        let inline = "terms = [{ point = [1, 1], component = \"q\" }]";
        assert_eq!(
            key_before(inline, inline.find("\"q").unwrap()),
            Some("component".into())
        );
    }

    #[test]
    fn line_and_column() {
        let t = "a = 1\nbé = 2\n";
        assert_eq!(line_column(t, 0), (1, 1));
        assert_eq!(line_column(t, 6), (2, 1));
        assert_eq!(line_column(t, t.find('=').unwrap()), (1, 3));
        let second = t.rfind('=').unwrap();
        assert_eq!(line_column(t, second), (2, 4));
        assert_eq!(line_column(t, 10_000).0, 3);
    }
}
