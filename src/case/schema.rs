//! JSON Schema of the case format, generated from the serde types (schemars) and
//! committed as `api/case.schema.json`; a test keeps the two identical.

use super::Case;

/// The case schema, pretty-printed with a trailing newline (the committed file's text).
pub fn case_schema_json() -> String {
    let schema = schemars::schema_for!(Case);
    let mut text = serde_json::to_string_pretty(&schema).expect("a JSON Schema serialises");
    text.push('\n');
    text
}
