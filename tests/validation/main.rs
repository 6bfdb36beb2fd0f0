//! Physics validation against references (docs/references.md): hydrostatics, the
//! Martin & Moyce dam break and the viscous standing wave. Cases are the shipped files
//! in cases/.

mod dam_break;
mod hydrostatic;
mod standing_wave;

use mpsfsi::case::{load_case_file, Case};
use std::path::PathBuf;

pub fn shipped_case(name: &str, overrides: &[&str]) -> Case {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("cases")
        .join(name);
    let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    load_case_file(&path, &overrides).unwrap_or_else(|e| panic!("{name}: {e}"))
}

pub fn read_csv(path: &std::path::Path) -> Vec<Vec<String>> {
    let text = std::fs::read_to_string(path).unwrap();
    text.lines()
        .skip(1)
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect()
}
