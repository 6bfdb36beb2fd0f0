//! Rule 1: every number is finite.
//!
//! The case is turned into a YAML value tree and walked generically, so fields added
//! later are covered too. YAML rather than JSON: `serde_json::Value` turns NaN and
//! infinities into `null` (indistinguishable from an absent option), while
//! `serde_norway::Value` keeps them and keeps fields in declaration order, so the first
//! non-finite number in the case's own order is the one reported.

use super::{reject, Check};
use crate::case::Case;
use serde_norway::Value;

pub(super) fn check_finite(case: &Case) -> Check {
    // the case's types always serialise; were one not to, the typed rules still run
    let Ok(tree) = serde_norway::to_value(case) else {
        return Ok(());
    };
    let mut path = String::new();
    match first_non_finite(&tree, &mut path) {
        Some(value) => reject(path, format!("must be a finite number (got {value})")),
        None => Ok(()),
    }
}

/// The first non-finite number below `value`; `path` is left naming it
/// (`bodies[1].polygon[2][0]`: fields joined by dots, indices in brackets).
fn first_non_finite(value: &Value, path: &mut String) -> Option<f64> {
    match value {
        Value::Number(n) if !n.is_finite() => n.as_f64(),
        Value::Sequence(items) => items
            .iter()
            .enumerate()
            .find_map(|(i, item)| descend(path, &format!("[{i}]"), item)),
        // struct fields and map keys are strings; any other key is named by position
        Value::Mapping(fields) => fields.iter().enumerate().find_map(|(i, (key, item))| {
            let name = key.as_str().map_or_else(|| i.to_string(), str::to_string);
            let segment = field(path, &name);
            descend(path, &segment, item)
        }),
        // an externally tagged enum variant: named like a field
        Value::Tagged(tagged) => {
            let tag = tagged.tag.to_string();
            let name = tag.strip_prefix('!').unwrap_or(&tag);
            let segment = field(path, name);
            descend(path, &segment, &tagged.value)
        }
        _ => None,
    }
}

fn field(path: &str, name: &str) -> String {
    if path.is_empty() {
        name.to_string()
    } else {
        format!(".{name}")
    }
}

/// Walk `value` with `segment` appended to `path`; the path is restored unless
/// something was found there.
fn descend(path: &mut String, segment: &str, value: &Value) -> Option<f64> {
    let len = path.len();
    path.push_str(segment);
    let found = first_non_finite(value, path);
    if found.is_none() {
        path.truncate(len);
    }
    found
}
