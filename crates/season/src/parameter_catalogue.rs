//! The scenario's parameters described for front ends (the editor's parameter panel, the
//! CLI's help): one entry per settable leaf of [`Parameters`], generated from the Rust types
//! themselves so that no front end copies a name, a unit or a range by hand.
//!
//! - **Help** is the field's documentation (its doc comment, through the JSON Schema that
//!   `schemars` derives from the types): the first sentence as `help`, the whole as `doc`
//!   (units and the source of each default are written there).
//! - **Range**: the values [`Parameters::validate`] accepts, found by bisection from the
//!   default towards ±1e12 with every other parameter at its default (the check itself is the
//!   one source of truth: the CLI, scenario files and the editor all call it). A bound is
//!   `None` when ±1e12 is accepted; for a range open at a bound, the bound is the closest
//!   accepted value (e.g. 5e-324 for `> 0`).
//! - **Choices** of an enumeration are its serialised names.

use crate::scenario::Parameters;
use serde::Serialize;
use serde_json::{Map, Value};
use std::sync::OnceLock;

/// What kind of value a parameter takes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ParameterKind {
    Number,
    Integer,
    Boolean,
    Choice,
}

/// One settable parameter.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ParameterInfo {
    /// Dotted path below `parameters` (`melt.enhanced.f_t_mm_h_c`).
    pub path: String,
    /// The section it belongs to (the first component of the path).
    pub section: String,
    pub kind: ParameterKind,
    /// The first sentence of its documentation.
    pub help: String,
    /// Its whole documentation.
    pub doc: String,
    /// The default value.
    pub default: Value,
    /// The accepted range with every other parameter at its default (numbers only).
    pub min: Option<f64>,
    pub max: Option<f64>,
    /// The accepted names (choices only).
    pub choices: Vec<String>,
}

/// Every settable parameter, in the order of the types' fields (computed once).
pub fn parameter_catalogue() -> &'static [ParameterInfo] {
    static CATALOGUE: OnceLock<Vec<ParameterInfo>> = OnceLock::new();
    CATALOGUE.get_or_init(build)
}

fn build() -> Vec<ParameterInfo> {
    let schema = serde_json::to_value(schemars::schema_for!(Parameters)).unwrap_or_default();
    let defaults = serde_json::to_value(Parameters::default()).unwrap_or_default();
    let defs = schema
        .get("$defs")
        .and_then(Value::as_object)
        .cloned()
        .unwrap_or_default();
    let mut out = Vec::new();
    walk(
        &schema,
        &defs,
        &defaults,
        &defaults,
        &mut Vec::new(),
        &mut out,
    );
    out
}

/// The schema a `$ref` (or a one-element `allOf`) points to, else `s` itself.
fn resolve<'a>(s: &'a Value, defs: &'a Map<String, Value>) -> &'a Value {
    if let Some(r) = s.get("$ref").and_then(Value::as_str)
        && let Some(d) = r.strip_prefix("#/$defs/").and_then(|n| defs.get(n))
    {
        return resolve(d, defs);
    }
    if let Some([one]) = s.get("allOf").and_then(Value::as_array).map(Vec::as_slice) {
        return resolve(one, defs);
    }
    s
}

fn walk(
    schema: &Value,
    defs: &Map<String, Value>,
    root_defaults: &Value,
    defaults: &Value,
    path: &mut Vec<String>,
    out: &mut Vec<ParameterInfo>,
) {
    let schema = resolve(schema, defs);
    let Some(props) = schema.get("properties").and_then(Value::as_object) else {
        return;
    };
    for (name, prop) in props {
        let Some(default) = defaults.get(name) else {
            continue;
        };
        path.push(name.clone());
        let target = resolve(prop, defs);
        let doc = prop
            .get("description")
            .or_else(|| target.get("description"))
            .and_then(Value::as_str)
            .unwrap_or("")
            .to_string();
        let kind = match default {
            Value::Object(_) => None,
            Value::Bool(_) => Some(ParameterKind::Boolean),
            Value::Number(n) if n.is_f64() => Some(ParameterKind::Number),
            Value::Number(_) => Some(ParameterKind::Integer),
            Value::String(_) => Some(ParameterKind::Choice),
            _ => None,
        };
        match kind {
            None => walk(prop, defs, root_defaults, default, path, out),
            Some(kind) => {
                let (min, max) = if matches!(kind, ParameterKind::Number | ParameterKind::Integer) {
                    let d = default.as_f64().unwrap_or(0.0);
                    let int = kind == ParameterKind::Integer;
                    (
                        bound(root_defaults, path, d, -1e12, int),
                        bound(root_defaults, path, d, 1e12, int),
                    )
                } else {
                    (None, None)
                };
                out.push(ParameterInfo {
                    path: path.join("."),
                    section: path[0].clone(),
                    kind,
                    help: first_sentence(&doc),
                    doc,
                    default: default.clone(),
                    min,
                    max,
                    choices: choices(target),
                });
            }
        }
        path.pop();
    }
}

/// The serialised names of an enumeration's schema (`enum`, or `oneOf` of `const`s).
fn choices(s: &Value) -> Vec<String> {
    let names = |v: &Value| v.as_str().map(str::to_string);
    if let Some(e) = s.get("enum").and_then(Value::as_array) {
        return e.iter().filter_map(names).collect();
    }
    s.get("oneOf")
        .and_then(Value::as_array)
        .map(|alts| {
            alts.iter()
                .flat_map(|a| {
                    a.get("const").and_then(names).into_iter().chain(
                        a.get("enum")
                            .and_then(Value::as_array)
                            .into_iter()
                            .flatten()
                            .filter_map(names),
                    )
                })
                .collect()
        })
        .unwrap_or_default()
}

/// The documentation up to the first full stop that ends a sentence (followed by a capital,
/// not after an abbreviation such as "Eq." or "et al.").
fn first_sentence(doc: &str) -> String {
    const ABBREVIATIONS: [&str; 8] = ["Eq", "Eqs", "e.g", "i.e", "al", "Fig", "cf", "vs"];
    let words: Vec<&str> = doc.split_whitespace().collect();
    let mut out = Vec::new();
    for (k, w) in words.iter().enumerate() {
        out.push(*w);
        let next_capital = words
            .get(k + 1)
            .and_then(|n| n.chars().next())
            .is_some_and(char::is_uppercase);
        if let Some(stem) = w.strip_suffix('.')
            && next_capital
            && !ABBREVIATIONS.iter().any(|a| stem.ends_with(a))
        {
            break;
        }
    }
    out.join(" ")
}

/// Whether the defaults with the leaf at `path` set to `v` pass [`Parameters::validate`].
fn accepted(defaults: &Value, path: &[String], v: f64, int: bool) -> bool {
    let mut p = defaults.clone();
    let mut slot = &mut p;
    for k in path {
        match slot.get_mut(k) {
            Some(s) => slot = s,
            None => return false,
        }
    }
    *slot = if int {
        if v < 0.0 {
            Value::from(v as i64)
        } else {
            Value::from(v as u64)
        }
    } else {
        match serde_json::Number::from_f64(v) {
            Some(n) => Value::Number(n),
            None => return false,
        }
    };
    serde_json::from_value::<Parameters>(p).is_ok_and(|p| p.validate().is_ok())
}

/// The accepted value closest to `limit` on the way from the accepted `start`: `None` if
/// `limit` itself is accepted (or `start` is not).
fn bound(defaults: &Value, path: &[String], start: f64, limit: f64, int: bool) -> Option<f64> {
    if !accepted(defaults, path, start, int) || accepted(defaults, path, limit, int) {
        return None;
    }
    // Bisect on the order of the doubles (their bits, made monotone), so that the bound is
    // found to the last bit whatever its magnitude.
    let key = |x: f64| {
        let b = x.to_bits() as i64;
        if b < 0 { i64::MIN - b } else { b }
    };
    let value = |k: i64| f64::from_bits((if k < 0 { i64::MIN - k } else { k }) as u64);
    let (mut ok, mut bad) = (i128::from(key(start)), i128::from(key(limit)));
    while (ok - bad).abs() > 1 {
        let mid = ok + (bad - ok) / 2;
        let mut v = value(mid as i64);
        if int {
            v = v.round();
        }
        if accepted(defaults, path, v, int) {
            ok = mid;
        } else {
            bad = mid;
        }
    }
    let v = value(ok as i64);
    Some(if int { v.round() } else { v })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn find(path: &str) -> &'static ParameterInfo {
        parameter_catalogue()
            .iter()
            .find(|p| p.path == path)
            .unwrap_or_else(|| panic!("no {path}"))
    }

    #[test]
    fn every_leaf_of_the_parameters_is_described() {
        let cat = parameter_catalogue();
        // Every number, boolean and name of the defaults has an entry, with help.
        fn leaves(v: &Value, path: &str, out: &mut Vec<String>) {
            match v {
                Value::Object(m) => {
                    for (k, v) in m {
                        let p = if path.is_empty() {
                            k.clone()
                        } else {
                            format!("{path}.{k}")
                        };
                        leaves(v, &p, out);
                    }
                }
                Value::Number(_) | Value::Bool(_) | Value::String(_) => out.push(path.into()),
                _ => {}
            }
        }
        let mut all = Vec::new();
        leaves(
            &serde_json::to_value(Parameters::default()).unwrap(),
            "",
            &mut all,
        );
        assert!(all.len() > 100, "{}", all.len());
        for path in &all {
            let p = find(path);
            assert!(!p.help.is_empty(), "{path} has no documentation");
        }
        assert_eq!(cat.len(), all.len());
    }

    #[test]
    fn ranges_come_from_the_checks_and_help_from_the_docs() {
        let p = find("slope_shedding.min_slope_deg");
        assert_eq!((p.min, p.max), (Some(0.0), Some(90.0)));
        assert!(p.help.starts_with("Slope below which"), "{}", p.help);
        assert!(p.doc.contains("FSM2oshd"), "{}", p.doc);
        let p = find("slope_shedding.dynamic_ratio");
        assert_eq!(p.max, Some(1.0));
        assert!(p.min.is_some_and(|m| m > 0.0 && m < 1e-300), "{:?}", p.min);
        let p = find("slope_shedding.law");
        assert_eq!(p.kind, ParameterKind::Choice);
        assert_eq!(p.choices, ["exponential", "power_law"]);
        let p = find("snowtran.cloud_cover_pct");
        assert!(p.help.len() > "Cloud cover, % (Eq.".len(), "{}", p.help);
        let p = find("slope_shedding.enabled");
        assert_eq!(p.kind, ParameterKind::Boolean);
        assert_eq!(p.section, "slope_shedding");
    }
}
