//! The scenario the page sends with `set_scenario`: a JSON object of the scenario's fields
//! (weather timeline, Table 2 parameters of Cordonnier et al. 2018), read into a validated
//! [`Scenario`].
//!
//! serde reads a struct from a JSON array too (its fields by position, the missing ones from
//! their defaults), so `[]` or `{"parameters": [1, 2]}` would pass as a scenario. Here every
//! value that the scenario holds as an object must be a JSON object in the page's message;
//! anything else is refused with [`ErrorCode::InvalidValue`] naming where and what it got.

use crate::protocol::ErrorCode;
use crate::session::Refusal;
use serde_json::Value;
use snowscape_season::scenario::Scenario;

/// The JSON kind of a value, in words.
fn kind(v: &Value) -> &'static str {
    match v {
        Value::Null => "null",
        Value::Bool(_) => "a boolean",
        Value::Number(_) => "a number",
        Value::String(_) => "a string",
        Value::Array(_) => "an array",
        Value::Object(_) => "an object",
    }
}

/// The first place (a path like `scenario.parameters`) where `input` holds an array while the
/// scenario read from it holds an object there, with what it got.
fn array_read_as_object(input: &Value, read: &Value, path: &str) -> Option<String> {
    match (input, read) {
        (Value::Object(a), Value::Object(b)) => a.iter().find_map(|(k, v)| {
            b.get(k)
                .and_then(|w| array_read_as_object(v, w, &format!("{path}.{k}")))
        }),
        (Value::Array(a), Value::Array(b)) => a
            .iter()
            .zip(b)
            .enumerate()
            .find_map(|(i, (v, w))| array_read_as_object(v, w, &format!("{path}[{i}]"))),
        (Value::Array(_), Value::Object(_)) => Some(path.to_string()),
        _ => None,
    }
}

fn invalid(message: String) -> Refusal {
    (ErrorCode::InvalidValue, message)
}

/// Reads and validates the page's scenario; a refusal names the problem.
pub fn read_scenario(value: Value) -> Result<Scenario, Refusal> {
    if !value.is_object() {
        return Err(invalid(format!(
            "the scenario must be a JSON object of its fields (days, weather, parameters, ...), got {}",
            kind(&value)
        )));
    }
    let array_at = |path: String| {
        invalid(format!(
            "{path} must be a JSON object of its fields, got an array"
        ))
    };
    // Against the default scenario first (before serde's own, positional, complaints), then
    // against what was read (the elements of lists the default leaves empty).
    let shape = serde_json::to_value(Scenario::default()).unwrap_or_default();
    if let Some(path) = array_read_as_object(&value, &shape, "scenario") {
        return Err(array_at(path));
    }
    let scenario: Scenario = serde_json::from_value(value.clone())
        .map_err(|e| invalid(format!("invalid scenario: {e}")))?;
    let read =
        serde_json::to_value(&scenario).map_err(|e| invalid(format!("invalid scenario: {e}")))?;
    if let Some(path) = array_read_as_object(&value, &read, "scenario") {
        return Err(array_at(path));
    }
    scenario
        .validate("the page")
        .map_err(|e| invalid(e.to_string()))?;
    Ok(scenario)
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn only_objects_are_scenarios() {
        // serde alone takes an array for the scenario (its fields by position).
        assert!(serde_json::from_value::<Scenario>(json!([])).is_ok());
        let good = serde_json::to_value(Scenario::default()).unwrap();
        assert!(read_scenario(good.clone()).is_ok());
        for bad in [
            json!([]),
            json!([1, 2]),
            json!(null),
            json!(3),
            json!("days"),
        ] {
            let (code, message) = read_scenario(bad.clone()).unwrap_err();
            assert_eq!(code, ErrorCode::InvalidValue);
            assert!(message.contains("must be a JSON object"), "{message}");
            assert!(message.contains(kind(&bad)), "{message}");
        }
        let mut nested = good;
        nested["parameters"] = json!([]);
        let (_, message) = read_scenario(nested).unwrap_err();
        assert!(message.contains("scenario.parameters"), "{message}");
    }
}
