//! Reading a case: JSON text -> `serde_json::Value` -> `--set` overrides -> `Case`,
//! with type errors reported at their field path (serde_path_to_error).

use super::{Case, CaseError};
use serde_json::Value;
use std::path::Path;

/// Read, override and parse a case file. Validation is separate ([`super::validate`]).
pub fn load_case_file(path: &Path, overrides: &[String]) -> Result<Case, CaseError> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| CaseError::new("", format!("cannot read {}: {e}", path.display())))?;
    let mut value: Value = serde_json::from_str(&text)
        .map_err(|e| CaseError::new("", format!("{} is not valid JSON: {e}", path.display())))?;
    for assignment in overrides {
        apply_override(&mut value, assignment)?;
    }
    parse_case_value(value)
}

/// Parse a case from JSON text.
pub fn parse_case_str(text: &str) -> Result<Case, CaseError> {
    let value: Value =
        serde_json::from_str(text).map_err(|e| CaseError::new("", format!("invalid JSON: {e}")))?;
    parse_case_value(value)
}

/// Deserialize a case, naming the field path of the first type error.
pub fn parse_case_value(value: Value) -> Result<Case, CaseError> {
    check_objects(&value, &case_schema()["properties"], "")?;
    serde_path_to_error::deserialize(value).map_err(|e| {
        let path = e.path().to_string();
        let path = if path == "." { String::new() } else { path };
        CaseError::new(path, e.into_inner().to_string())
    })
}

/// The case schema as a JSON value, generated once.
fn case_schema() -> &'static Value {
    static SCHEMA: std::sync::OnceLock<Value> = std::sync::OnceLock::new();
    SCHEMA.get_or_init(|| {
        serde_json::to_value(schemars::schema_for!(Case)).expect("a JSON Schema serialises")
    })
}

/// Objects must be JSON objects. serde's derived structs also read a JSON array as
/// their fields in order, so `"output": [null, null]` passed as an output block with two
/// nulls; the schema forbids it. Walks the object `value` beside the schema's
/// `properties` and rejects, with its field path, a value that is not an object where
/// the schema has one (through `$ref`s and arrays' items; a field under `anyOf`/`oneOf`
/// is left to serde).
fn check_objects(value: &Value, properties: &Value, path: &str) -> Result<(), CaseError> {
    let Some(fields) = value.as_object() else {
        return Ok(());
    };
    for (name, v) in fields {
        let field = if path.is_empty() {
            name.clone()
        } else {
            format!("{path}.{name}")
        };
        check_node(v, &properties[name], &field)?;
    }
    Ok(())
}

fn check_node(value: &Value, node: &Value, path: &str) -> Result<(), CaseError> {
    let node = match node["$ref"].as_str() {
        Some(r) => &case_schema()["$defs"][r.trim_start_matches("#/$defs/")],
        None => node,
    };
    match node["type"].as_str() {
        Some("object") => {
            if !value.is_object() {
                return Err(CaseError::new(
                    path,
                    format!("expected an object {{…}}, got {}", kind(value)),
                ));
            }
            check_objects(value, &node["properties"], path)
        }
        Some("array") => {
            for (k, item) in value.as_array().into_iter().flatten().enumerate() {
                check_node(item, &node["items"], &format!("{path}[{k}]"))?;
            }
            Ok(())
        }
        _ => Ok(()),
    }
}

fn kind(value: &Value) -> &'static str {
    match value {
        Value::Null => "null",
        Value::Bool(_) => "a boolean",
        Value::Number(_) => "a number",
        Value::String(_) => "a string",
        Value::Array(_) => "an array",
        Value::Object(_) => "an object",
    }
}

/// Apply one `PATH=VALUE` override. VALUE is parsed as JSON, or taken as a string when
/// it is not valid JSON (`scheme.laplacian=higher_order`). Array elements are addressed
/// as `bodies.0.motion.mass` or `bodies[0].motion.mass`.
pub fn apply_override(value: &mut Value, assignment: &str) -> Result<(), CaseError> {
    let (path, raw) = assignment
        .split_once('=')
        .ok_or_else(|| CaseError::new(assignment, "an override is PATH=VALUE"))?;
    let path = path.trim();
    if path.is_empty() {
        return Err(CaseError::new("", "empty override path"));
    }
    let new_value: Value =
        serde_json::from_str(raw.trim()).unwrap_or_else(|_| Value::String(raw.trim().to_string()));
    let normalized = path.replace('[', ".").replace(']', "");
    let keys: Vec<&str> = normalized.split('.').filter(|k| !k.is_empty()).collect();
    let mut cursor = value;
    for (depth, key) in keys.iter().enumerate() {
        let last = depth + 1 == keys.len();
        let here = keys[..=depth].join(".");
        cursor = match cursor {
            Value::Object(map) => {
                if last {
                    map.insert((*key).to_string(), new_value);
                    return Ok(());
                }
                map.entry((*key).to_string())
                    .or_insert_with(|| Value::Object(Default::default()))
            }
            Value::Array(items) => {
                let index: usize = key
                    .parse()
                    .map_err(|_| CaseError::new(here.clone(), "expected an array index"))?;
                let len = items.len();
                let slot = items.get_mut(index).ok_or_else(|| {
                    CaseError::new(here.clone(), format!("index out of range (length {len})"))
                })?;
                if last {
                    *slot = new_value;
                    return Ok(());
                }
                slot
            }
            _ => {
                return Err(CaseError::new(
                    here,
                    "cannot set a field inside a number, string or null",
                ))
            }
        };
    }
    Ok(())
}
