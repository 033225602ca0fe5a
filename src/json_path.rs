//! Reading a part of a JSON body (a `serde_json::Value` taken out of it)
//! into a type, with an error that names the failing field's path, as
//! `axum`'s extractor does for a whole body. The path's bookkeeping
//! (`serde_path_to_error`) slows every parse, so a value is read plainly
//! and only one that fails is read again, for its message.

use serde::de::DeserializeOwned;

/// `value` read as a `T`; else a message that starts with the failing
/// field's path under `prefix` (`scenario.obstacles[1].kind: invalid
/// type…`; `prefix` empty for a body's own fields).
///
/// # Errors
/// The message, when `value` is not a `T`.
pub fn from_value<T: DeserializeOwned>(
    value: &serde_json::Value,
    prefix: &str,
) -> Result<T, String> {
    T::deserialize(value).map_err(|plain| {
        let (path, inner) = match serde_path_to_error::deserialize::<_, T>(value) {
            Err(e) => (e.path().to_string(), e.inner().to_string()),
            // Not expected: both read the same value with the same serde.
            Ok(_) => (String::new(), plain.to_string()),
        };
        let path = if path == "." { "" } else { path.as_str() };
        match (prefix, path) {
            ("", "") => inner,
            ("", path) => format!("{path}: {inner}"),
            (prefix, "") => format!("{prefix}: {inner}"),
            (prefix, path) if path.starts_with('[') => format!("{prefix}{path}: {inner}"),
            (prefix, path) => format!("{prefix}.{path}: {inner}"),
        }
    })
}

#[cfg(test)]
mod tests {
    use super::from_value;
    use serde_json::json;

    #[derive(Debug, serde::Deserialize)]
    #[allow(dead_code)]
    struct Cell {
        col: i32,
    }

    #[test]
    fn the_message_names_the_path_under_the_prefix() {
        let bad = json!([{"col": 1}, {"col": "6"}]);
        let e = from_value::<Vec<Cell>>(&bad, "paths").unwrap_err();
        assert!(e.starts_with("paths[1].col: invalid type"), "{e}");
        let e = from_value::<Cell>(&json!({"col": "6"}), "").unwrap_err();
        assert!(e.starts_with("col: invalid type"), "{e}");
        let e = from_value::<Cell>(&json!({"col": 1.5}), "scenario").unwrap_err();
        assert!(e.starts_with("scenario.col: invalid type"), "{e}");
        let e = from_value::<Cell>(&json!(3), "scenario").unwrap_err();
        assert!(e.starts_with("scenario: invalid type"), "{e}");
        assert_eq!(from_value::<Cell>(&json!({"col": 4}), "").unwrap().col, 4);
    }
}
