//! JSON output (pretty-printed, trailing newline).

use std::path::Path;

use serde::Serialize;

use crate::OutputError;
use crate::atomic::write_atomic;

/// Writes `value` as pretty-printed JSON (two-space indent, trailing newline). Non-finite
/// floats become `null`, as serde_json does.
///
/// ```
/// # let dir = tempfile::tempdir().unwrap();
/// let path = dir.path().join("r.json");
/// nurbspring_io::output::write_json(&path, &serde_json::json!({ "k_edge": 2.7225 })).unwrap();
/// assert!(std::fs::read_to_string(&path).unwrap().contains("\"k_edge\": 2.7225"));
/// ```
pub fn write_json<T: Serialize + ?Sized>(
    path: impl AsRef<Path>,
    value: &T,
) -> Result<(), OutputError> {
    let path = path.as_ref();
    // Serialize first so that a serialization error is reported as such, and nothing is written.
    let mut bytes = serde_json::to_vec_pretty(value).map_err(|source| OutputError::Json {
        path: path.to_path_buf(),
        source,
    })?;
    bytes.push(b'\n');
    write_atomic(path, |w| w.write_all(&bytes))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Serialize, serde::Deserialize, PartialEq, Debug)]
    struct Report {
        name: String,
        values: Vec<f64>,
    }

    #[test]
    fn round_trips_exactly() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("r.json");
        let r = Report {
            name: "fit \"k\"".into(),
            values: vec![0.1, 1.0 / 3.0, -2.5e-300, 6.02e23],
        };
        write_json(&p, &r).unwrap();
        let text = std::fs::read_to_string(&p).unwrap();
        assert!(text.ends_with("}\n"));
        assert!(text.contains("\n  \"name\""));
        let back: Report = serde_json::from_str(&text).unwrap();
        assert_eq!(back, r);
    }
}
