//! Output suite: VTK snapshots, load plots, the impulse-conserving load filter and the
//! benchmark's error measures.

mod bench_measures;
mod bench_scaling;
mod filter;
mod flow;
mod plot;
mod surface;
mod uncertainty;
mod vtk;

/// A small hydrostatic tank (20 x 10 particles) as a case value.
pub fn small_tank() -> serde_json::Value {
    serde_json::json!({
        "name": "small-tank",
        "fluid": { "density": 1000.0, "kinematic_viscosity": 1.0e-6, "gravity": [0.0, -9.81] },
        "particle_spacing": 0.01,
        "domain": { "min": [-0.05, -0.05], "max": [0.25, 0.2] },
        "fluid_blocks": [ { "polygon": [[0.0, 0.0], [0.2, 0.0], [0.2, 0.1], [0.0, 0.1]] } ],
        "walls": [ { "name": "tank", "polyline": [[0.0, 0.15], [0.0, 0.0], [0.2, 0.0], [0.2, 0.15]] } ],
        "time": { "end": 0.05, "cfl": 0.2, "max_dt": 0.0005 },
        "output": { "load_interval": 0.005, "snapshot_interval": 0.01 },
        "scheme": {}
    })
}

/// A fresh empty directory under the target folder.
pub fn scratch_dir(name: &str) -> std::path::PathBuf {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("output-suite")
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}
