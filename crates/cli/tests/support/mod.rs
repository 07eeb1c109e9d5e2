//! Helpers shared by the CLI's test files.

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
