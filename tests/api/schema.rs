//! The served contract (`api/openapi.yaml` with the case schema), and a small JSON
//! Schema checker for the keywords it uses (`$ref`, `type`, `enum`, `const`, `required`,
//! `properties`, `additionalProperties`, `items`, `minItems`, `maxItems`, `oneOf`,
//! `anyOf`, `minimum`, `maximum`, `exclusiveMinimum`, `pattern`; `format` and
//! annotations are ignored). An unknown keyword fails the check, so the file cannot
//! drift into schema features this checker would silently skip.

use serde_json::Value;
use std::sync::LazyLock;

/// The document the server serves: api/openapi.yaml with the full case schema.
pub static OPENAPI: LazyLock<Value> = LazyLock::new(|| {
    mpsfsi::service::contract::openapi_document().expect("the served contract builds")
});

const KNOWN: &[&str] = &[
    "$ref",
    "type",
    "enum",
    "required",
    "properties",
    "additionalProperties",
    "items",
    "oneOf",
    "anyOf",
    "const",
    "minimum",
    "maximum",
    "exclusiveMinimum",
    "minItems",
    "maxItems",
    "pattern",
    "format",
    "title",
    "description",
    "default",
    "example",
];

fn resolve<'a>(doc: &'a Value, reference: &str) -> &'a Value {
    let pointer = reference
        .strip_prefix('#')
        .unwrap_or_else(|| panic!("only local refs: {reference}"));
    doc.pointer(pointer)
        .unwrap_or_else(|| panic!("dangling $ref {reference}"))
}

fn type_matches(t: &str, v: &Value) -> bool {
    match t {
        "null" => v.is_null(),
        "boolean" => v.is_boolean(),
        "object" => v.is_object(),
        "array" => v.is_array(),
        "string" => v.is_string(),
        "number" => v.is_number(),
        "integer" => v.as_i64().is_some() || v.as_u64().is_some(),
        other => panic!("unknown type {other}"),
    }
}

/// Errors of `value` against `schema` (empty when it conforms).
pub fn check(doc: &Value, schema: &Value, value: &Value, at: &str) -> Vec<String> {
    let mut errors = Vec::new();
    let Some(s) = schema.as_object() else {
        return errors;
    };
    for key in s.keys() {
        assert!(
            KNOWN.contains(&key.as_str()),
            "schema keyword {key} at {at} is not supported by the checker"
        );
    }
    if let Some(Value::String(r)) = s.get("$ref") {
        errors.extend(check(doc, resolve(doc, r), value, at));
    }
    if let Some(t) = s.get("type") {
        let ok = match t {
            Value::String(t) => type_matches(t, value),
            Value::Array(ts) => ts.iter().any(|t| type_matches(t.as_str().unwrap(), value)),
            _ => panic!("bad type at {at}"),
        };
        if !ok {
            errors.push(format!("{at}: {value} is not of type {t}"));
            return errors;
        }
    }
    if let Some(Value::Array(options)) = s.get("enum") {
        if !options.contains(value) {
            errors.push(format!("{at}: {value} not in {options:?}"));
        }
    }
    if let (Some(min), Some(v)) = (s.get("minimum").and_then(Value::as_f64), value.as_f64()) {
        if v < min {
            errors.push(format!("{at}: {v} < minimum {min}"));
        }
    }
    if let (Some(max), Some(v)) = (s.get("maximum").and_then(Value::as_f64), value.as_f64()) {
        if v > max {
            errors.push(format!("{at}: {v} > maximum {max}"));
        }
    }
    if let Some(c) = s.get("const") {
        if c != value {
            errors.push(format!("{at}: {value} is not {c}"));
        }
    }
    if let (Some(min), Some(v)) = (
        s.get("exclusiveMinimum").and_then(Value::as_f64),
        value.as_f64(),
    ) {
        if v <= min {
            errors.push(format!("{at}: {v} <= exclusive minimum {min}"));
        }
    }
    if let (Some(pattern), Some(text)) = (s.get("pattern").and_then(Value::as_str), value.as_str())
    {
        let re = regex::Regex::new(pattern).unwrap_or_else(|e| panic!("pattern at {at}: {e}"));
        if !re.is_match(text) {
            errors.push(format!("{at}: {text:?} does not match {pattern}"));
        }
    }
    if let Value::Array(items) = value {
        let n = items.len() as u64;
        if s.get("minItems")
            .and_then(Value::as_u64)
            .is_some_and(|m| n < m)
        {
            errors.push(format!("{at}: {n} items, fewer than minItems"));
        }
        if s.get("maxItems")
            .and_then(Value::as_u64)
            .is_some_and(|m| n > m)
        {
            errors.push(format!("{at}: {n} items, more than maxItems"));
        }
    }
    if let Some(Value::Array(options)) = s.get("anyOf") {
        if !options.iter().any(|o| check(doc, o, value, at).is_empty()) {
            errors.push(format!("{at}: {value} matches none of the anyOf options"));
        }
    }
    if let Some(Value::Array(options)) = s.get("oneOf") {
        let matching = options
            .iter()
            .filter(|o| check(doc, o, value, at).is_empty())
            .count();
        if matching != 1 {
            errors.push(format!(
                "{at}: {value} matches {matching} of the oneOf options, not exactly one"
            ));
        }
    }
    if let Value::Object(map) = value {
        if let Some(Value::Array(required)) = s.get("required") {
            for r in required {
                if !map.contains_key(r.as_str().unwrap()) {
                    errors.push(format!("{at}: missing required {r}"));
                }
            }
        }
        let props = s.get("properties").and_then(Value::as_object);
        for (k, v) in map {
            let here = format!("{at}.{k}");
            if let Some(p) = props.and_then(|p| p.get(k)) {
                errors.extend(check(doc, p, v, &here));
            } else {
                match s.get("additionalProperties") {
                    Some(Value::Bool(false)) => {
                        errors.push(format!("{at}: unexpected property {k}"))
                    }
                    Some(extra @ Value::Object(_)) => errors.extend(check(doc, extra, v, &here)),
                    _ => {}
                }
            }
        }
    }
    if let (Some(items), Value::Array(values)) = (s.get("items"), value) {
        for (i, v) in values.iter().enumerate() {
            errors.extend(check(doc, items, v, &format!("{at}[{i}]")));
        }
    }
    errors
}

/// The response object of `method path` (OpenAPI template) for `status`, refs resolved.
pub fn response_spec(method: &str, path: &str, status: u16) -> &'static Value {
    let doc = &*OPENAPI;
    let op = doc["paths"][path]
        .get(method.to_lowercase())
        .unwrap_or_else(|| panic!("{method} {path} is not in api/openapi.yaml"));
    let response = op["responses"]
        .get(status.to_string())
        .unwrap_or_else(|| panic!("{method} {path} does not document status {status}"));
    match response.get("$ref").and_then(Value::as_str) {
        Some(r) => resolve(doc, r),
        None => response,
    }
}

/// Assert that a JSON body the server sent conforms to the documented schema.
pub fn assert_conforms(method: &str, path: &str, status: u16, body: &Value) {
    let spec = response_spec(method, path, status);
    let schema = &spec["content"]["application/json"]["schema"];
    assert!(
        !schema.is_null(),
        "{method} {path} {status} documents no JSON body"
    );
    let errors = check(&OPENAPI, schema, body, "$");
    assert!(
        errors.is_empty(),
        "{method} {path} {status} does not match api/openapi.yaml: {errors:#?}\n{body:#}"
    );
}
