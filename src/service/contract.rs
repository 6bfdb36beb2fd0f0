//! The served contract: `api/openapi.yaml` with the full case schema in place of its
//! `Case` placeholder. The case schema is generated from the case types (the text of
//! `api/case.schema.json`), so the contract a client validates against is the one the
//! server parses with; its definitions join the document's components.

use crate::case::Case;
use serde_json::Value;

const CASE_REFS: &str = "#/$defs/";
const COMPONENT_REFS: &str = "#/components/schemas/";

/// The OpenAPI document `GET /v1/openapi.json` serves.
pub fn openapi_document() -> Result<Value, String> {
    let mut doc: Value = serde_norway::from_str(super::OPENAPI_YAML)
        .map_err(|e| format!("api/openapi.yaml is not valid YAML: {e}"))?;
    let mut case = serde_json::to_value(schemars::schema_for!(Case))
        .map_err(|e| format!("the case schema: {e}"))?;
    let case_map = case
        .as_object_mut()
        .ok_or("the case schema is not an object")?;
    let defs = case_map.remove("$defs");
    case_map.remove("$schema");
    let schemas = doc
        .pointer_mut("/components/schemas")
        .and_then(Value::as_object_mut)
        .ok_or("api/openapi.yaml has no components.schemas")?;
    // the placeholder's description names the rules a JSON Schema cannot express
    if let Some(description) = schemas.get("Case").and_then(|c| c.get("description")) {
        case_map.insert("description".into(), description.clone());
    }
    rewrite_refs(&mut case);
    if let Some(Value::Object(defs)) = defs {
        for (name, mut def) in defs {
            if schemas.contains_key(&name) {
                return Err(format!(
                    "the case schema's definition {name} collides with a schema of api/openapi.yaml"
                ));
            }
            rewrite_refs(&mut def);
            schemas.insert(name, def);
        }
    }
    schemas.insert("Case".into(), case);
    Ok(doc)
}

/// `#/$defs/X` -> `#/components/schemas/X` everywhere in `v`.
fn rewrite_refs(v: &mut Value) {
    match v {
        Value::Object(map) => {
            for (key, value) in map.iter_mut() {
                match value {
                    Value::String(s) if key == "$ref" => {
                        if let Some(name) = s.strip_prefix(CASE_REFS) {
                            *s = format!("{COMPONENT_REFS}{name}");
                        }
                    }
                    _ => rewrite_refs(value),
                }
            }
        }
        Value::Array(items) => items.iter_mut().for_each(rewrite_refs),
        _ => {}
    }
}
