//! The same case twice, and on 1 and 2 threads, gives byte-identical loads.csv.

use mpsfsi::case::{parse_case_str, Limits, ValidCase};
use mpsfsi::run::{run_case, Quiet, RunStatus};

const CASE: &str = r#"{
  "name": "determinism-dam-break",
  "fluid": { "density": 1000.0, "kinematic_viscosity": 1.0e-6, "gravity": [0.0, -9.81] },
  "particle_spacing": 0.01,
  "domain": { "min": [-0.05, -0.05], "max": [0.65, 0.5] },
  "fluid_blocks": [ { "polygon": [[0.0, 0.0], [0.15, 0.0], [0.15, 0.3], [0.0, 0.3]] } ],
  "walls": [ { "name": "tank", "polyline": [[0.0, 0.45], [0.0, 0.0], [0.6, 0.0], [0.6, 0.45]] } ],
  "time": { "end": 0.05, "cfl": 0.2, "max_dt": 0.0005 },
  "output": { "load_interval": 0.001, "probes": [ { "name": "p", "position": [0.05, 0.05] } ] }
}"#;

fn run_with_threads(threads: usize, tag: &str) -> (Vec<u8>, Vec<u8>) {
    let case = ValidCase::new(parse_case_str(CASE).unwrap(), &Limits::default()).unwrap();
    let dir = std::env::temp_dir().join(format!("mpsfsi-determinism-{}-{tag}", std::process::id()));
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    let summary = pool.install(|| run_case(&case, &dir, &mut Quiet)).unwrap();
    assert_eq!(summary.status, RunStatus::Succeeded, "{:?}", summary.reason);
    let out = (
        std::fs::read(dir.join("loads.csv")).unwrap(),
        std::fs::read(dir.join("probes.csv")).unwrap(),
    );
    std::fs::remove_dir_all(&dir).ok();
    out
}

#[test]
fn same_case_same_bytes_on_one_and_two_threads() {
    let a = run_with_threads(2, "a");
    let b = run_with_threads(2, "b");
    let c = run_with_threads(1, "c");
    assert!(a.0.len() > 100, "loads.csv has rows");
    assert_eq!(a, b, "two runs on 2 threads differ");
    assert_eq!(a, c, "1 and 2 threads differ");
}
