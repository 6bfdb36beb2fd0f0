//! The committed `api/case.schema.json` is the schema generated from the Rust types.

use mpsfsi::case::schema::case_schema_json;
use std::path::Path;

#[test]
fn committed_schema_matches_the_types() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("api/case.schema.json");
    let generated = case_schema_json();
    if std::env::var_os("UPDATE_SCHEMA").is_some() {
        std::fs::write(&path, &generated).expect("write api/case.schema.json");
    }
    let committed = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        committed == generated,
        "api/case.schema.json is out of date with the case types: regenerate it with \
         `cargo run --release -- schema > api/case.schema.json` or `UPDATE_SCHEMA=1 cargo test --release --test cases`"
    );
}

#[test]
fn schema_describes_the_case() {
    let schema: serde_json::Value = serde_json::from_str(&case_schema_json()).unwrap();
    let required: Vec<&str> = schema["required"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|v| v.as_str())
        .collect();
    for field in [
        "name",
        "fluid",
        "particle_spacing",
        "domain",
        "fluid_blocks",
        "time",
    ] {
        assert!(
            required.contains(&field),
            "{field} should be required: {required:?}"
        );
    }
    assert_eq!(
        schema["additionalProperties"],
        serde_json::json!(false),
        "unknown fields are rejected"
    );
    // the scheme's variant names are listed
    let text = case_schema_json();
    for name in [
        "higher_order",
        "corrected_higher_order",
        "pcg_jacobi",
        "wendland_c2",
    ] {
        assert!(
            text.contains(&format!("\"{name}\"")),
            "{name} missing from the schema"
        );
    }
}
