//! Helpers shared by the CLI's test files (each file uses some of them).
#![allow(dead_code)]

use std::path::{Path, PathBuf};

use assert_cmd::Command;

/// The binary, quiet.
pub fn bin() -> Command {
    let mut c = Command::cargo_bin("nurbspring").unwrap();
    c.arg("--quiet");
    c
}

/// The repository's root.
pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The examples folder.
pub fn examples() -> PathBuf {
    root().join("examples")
}

/// A command's stderr as text.
pub fn stderr_of(a: &assert_cmd::assert::Assert) -> String {
    String::from_utf8_lossy(&a.get_output().stderr).into_owned()
}

/// An example scene.
pub fn example(name: &str) -> PathBuf {
    examples().join(name)
}

/// The paper's scene.
pub fn paper() -> PathBuf {
    examples().join("paper.toml")
}

/// stdout parsed as JSON.
pub fn json_of(out: &[u8]) -> serde_json::Value {
    serde_json::from_slice(out)
        .unwrap_or_else(|e| panic!("not JSON ({e}): {}", String::from_utf8_lossy(out)))
}

/// A scene written to a temp folder.
pub fn scene(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// The path of the first null in `v`, if any.
pub fn null_in(v: &serde_json::Value, path: &str) -> Option<String> {
    match v {
        serde_json::Value::Null => Some(path.to_string()),
        serde_json::Value::Array(items) => items
            .iter()
            .enumerate()
            .find_map(|(i, x)| null_in(x, &format!("{path}[{i}]"))),
        serde_json::Value::Object(map) => map
            .iter()
            .find_map(|(k, x)| null_in(x, &format!("{path}.{k}"))),
        _ => None,
    }
}

/// The rows of a CSV file of `dir` after its header (checked when given).
pub fn csv_rows(dir: &Path, file: &str, header: Option<&str>) -> Vec<Vec<f64>> {
    let text = std::fs::read_to_string(dir.join(file)).unwrap();
    let mut lines = text.lines();
    let first = lines.next().unwrap();
    if let Some(h) = header {
        assert_eq!(first, h, "{file}");
    }
    lines
        .map(|l| l.split(',').map(|x| x.parse::<f64>().unwrap()).collect())
        .collect()
}
