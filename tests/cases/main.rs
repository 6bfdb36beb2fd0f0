//! The case format: validation (one test per rejection class, each asserting the
//! field path and a key word of the reason), `--set` overrides, the committed JSON
//! Schema, and the `mpsfsi` command end to end.

mod cli;
mod layout;
mod overrides;
mod schema;
mod validation;

use mpsfsi::case::{parse_case_value, Case, CaseError};
use serde_json::{json, Value};

/// A valid case exercising every part of the format: a tank, a prescribed wedge with
/// a velocity table, a free box, two probes.
pub fn base_value() -> Value {
    json!({
        "name": "validation-base",
        "fluid": { "density": 1000.0, "kinematic_viscosity": 1.0e-6, "gravity": [0.0, -9.81] },
        "particle_spacing": 0.01,
        "domain": { "min": [-0.5, -0.5], "max": [0.5, 0.5] },
        "fluid_blocks": [ { "polygon": [[-0.3, -0.3], [0.3, -0.3], [0.3, 0.0], [-0.3, 0.0]] } ],
        "walls": [ { "name": "tank", "polyline": [[-0.3, 0.3], [-0.3, -0.3], [0.3, -0.3], [0.3, 0.3]] } ],
        "bodies": [
            {
                "name": "wedge",
                "polygon": [[0.0, 0.0], [0.05, 0.03], [0.05, 0.06], [-0.05, 0.06], [-0.05, 0.03]],
                "position": [0.0, 0.1],
                "motion": { "type": "prescribed", "table": [
                    { "time": 0.0, "velocity": [0.0, -1.0] },
                    { "time": 0.01, "velocity": [0.0, -2.0] }
                ] }
            },
            {
                "name": "box",
                "polygon": [[-0.02, -0.02], [0.02, -0.02], [0.02, 0.02], [-0.02, 0.02]],
                "position": [0.2, 0.2],
                "motion": { "type": "free", "mass": 1.6, "inertia": 0.001 }
            }
        ],
        "time": { "end": 0.01, "cfl": 0.2, "max_dt": 1.0e-4 },
        "output": {
            "load_interval": 1.0e-3,
            "probes": [ { "name": "p1", "position": [0.0, -0.15] }, { "name": "p2", "position": [0.1, -0.15] } ]
        },
        "scheme": { }
    })
}

pub fn base_case() -> Case {
    parse_case_value(base_value()).expect("the base case parses")
}

/// Assert an error names exactly `path` and its reason contains `word`.
#[track_caller]
pub fn assert_error(err: &CaseError, path: &str, word: &str) {
    assert_eq!(err.path, path, "wrong field path in {err:?}");
    assert!(
        err.message.to_lowercase().contains(&word.to_lowercase()),
        "reason of {err:?} should mention {word:?}"
    );
}
