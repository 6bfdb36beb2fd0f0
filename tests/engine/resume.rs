//! A run stopped at a step and resumed from its checkpoint writes the same bytes as the
//! run that never stopped (loads, bodies, probes, energy, the filtered loads and the
//! snapshot collection), however many times it is stopped: the checkpoint holds the
//! whole state the later steps read (particles, the last accelerations, the solver's
//! reused hierarchy, rapier's world, the writers' interval sums).

use mpsfsi::case::{load_case_file, parse_case_str, Limits, ValidCase};
use mpsfsi::run::{checkpoint, run_case, run_case_with, Checkpoint, Observer, Progress};
use mpsfsi::run::{Quiet, RunError, RunOptions, RunStatus};
use std::io::{Read, Write};
use std::path::{Path, PathBuf};

/// Asks the run to stop once it has taken `at` steps.
struct StopAt {
    at: u64,
    stop: bool,
}

impl Observer for StopAt {
    fn progress(&mut self, p: &Progress) {
        self.stop |= p.step >= self.at;
    }
    fn is_cancelled(&self) -> bool {
        self.stop
    }
}

fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("engine-resume-{name}"));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

fn case_of(file: &str, overrides: &[&str]) -> ValidCase {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(file);
    let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    ValidCase::new(
        load_case_file(&path, &overrides).unwrap(),
        &Limits::default(),
    )
    .unwrap()
}

/// Run `case` into `dir`, stopping after each step count of `stops` and resuming from
/// the checkpoint each time; the steps at which it stopped.
fn run_with_stops(case: &ValidCase, dir: &Path, stops: &[u64]) {
    let mut resume = None;
    for &at in stops {
        let options = RunOptions {
            checkpoint_on_stop: true,
            resume: resume.take(),
            ..RunOptions::default()
        };
        let summary = run_case_with(case, dir, &mut StopAt { at, stop: false }, options).unwrap();
        assert_eq!(summary.status, RunStatus::Cancelled, "stopped at step {at}");
        assert_eq!(summary.steps, at);
        let saved = Checkpoint::read(&dir.join(checkpoint::FILE)).unwrap();
        assert_eq!(saved.header.steps, at);
        resume = Some(saved);
    }
    let options = RunOptions {
        resume,
        ..RunOptions::default()
    };
    let summary = run_case_with(case, dir, &mut Quiet, options).unwrap();
    assert_eq!(summary.status, RunStatus::Succeeded, "{:?}", summary.reason);
    assert!(
        !dir.join(checkpoint::FILE).exists(),
        "a finished run keeps no checkpoint"
    );
}

fn assert_same_files(a: &Path, b: &Path, files: &[&str]) {
    for f in files {
        let (x, y) = (std::fs::read(a.join(f)), std::fs::read(b.join(f)));
        let (x, y) = (x.unwrap_or_else(|e| panic!("{f}: {e}")), y.unwrap());
        assert!(x.len() > 40, "{f} has rows");
        assert!(x == y, "{f} differs after resuming");
    }
}

#[test]
fn a_free_falling_wedge_resumed_twice_writes_the_uninterrupted_bytes() {
    // rapier integrates the body every step and the added-mass stabilisation reads the
    // last acceleration; snapshots and energy rows are written across the stops
    let case = case_of(
        "cases/wedge_free_fall.json",
        &[
            "particle_spacing=0.01",
            "time.end=0.012",
            "output.snapshot_interval=0.004",
            "output.energy=true",
        ],
    );
    let (whole, resumed) = (scratch("wedge-whole"), scratch("wedge-resumed"));
    let summary = run_case(&case, &whole, &mut Quiet).unwrap();
    assert_eq!(summary.status, RunStatus::Succeeded);
    run_with_stops(&case, &resumed, &[37, 90]);
    assert_same_files(
        &whole,
        &resumed,
        &[
            "loads.csv",
            "bodies.csv",
            "energy.csv",
            "loads_filtered.csv",
            "snapshots/run.pvd",
        ],
    );
    let read = |d: &Path| {
        serde_json::from_str::<serde_json::Value>(
            &std::fs::read_to_string(d.join("summary.json")).unwrap(),
        )
        .unwrap()
    };
    let (a, b) = (read(&whole), read(&resumed));
    for key in [
        "steps",
        "particle_steps",
        "simulated_time",
        "min_dt",
        "max_dt",
        "max_velocity",
    ] {
        assert_eq!(a[key], b[key], "summary.json {key}");
    }
}

const DAM_BREAK: &str = r#"{
  "name": "resume-dam-break",
  "fluid": { "density": 1000.0, "kinematic_viscosity": 1.0e-6, "gravity": [0.0, -9.81] },
  "particle_spacing": 0.01,
  "domain": { "min": [-0.05, -0.05], "max": [0.65, 0.5] },
  "fluid_blocks": [ { "polygon": [[0.0, 0.0], [0.15, 0.0], [0.15, 0.3], [0.0, 0.3]] } ],
  "walls": [ { "name": "tank", "polyline": [[0.0, 0.45], [0.0, 0.0], [0.6, 0.0], [0.6, 0.45]] } ],
  "time": { "end": 0.06, "cfl": 0.2, "max_dt": 0.0005 },
  "scheme": { "projection": "exact" },
  "output": { "load_interval": 0.001, "probes": [ { "name": "p", "position": [0.05, 0.05] } ] }
}"#;

#[test]
fn a_dam_break_with_the_exact_projection_and_probes_resumes_exactly() {
    // the exact projection carries its correction from one step to the next; the probe
    // rows carry the peak since the last row across the stop
    let case = ValidCase::new(parse_case_str(DAM_BREAK).unwrap(), &Limits::default()).unwrap();
    let (whole, resumed) = (scratch("dam-whole"), scratch("dam-resumed"));
    assert_eq!(
        run_case(&case, &whole, &mut Quiet).unwrap().status,
        RunStatus::Succeeded
    );
    run_with_stops(&case, &resumed, &[1, 55]);
    assert_same_files(
        &whole,
        &resumed,
        &["loads.csv", "probes.csv", "loads_filtered.csv"],
    );
}

#[test]
fn a_checkpoint_of_another_case_is_refused() {
    let case = ValidCase::new(parse_case_str(DAM_BREAK).unwrap(), &Limits::default()).unwrap();
    let dir = scratch("other-case");
    let options = RunOptions {
        checkpoint_on_stop: true,
        ..RunOptions::default()
    };
    run_case_with(&case, &dir, &mut StopAt { at: 3, stop: false }, options).unwrap();
    let saved = Checkpoint::read(&dir.join(checkpoint::FILE)).unwrap();
    let other = parse_case_str(&DAM_BREAK.replace("\"end\": 0.06", "\"end\": 0.07")).unwrap();
    let other = ValidCase::new(other, &Limits::default()).unwrap();
    let options = RunOptions {
        resume: Some(saved),
        ..RunOptions::default()
    };
    let loads = std::fs::read(dir.join("loads.csv")).unwrap();
    match run_case_with(&other, &dir, &mut Quiet, options) {
        Err(RunError::Resume(e)) => assert!(e.to_string().contains("another case"), "{e}"),
        other => panic!("expected a refusal, got {other:?}"),
    }
    assert_eq!(
        std::fs::read(dir.join("loads.csv")).unwrap(),
        loads,
        "untouched"
    );

    // a damaged file is an error, not a panic
    let path = dir.join(checkpoint::FILE);
    let bytes = std::fs::read(&path).unwrap();
    assert!(Checkpoint::from_bytes(&bytes[..bytes.len() / 2]).is_err());
    // one whose header reads but whose state ends early is refused before the run
    // directory is touched
    let (tag, body) = bytes.split_at(8);
    let mut state = Vec::new();
    flate2::read::GzDecoder::new(body)
        .read_to_end(&mut state)
        .unwrap();
    state.truncate(state.len() - 64);
    let mut damaged = tag.to_vec();
    let mut gz = flate2::write::GzEncoder::new(&mut damaged, flate2::Compression::fast());
    gz.write_all(&state).unwrap();
    gz.finish().unwrap();
    let saved = Checkpoint::from_bytes(&damaged).expect("the header reads");
    let options = RunOptions {
        resume: Some(saved),
        ..RunOptions::default()
    };
    match run_case_with(&case, &dir, &mut Quiet, options) {
        Err(RunError::Resume(e)) => assert!(e.to_string().contains("damaged"), "{e}"),
        other => panic!("expected a refusal, got {other:?}"),
    }
    assert_eq!(
        std::fs::read(dir.join("loads.csv")).unwrap(),
        loads,
        "untouched"
    );
}
