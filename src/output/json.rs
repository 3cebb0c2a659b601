//! JSON documents (`meter --json`, `lights --json`, illuminance maps): the only module that
//! names serde_json. Non-finite numbers are written as `null`.

use crate::error::{Error, Result};
use serde::Serialize;

/// `value` as indented JSON with a final newline.
pub fn pretty<T: Serialize>(value: &T) -> Result<String> {
    serde_json::to_string_pretty(value)
        .map(|s| s + "\n")
        .map_err(|e| Error::resource(format!("cannot write JSON: {e}")))
}

/// `value` as JSON on one line with a final newline (a document per command, for pipes).
pub fn compact<T: Serialize>(value: &T) -> Result<String> {
    serde_json::to_string(value)
        .map(|s| s + "\n")
        .map_err(|e| Error::resource(format!("cannot write JSON: {e}")))
}

/// `text` read as a `T` (a meter part, `meter --part`); the reason when it is not one.
pub fn parse<T: serde::de::DeserializeOwned>(text: &str) -> std::result::Result<T, String> {
    serde_json::from_str(text).map_err(|e| e.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn non_finite_numbers_are_null() {
        #[derive(Serialize)]
        struct T {
            a: f64,
            b: Option<f64>,
            c: [f64; 2],
        }
        let t = T {
            a: f64::NAN,
            b: None,
            c: [1.5, f64::INFINITY],
        };
        let s = pretty(&t).unwrap();
        let v: serde_json::Value = serde_json::from_str(&s).unwrap();
        assert_eq!(
            v,
            serde_json::json!({"a": null, "b": null, "c": [1.5, null]})
        );
    }
}
