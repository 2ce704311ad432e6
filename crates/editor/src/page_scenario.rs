//! The scenario the page sends with `set_scenario`: a JSON object of the scenario's fields
//! (weather timeline, Table 2 parameters of Cordonnier et al. 2018), read into a validated
//! [`Scenario`].
//!
//! serde reads a struct from a JSON array too (its fields by position, the missing ones from
//! their defaults), so `[]` or `{"parameters": [1, 2]}` would pass as a scenario. Here every
//! value that the scenario holds as an object must be a JSON object in the page's message;
//! anything else is refused with [`ErrorCode::InvalidValue`] naming where and what it got.
//!
//! **Paths.** A scenario names files relative to its own folder (`forcing`, the station
//! record). A path that would leave the project folder (absolute, with a root or a drive, with
//! `..`, or resolving through a symbolic link outside it) is refused with a
//! [`ScenarioPathError`] naming the key and the value ([`ErrorCode::BadPath`] to the page),
//! when the page sends the scenario, when a project is saved and when one is loaded.

use crate::project::{ProjectDir, ProjectError};
use crate::protocol::ErrorCode;
use crate::session::Refusal;
use serde_json::Value;
use snowscape_season::scenario::Scenario;
use std::path::{Component, Path};

/// A scenario path that leaves the project folder: the key, its value and why.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("scenario.{key} = {value:?} is refused: {reason}")]
pub struct ScenarioPathError {
    pub key: &'static str,
    pub value: String,
    pub reason: &'static str,
}

/// The scenario's paths, by key.
fn scenario_paths(s: &Scenario) -> Vec<(&'static str, &Path)> {
    s.forcing.iter().map(|p| ("forcing", p.as_path())).collect()
}

/// Refuses any path of `scenario` that leaves the project folder: absolute paths, `..` and
/// roots always; with `within = Some((project, folder))` also paths that, taken relative to
/// `folder` of the project (where the scenario file lives), resolve through a symbolic link
/// outside the project folder.
pub fn check_scenario_paths(
    scenario: &Scenario,
    within: Option<(&ProjectDir, &str)>,
) -> Result<(), ScenarioPathError> {
    for (key, path) in scenario_paths(scenario) {
        let value: String = path.to_string_lossy().chars().take(200).collect();
        let err = |reason| ScenarioPathError {
            key,
            value: value.clone(),
            reason,
        };
        let text = path.to_string_lossy();
        if path.is_absolute()
            || path.has_root()
            || text.starts_with('/')
            || text.starts_with('\\')
            || text.get(1..2) == Some(":")
        {
            return Err(err(
                "an absolute path; name a file relative to the scenario, inside the project folder",
            ));
        }
        if text.is_empty() || text.contains('\0') || text.contains('\\') {
            return Err(err("not a relative path of the project folder"));
        }
        if !path
            .components()
            .all(|c| matches!(c, Component::Normal(_) | Component::CurDir))
        {
            return Err(err("'..' would leave the scenario's folder"));
        }
        if let Some((project, folder)) = within {
            let rel: Vec<String> = path
                .components()
                .filter_map(|c| match c {
                    Component::Normal(n) => Some(n.to_string_lossy().into_owned()),
                    _ => None,
                })
                .collect();
            let rel = if folder.is_empty() {
                rel.join("/")
            } else {
                format!("{folder}/{}", rel.join("/"))
            };
            match project.resolve(&rel) {
                Ok(_) => {}
                Err(ProjectError::Escapes(_)) => {
                    return Err(err(
                        "it resolves through a symbolic link outside the project folder",
                    ));
                }
                Err(_) => return Err(err("not a path inside the project folder")),
            }
        }
    }
    Ok(())
}

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

/// Reads and validates the page's scenario; a refusal names the problem. With the project
/// folder, its paths are checked against it ([`check_scenario_paths`], relative to the
/// folder's root); without, lexically.
pub fn read_scenario(value: Value, project: Option<&ProjectDir>) -> Result<Scenario, Refusal> {
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
    check_scenario_paths(&scenario, project.map(|p| (p, "")))
        .map_err(|e| (ErrorCode::BadPath, e.to_string()))?;
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
        assert!(read_scenario(good.clone(), None).is_ok());
        for bad in [
            json!([]),
            json!([1, 2]),
            json!(null),
            json!(3),
            json!("days"),
        ] {
            let (code, message) = read_scenario(bad.clone(), None).unwrap_err();
            assert_eq!(code, ErrorCode::InvalidValue);
            assert!(message.contains("must be a JSON object"), "{message}");
            assert!(message.contains(kind(&bad)), "{message}");
        }
        let mut nested = good;
        nested["parameters"] = json!([]);
        let (_, message) = read_scenario(nested, None).unwrap_err();
        assert!(message.contains("scenario.parameters"), "{message}");
    }

    #[test]
    fn scenario_paths_may_not_leave_the_project_folder() {
        let tmp = tempfile::tempdir().unwrap();
        let project = ProjectDir::open(&tmp.path().join("p")).unwrap();
        let with = |forcing: &str| {
            let mut v = serde_json::to_value(Scenario::default()).unwrap();
            v["forcing"] = json!(forcing);
            v
        };
        for bad in [
            "/etc/passwd",
            "../../etc/passwd",
            "a/../../b.csv",
            "..",
            "\\\\server\\share",
            "C:\\x.csv",
        ] {
            for p in [None, Some(&project)] {
                let (code, message) = read_scenario(with(bad), p).unwrap_err();
                assert_eq!(code, ErrorCode::BadPath, "{bad}: {message}");
                assert!(message.contains("scenario.forcing"), "{message}");
                let shown = format!("{bad:?}");
                assert!(message.contains(&shown), "{message} names {shown}");
            }
        }
        let ok = read_scenario(with("station.csv"), Some(&project)).unwrap();
        assert_eq!(ok.forcing.as_deref(), Some(Path::new("station.csv")));
        #[cfg(unix)]
        {
            std::os::unix::fs::symlink("/etc", project.root().join("outside")).unwrap();
            let (code, message) =
                read_scenario(with("outside/passwd"), Some(&project)).unwrap_err();
            assert_eq!(code, ErrorCode::BadPath);
            assert!(message.contains("symbolic link"), "{message}");
            let e =
                check_scenario_paths(&ok_with("outside/passwd"), Some((&project, ""))).unwrap_err();
            assert_eq!(e.key, "forcing");
        }
    }

    fn ok_with(forcing: &str) -> Scenario {
        Scenario {
            forcing: Some(forcing.into()),
            ..Scenario::default()
        }
    }
}
