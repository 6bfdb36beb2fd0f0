//! Rule 6: names. They label rows of loads.csv (walls and bodies together) and of
//! probes.csv, so they are non-empty, unique and free of CSV delimiters.

use super::{reject, Check};
use crate::case::Case;
use std::collections::HashMap;

pub(super) fn check_names(case: &Case) -> Check {
    // walls and bodies share the `body` column of loads.csv
    let mut seen: HashMap<&str, String> = HashMap::new();
    let named = case
        .walls
        .iter()
        .enumerate()
        .map(|(i, w)| (format!("walls[{i}].name"), w.name.as_str()))
        .chain(
            case.bodies
                .iter()
                .enumerate()
                .map(|(i, b)| (format!("bodies[{i}].name"), b.name.as_str())),
        );
    for (path, name) in named {
        if name.trim().is_empty() {
            return reject(
                path,
                "a name must not be empty (it labels rows of loads.csv)",
            );
        }
        if name.contains([',', '"', '\n', '\r']) {
            return reject(path, format!("name '{name}' must not contain commas, quotes or line breaks (it is a CSV field)"));
        }
        if let Some(first) = seen.get(name) {
            return reject(
                path,
                format!("duplicate name '{name}' (already used by {first}): walls and bodies need distinct names"),
            );
        }
        seen.insert(name, path.trim_end_matches(".name").to_string());
    }
    let mut probes: HashMap<&str, usize> = HashMap::new();
    for (i, p) in case.output.probes.iter().enumerate() {
        let path = format!("output.probes[{i}].name");
        if p.name.trim().is_empty() {
            return reject(
                path,
                "a probe name must not be empty (it labels rows of probes.csv)",
            );
        }
        if p.name.contains([',', '"', '\n', '\r']) {
            return reject(
                path,
                format!(
                    "probe name '{}' must not contain commas, quotes or line breaks",
                    p.name
                ),
            );
        }
        if let Some(first) = probes.insert(p.name.as_str(), i) {
            return reject(
                path,
                format!(
                    "duplicate probe name '{}' (already used by output.probes[{first}])",
                    p.name
                ),
            );
        }
    }
    Ok(())
}
