//! The same case twice, and on 1, 2 and 4 threads, gives byte-identical outputs: a dam
//! break (walls, probes) and the shipped wedge at 1 cm (a moving body, two spacings,
//! over 8192 unknowns, so the solver's vector passes take their parallel path).

use mpsfsi::case::{load_case_file, parse_case_str, Case, Limits, ValidCase};
use mpsfsi::run::{run_case, Quiet, RunStatus};
use std::path::PathBuf;

const DAM_BREAK: &str = r#"{
  "name": "determinism-dam-break",
  "fluid": { "density": 1000.0, "kinematic_viscosity": 1.0e-6, "gravity": [0.0, -9.81] },
  "particle_spacing": 0.01,
  "domain": { "min": [-0.05, -0.05], "max": [0.65, 0.5] },
  "fluid_blocks": [ { "polygon": [[0.0, 0.0], [0.15, 0.0], [0.15, 0.3], [0.0, 0.3]] } ],
  "walls": [ { "name": "tank", "polyline": [[0.0, 0.45], [0.0, 0.0], [0.6, 0.0], [0.6, 0.45]] } ],
  "time": { "end": 0.05, "cfl": 0.2, "max_dt": 0.0005 },
  "output": { "load_interval": 0.001, "probes": [ { "name": "p", "position": [0.05, 0.05] } ] }
}"#;

/// The run directory's result files after running `case` on `threads` threads.
fn run_with_threads(case: &Case, threads: usize, tag: &str) -> Vec<Vec<u8>> {
    let case = ValidCase::new(case.clone(), &Limits::default()).unwrap();
    let dir = std::env::temp_dir().join(format!("mpsfsi-determinism-{}-{tag}", std::process::id()));
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    let summary = pool.install(|| run_case(&case, &dir, &mut Quiet)).unwrap();
    assert_eq!(summary.status, RunStatus::Succeeded, "{:?}", summary.reason);
    let out = ["loads.csv", "bodies.csv", "probes.csv"]
        .iter()
        .map(|f| std::fs::read(dir.join(f)).unwrap_or_default())
        .collect();
    std::fs::remove_dir_all(&dir).ok();
    out
}

#[test]
fn same_case_same_bytes_on_one_two_and_four_threads() {
    let case = parse_case_str(DAM_BREAK).unwrap();
    let a = run_with_threads(&case, 2, "dam-a");
    let b = run_with_threads(&case, 2, "dam-b");
    assert!(a[0].len() > 100, "loads.csv has rows");
    assert_eq!(a, b, "two runs on 2 threads differ");
    assert_eq!(
        a,
        run_with_threads(&case, 1, "dam-1"),
        "1 and 2 threads differ"
    );
    assert_eq!(
        a,
        run_with_threads(&case, 4, "dam-4"),
        "4 and 2 threads differ"
    );
}

#[test]
fn a_body_entering_the_water_gives_the_same_bytes_on_one_two_and_four_threads() {
    let path =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("cases/wedge_30deg_constant_velocity.json");
    let overrides = ["particle_spacing=0.01", "time.end=0.004"].map(String::from);
    let case = load_case_file(&path, &overrides).unwrap();
    let two = run_with_threads(&case, 2, "wedge-2");
    assert!(two[1].len() > 100, "bodies.csv has rows");
    assert_eq!(
        two,
        run_with_threads(&case, 1, "wedge-1"),
        "1 and 2 threads differ"
    );
    assert_eq!(
        two,
        run_with_threads(&case, 4, "wedge-4"),
        "4 and 2 threads differ"
    );
}
