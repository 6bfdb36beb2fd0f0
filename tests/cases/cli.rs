//! The `mpsfsi` command end to end.

use mpsfsi::case::load_case_file;
use mpsfsi::engine::params::MpsParameters;
use mpsfsi::engine::scene::build_scene;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

fn mpsfsi(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mpsfsi"))
        .args(args)
        .output()
        .expect("mpsfsi runs")
}

fn tiny() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/cases/tiny.json")
}

/// The shipped default job's case.
fn shipped_wedge() -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("cases/wedge_30deg_constant_velocity.json")
        .to_str()
        .unwrap()
        .to_string()
}

/// A fresh directory under the target's test scratch space.
fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("cases-cli-{name}"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

#[test]
fn check_prints_the_particle_count_of_the_scene() {
    let case = load_case_file(&tiny(), &[]).unwrap();
    let expected = build_scene(&case, &MpsParameters::new(&case))
        .particles
        .len();
    assert!(expected > 0);
    let out = mpsfsi(&["check", tiny().to_str().unwrap()]);
    let stdout = text(&out.stdout);
    assert!(
        out.status.success(),
        "stdout {stdout}\nstderr {}",
        text(&out.stderr)
    );
    assert!(
        stdout.contains(&format!("particles: {expected} ")),
        "{stdout}"
    );
    assert!(
        stdout.contains("estimated steps:") && stdout.contains("n0 = "),
        "{stdout}"
    );
}

#[test]
fn check_applies_overrides() {
    let out = mpsfsi(&[
        "check",
        tiny().to_str().unwrap(),
        "--set",
        "particle_spacing=0.005",
    ]);
    let stdout = text(&out.stdout);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let mut case = load_case_file(&tiny(), &[]).unwrap();
    case.particle_spacing = 0.005;
    let expected = build_scene(&case, &MpsParameters::new(&case))
        .particles
        .len();
    assert!(
        stdout.contains(&format!("particles: {expected} ")),
        "{stdout}"
    );
}

#[test]
fn check_enforces_a_particle_limit() {
    let out = mpsfsi(&["check", tiny().to_str().unwrap(), "--max-particles", "10"]);
    assert_eq!(out.status.code(), Some(2));
    let stderr = text(&out.stderr);
    assert!(
        stderr.contains("particle_spacing:") && stderr.contains("limit of 10"),
        "{stderr}"
    );
}

#[test]
fn run_writes_the_run_directory() {
    let dir = scratch("run");
    let out = mpsfsi(&[
        "run",
        tiny().to_str().unwrap(),
        "--out",
        dir.to_str().unwrap(),
    ]);
    let (stdout, stderr) = (text(&out.stdout), text(&out.stderr));
    assert!(out.status.success(), "stdout {stdout}\nstderr {stderr}");
    assert!(
        stdout.starts_with("succeeded:") && stdout.lines().count() == 1,
        "{stdout}"
    );
    // not a terminal: no progress bar
    assert!(stderr.is_empty(), "{stderr}");
    let loads = std::fs::read_to_string(dir.join("loads.csv")).expect("loads.csv");
    assert!(loads.starts_with("time,body,fx,fy,mz"), "{loads}");
    assert!(
        loads.lines().skip(1).any(|l| l.contains(",tank,")),
        "{loads}"
    );
    let summary: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.join("summary.json")).expect("summary.json"),
    )
    .unwrap();
    assert_eq!(summary["status"], "succeeded");
    assert!(
        (summary["simulated_time"].as_f64().unwrap() - 0.01).abs() < 1e-9,
        "{summary}"
    );
    assert!(summary["particles"].as_u64().unwrap() > 0);
}

#[test]
fn run_rejects_a_bad_case_with_the_path() {
    let dir = scratch("bad");
    let out = mpsfsi(&[
        "run",
        tiny().to_str().unwrap(),
        "--out",
        dir.to_str().unwrap(),
        "--set",
        "fluid.density=-1",
    ]);
    assert_eq!(out.status.code(), Some(2));
    let stderr = text(&out.stderr);
    assert!(
        stderr.contains("fluid.density") && stderr.contains("positive"),
        "{stderr}"
    );
    assert_eq!(stderr.trim_end().lines().count(), 1, "one line: {stderr}");
    assert!(
        !dir.join("summary.json").exists(),
        "no work on a rejected case"
    );
}

#[test]
fn unknown_scheme_name_reaches_the_user() {
    let out = mpsfsi(&[
        "check",
        tiny().to_str().unwrap(),
        "--set",
        "scheme.gradient=fancy",
    ]);
    assert_eq!(out.status.code(), Some(2));
    let stderr = text(&out.stderr);
    assert!(
        stderr.contains("scheme.gradient")
            && stderr.contains("fancy")
            && stderr.contains("corrected"),
        "{stderr}"
    );
}

#[test]
fn bad_json_and_missing_file_are_one_line_errors() {
    let dir = scratch("json");
    let broken = dir.join("broken.json");
    std::fs::write(&broken, "{ \"name\": ").unwrap();
    for path in [broken.clone(), dir.join("missing.json")] {
        let out = mpsfsi(&["check", path.to_str().unwrap()]);
        assert_eq!(out.status.code(), Some(2));
        let stderr = text(&out.stderr);
        assert!(
            stderr.starts_with("error: invalid case:") && stderr.trim_end().lines().count() == 1,
            "{stderr}"
        );
    }
}

#[test]
fn schema_prints_the_committed_schema() {
    let out = mpsfsi(&["schema"]);
    assert!(out.status.success());
    assert_eq!(text(&out.stdout), mpsfsi::case::schema::case_schema_json());
}

#[test]
fn failed_run_exits_non_zero_and_keeps_its_directory() {
    // particles launched at 5 m/s against a 1 m/s speed limit fail on the first step
    let dir = scratch("failed");
    let out = mpsfsi(&[
        "run",
        tiny().to_str().unwrap(),
        "--out",
        dir.to_str().unwrap(),
        "--set",
        "fluid_blocks[0].velocity=[0.0, -5.0]",
        "--set",
        "scheme.max_speed=1.0",
    ]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = text(&out.stderr);
    assert!(
        stderr.starts_with("error: run failed:") && stderr.contains("runaway"),
        "{stderr}"
    );
    let summary: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.join("summary.json")).expect("summary.json"),
    )
    .unwrap();
    assert_eq!(summary["status"], "failed");
    assert!(dir.join("loads.csv").exists(), "what was written stays");
}

#[test]
fn serve_and_bench_parse_their_flags() {
    // whatever they do in this build, the flags of README.md are accepted:
    // clap's usage error is exit code 2 with "unexpected argument"
    let out = mpsfsi(&["serve", "--addr", "not-an-address"]);
    assert_eq!(out.status.code(), Some(2), "a bad address is a usage error");
    let out = mpsfsi(&["bench", "--help"]);
    assert!(out.status.success());
    let help = text(&out.stdout);
    for flag in ["--quick", "--operators", "--stress", "--out"] {
        assert!(help.contains(flag), "{flag} missing: {help}");
    }
    let out = mpsfsi(&["serve", "--help"]);
    let help = text(&out.stdout);
    for flag in [
        "--addr",
        "--data",
        "--workers",
        "--queue-capacity",
        "--max-particles",
        "--max-body-bytes",
        "--token-file",
        "MPSFSI_TOKEN",
    ] {
        assert!(help.contains(flag), "{flag} missing: {help}");
    }
}

/// Kills the child if the test fails before it exits.
struct KillOnDrop(Child);

impl Drop for KillOnDrop {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

fn data_rows(path: &Path) -> usize {
    std::fs::read_to_string(path).map_or(0, |t| t.lines().count().saturating_sub(1))
}

/// Ctrl-C (SIGINT) or SIGTERM in the middle of a run that would go on for minutes: the
/// run ends after its current step, exit code 1, summary.json `cancelled` with the
/// signal in its reason, and every output kept up to the time it reached.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
#[test]
fn a_signal_ends_the_run_with_its_outputs_and_a_cancelled_summary() {
    let case = load_case_file(&tiny(), &[]).unwrap();
    let interval = case.output.load_interval.seconds(case.time.end).unwrap();
    let end = 1000.0; // over 10^6 steps at max_dt
    for (signal, name) in [(libc::SIGINT, "SIGINT"), (libc::SIGTERM, "SIGTERM")] {
        let dir = scratch(&format!("signal-{name}"));
        let child = Command::new(env!("CARGO_BIN_EXE_mpsfsi"))
            .args([
                "run",
                tiny().to_str().unwrap(),
                "--out",
                dir.to_str().unwrap(),
            ])
            .args(["--set", &format!("time.end={end}")])
            .args(["--set", "output.snapshot_interval=0.05"])
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .expect("mpsfsi runs");
        let mut child = KillOnDrop(child);
        let started = Instant::now();
        while data_rows(&dir.join("loads.csv")) < 5 {
            assert!(
                child.0.try_wait().unwrap().is_none(),
                "{name}: the run ended before the signal"
            );
            assert!(
                started.elapsed() < Duration::from_secs(60),
                "{name}: no loads after a minute"
            );
            std::thread::sleep(Duration::from_millis(20));
        }
        let pid = child.0.id() as libc::pid_t;
        // SAFETY: kill(2) on our own child, which has not been waited for (still running)
        assert_eq!(unsafe { libc::kill(pid, signal) }, 0, "{name}: kill");
        let signalled = Instant::now();
        let status = loop {
            if let Some(status) = child.0.try_wait().unwrap() {
                break status;
            }
            assert!(
                signalled.elapsed() < Duration::from_secs(60),
                "{name}: still running a minute after the signal"
            );
            std::thread::sleep(Duration::from_millis(20));
        };
        let mut stderr = String::new();
        std::io::Read::read_to_string(child.0.stderr.as_mut().unwrap(), &mut stderr).unwrap();
        assert_eq!(status.code(), Some(1), "{name}: {stderr}");
        assert!(
            stderr.contains("interrupted") && stderr.contains("error: run cancelled:"),
            "{name}: {stderr}"
        );

        let summary: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(dir.join("summary.json")).expect("summary.json"),
        )
        .unwrap();
        assert_eq!(summary["status"], "cancelled", "{name}: {summary}");
        let reason = summary["reason"].as_str().unwrap_or_default();
        assert!(
            reason.contains("interrupted") && reason.contains(name),
            "{name}: {reason}"
        );
        let t = summary["simulated_time"].as_f64().unwrap();
        assert!(t > 0.0 && t < end, "{name}: {summary}");
        assert!(summary["steps"].as_u64().unwrap() > 0, "{name}: {summary}");

        // the loads up to the last whole sample interval before t
        let loads = std::fs::read_to_string(dir.join("loads.csv")).unwrap();
        let last: f64 = loads
            .lines()
            .last()
            .and_then(|l| l.split(',').next())
            .and_then(|v| v.parse().ok())
            .expect("a last data row");
        assert!(
            last <= t + 1e-9 && t - last <= 2.0 * interval,
            "{name}: last load at {last} s, summary at {t} s"
        );
        for file in ["loads_filtered.csv", "probes.csv", "snapshots/run.pvd"] {
            assert!(dir.join(file).exists(), "{name}: {file} missing");
        }
    }
}

#[test]
fn plot_draws_a_snapshot_of_a_run_and_refuses_what_it_cannot_draw() {
    let dir = scratch("plot");
    let run = mpsfsi(&[
        "run",
        tiny().to_str().unwrap(),
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(run.status.success(), "{}", text(&run.stderr));
    let svg = dir.join("flow.svg");
    let out = mpsfsi(&[
        "plot",
        dir.to_str().unwrap(),
        "--time",
        "0.005",
        "--field",
        "speed",
        "--window",
        "-0.01,0.11,-0.01,0.08",
        "--out",
        svg.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let picture = std::fs::read_to_string(&svg).unwrap();
    // 50 particles, the tank's three walls, a colour bar labelled by the field
    assert!(picture.matches("<rect").count() > 50, "particle marks");
    assert!(picture.contains("stroke-width=\"2\""), "the tank's walls");
    assert!(picture.contains("speed (m/s)"));
    // the tiny tank's snapshots are at k * 1 ms: 0.005 s picks the one at 5 ms
    assert!(
        text(&out.stdout).starts_with("t = 0.005"),
        "{}",
        text(&out.stdout)
    );

    let bad_field = mpsfsi(&[
        "plot",
        dir.to_str().unwrap(),
        "--field",
        "vorticity",
        "--out",
        "x.svg",
    ]);
    assert_eq!(bad_field.status.code(), Some(2));
    assert!(text(&bad_field.stderr).contains("expected one of pressure, speed"));
    let bad_window = mpsfsi(&[
        "plot",
        dir.to_str().unwrap(),
        "--window",
        "1,0,zero,1",
        "--out",
        "x.svg",
    ]);
    assert_eq!(bad_window.status.code(), Some(2));
    let empty = scratch("plot-empty");
    let none = mpsfsi(&["plot", empty.to_str().unwrap(), "--out", "x.svg"]);
    assert_eq!(none.status.code(), Some(3));
    assert!(
        text(&none.stderr).contains("has no snapshots"),
        "{}",
        text(&none.stderr)
    );
}

/// `plot --surface`: the pressure along a body of the tiny tank (a box pushed into it at
/// 1 m/s, so Cp), along a wall (still, so kPa); an unknown name is refused with the
/// bodies and walls listed, and `--surface` does not go with `--field` or `--window`.
#[test]
fn plot_surface_draws_the_pressure_along_a_body_and_names_the_bodies_it_has() {
    let dir = scratch("plot-surface");
    let body = r#"bodies=[{"name": "float", "polygon": [[-0.02, 0.0], [0.02, 0.0], [0.02, 0.02], [-0.02, 0.02]], "position": [0.05, 0.052], "motion": {"type": "prescribed", "velocity": [0.0, -1.0]}}]"#;
    let run = mpsfsi(&[
        "run",
        tiny().to_str().unwrap(),
        "--out",
        dir.to_str().unwrap(),
        "--set",
        body,
    ]);
    assert!(run.status.success(), "{}", text(&run.stderr));
    let svg = dir.join("surface.svg");
    let out = mpsfsi(&[
        "plot",
        dir.to_str().unwrap(),
        "--surface",
        "float",
        "--time",
        "0.005",
        "--out",
        svg.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    // the snapshot nearest 5 ms (one every millisecond, each at the first step after its time)
    let stdout = text(&out.stdout);
    let t: f64 = stdout
        .strip_prefix("t = ")
        .and_then(|rest| rest.split(' ').next())
        .and_then(|t| t.parse().ok())
        .unwrap_or_else(|| panic!("{stdout}"));
    assert!((t - 0.005).abs() < 1e-3, "{stdout}");
    let picture = std::fs::read_to_string(&svg).unwrap();
    // the case's name and the time in the title; Cp against the arc length, one line
    // per face of the box
    for part in [
        &format!(
            "tiny-water-block: pressure along float, t = {:.3} ms",
            t * 1e3
        ),
        "Cp = p / (½ρV²), V = 1.000 m/s",
        "along the surface from vertex 0 (m)",
    ] {
        assert!(picture.contains(part), "{part:?} missing");
    }
    assert_eq!(picture.matches("stroke-width=\"2\"").count(), 4);
    let tank = mpsfsi(&[
        "plot",
        dir.to_str().unwrap(),
        "--surface",
        "tank",
        "--out",
        svg.to_str().unwrap(),
    ]);
    assert!(tank.status.success(), "{}", text(&tank.stderr));
    assert!(std::fs::read_to_string(&svg).unwrap().contains("p (kPa)"));

    let unknown = mpsfsi(&[
        "plot",
        dir.to_str().unwrap(),
        "--surface",
        "hull",
        "--out",
        "x.svg",
    ]);
    assert_eq!(unknown.status.code(), Some(2));
    assert!(
        text(&unknown.stderr)
            .contains("no body named \"hull\" in this run (bodies: float; walls: tank)"),
        "{}",
        text(&unknown.stderr)
    );
    for other in [["--field", "speed"], ["--window", "0,1,0,1"]] {
        let both = mpsfsi(&[
            "plot",
            dir.to_str().unwrap(),
            "--surface",
            "float",
            other[0],
            other[1],
            "--out",
            "x.svg",
        ]);
        assert_eq!(both.status.code(), Some(2), "{other:?}");
        assert!(
            text(&both.stderr).contains("cannot be used with"),
            "{other:?}"
        );
    }
}

#[test]
fn check_reports_the_layout_of_each_spacing() {
    let wedge = shipped_wedge();
    let wedge = wedge.as_str();
    let case = load_case_file(
        std::path::Path::new(wedge),
        &["particle_spacing=0.02".into()],
    )
    .unwrap();
    let scene = build_scene(&case, &MpsParameters::new(&case));
    let count = |scale: f64| scene.particles.count_of_scale(scale);
    let (fine, coarse, far) = (count(1.0), count(2.0), count(4.0));
    assert_eq!(fine + coarse + far, scene.particles.len());
    assert!(
        fine > 0 && coarse > 0 && far > 0,
        "{fine} / {coarse} / {far}"
    );
    let out = mpsfsi(&["check", wedge, "--set", "particle_spacing=0.02"]);
    let stdout = text(&out.stdout);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(
        stdout.contains(&format!(
            "layout: multi-resolution, {fine} particles of 0.02 m, {coarse} of 0.04 m and {far} of 0.08 m"
        )),
        "{stdout}"
    );
    let out = mpsfsi(&[
        "check",
        wedge,
        "--set",
        "particle_spacing=0.02",
        "--set",
        "refinement=\"none\"",
    ]);
    let stdout = text(&out.stdout);
    assert!(stdout.contains("layout: one spacing, 0.02 m"), "{stdout}");
}

#[test]
fn check_advises_on_a_body_outside_the_validated_impact_envelope() {
    let wedge = shipped_wedge();
    let wedge = wedge.as_str();
    // the shipped wedge: 0.5 m across at 5 mm, 30°
    let out = mpsfsi(&["check", wedge]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(
        !text(&out.stdout).contains("advice"),
        "{}",
        text(&out.stdout)
    );
    // the same at 2 cm: 25 spacings across
    let out = mpsfsi(&["check", wedge, "--set", "particle_spacing=0.02"]);
    let stdout = text(&out.stdout);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(
        stdout.contains("advice: body wedge: 25 spacings across"),
        "{stdout}"
    );
    // a run says it on stderr and keeps it in summary.json
    let dir = scratch("advice");
    let out = mpsfsi(&[
        "run",
        wedge,
        "--out",
        dir.to_str().unwrap(),
        "--set",
        "particle_spacing=0.02",
        "--set",
        "time.end=0.0005",
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(
        text(&out.stderr).contains("advice: body wedge: 25 spacings across"),
        "{}",
        text(&out.stderr)
    );
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    let advice = summary["advice"].as_array().expect("an advice array");
    assert_eq!(advice.len(), 1, "{advice:?}");
    assert!(
        advice[0]
            .as_str()
            .unwrap()
            .starts_with("body wedge: 25 spacings across"),
        "{advice:?}"
    );
}

/// `--uncertainty` runs the ladder (its parts named on stderr) and writes the half-width
/// files next to the usual run directory; a case too shallow for four levels is
/// rejected before any work, on `particle_spacing`.
#[test]
fn run_with_uncertainty_writes_the_ladder_files() {
    let dir = scratch("uncertainty");
    let out = mpsfsi(&[
        "run",
        tiny().to_str().unwrap(),
        "--out",
        dir.to_str().unwrap(),
        "--uncertainty",
    ]);
    let (stdout, stderr) = (text(&out.stdout), text(&out.stderr));
    assert!(out.status.success(), "stdout {stdout}\nstderr {stderr}");
    assert!(stderr.contains("part 7 of 7: level 3"), "{stderr}");
    assert!(
        stdout.contains("uncertainty: 4 levels, ratio 1.25"),
        "{stdout}"
    );
    let loads = std::fs::read_to_string(dir.join("loads_uncertainty.csv")).unwrap();
    assert!(
        loads.starts_with("time,body,fx,fy,mz,u_fx,u_fy,u_mz\n"),
        "{loads}"
    );
    let rows = std::fs::read_to_string(dir.join("loads.csv"))
        .unwrap()
        .lines()
        .count();
    assert_eq!(loads.lines().count(), rows, "one row per loads.csv row");
    let probes = std::fs::read_to_string(dir.join("probes_uncertainty.csv")).unwrap();
    assert!(
        probes.starts_with("time,probe,pressure,u_pressure\n"),
        "{probes}"
    );
    assert!(dir.join("levels/level_3_member_3/loads.csv").exists());
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    let levels = summary["uncertainty"]["levels"].as_array().unwrap();
    assert_eq!(levels.len(), 4);
    assert_eq!(levels[3]["members"], 4);
    let spacings: Vec<f64> = levels
        .iter()
        .map(|l| l["spacing"].as_f64().unwrap())
        .collect();
    assert!(spacings.windows(2).all(|w| w[1] > w[0]), "{spacings:?}");
    // the load plot shades the band (one area per body and panel)
    let svg = dir.join("loads.svg");
    let plot = mpsfsi(&[
        "plot",
        dir.to_str().unwrap(),
        "--loads",
        "--out",
        svg.to_str().unwrap(),
    ]);
    assert!(plot.status.success(), "{}", text(&plot.stderr));
    let svg = std::fs::read_to_string(svg).unwrap();
    assert_eq!(
        svg.matches("<polygon").count(),
        3,
        "the tank's band in 3 panels"
    );

    let shallow = scratch("uncertainty_shallow");
    let out = mpsfsi(&[
        "run",
        tiny().to_str().unwrap(),
        "--out",
        shallow.to_str().unwrap(),
        "--uncertainty",
        "--set",
        "particle_spacing=0.02",
    ]);
    assert_eq!(out.status.code(), Some(2));
    let stderr = text(&out.stderr);
    assert!(
        stderr.contains("particle_spacing: --uncertainty needs 4 levels"),
        "{stderr}"
    );
    assert!(!shallow.join("loads.csv").exists());
}

/// A ladder stopped in its second part keeps the user's complete run: summary.json says
/// `cancelled`, names the part, and loads.csv has every row of the user's level.
#[test]
fn a_ladder_stopped_in_a_coarser_level_keeps_the_user_s_run() {
    use mpsfsi::case::{Limits, ValidCase};
    use mpsfsi::run::{Observer, RunStatus};
    struct StopInPart(usize);
    impl Observer for StopInPart {
        fn part(&mut self, index: usize, _count: usize, _label: &str) {
            self.0 = index;
        }
        fn is_cancelled(&self) -> bool {
            self.0 >= 1
        }
    }
    let dir = scratch("uncertainty_stopped");
    let case = ValidCase::new(load_case_file(&tiny(), &[]).unwrap(), &Limits::default()).unwrap();
    let summary =
        mpsfsi::run::uncertainty::run_with_uncertainty(&case, &dir, &mut StopInPart(0)).unwrap();
    assert_eq!(summary.status, RunStatus::Cancelled);
    let reason = summary.reason.unwrap();
    assert!(
        reason.contains("part 2 of 7") && reason.contains("the user's level completed"),
        "{reason}"
    );
    let written: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    assert_eq!(written["status"], "cancelled");
    assert!((written["simulated_time"].as_f64().unwrap() - 0.01).abs() < 1e-12);
    let rows = std::fs::read_to_string(dir.join("loads.csv"))
        .unwrap()
        .lines()
        .count();
    assert_eq!(rows, 1 + 5, "0.01 s at 2 ms, one wall");
    assert!(!dir.join("loads_uncertainty.csv").exists());
}

/// Ctrl-C saves the run's state; `mpsfsi run --resume DIR` continues it to the end, and
/// its loads and probes are the uninterrupted run's, byte for byte. A finished run, or a
/// directory without a checkpoint, has nothing to resume: a one-line error.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
#[test]
fn resume_after_ctrl_c_gives_the_uninterrupted_loads() {
    let (whole, stopped) = (scratch("resume-whole"), scratch("resume-stopped"));
    let args = |dir: &Path| {
        vec![
            "run".to_string(),
            tiny().to_str().unwrap().to_string(),
            "--out".to_string(),
            dir.to_str().unwrap().to_string(),
            "--set".to_string(),
            "time.end=4".to_string(), // 4000 steps, seconds of work
        ]
    };
    let done = Command::new(env!("CARGO_BIN_EXE_mpsfsi"))
        .args(args(&whole))
        .output()
        .unwrap();
    assert!(done.status.success(), "{}", text(&done.stderr));

    let child = Command::new(env!("CARGO_BIN_EXE_mpsfsi"))
        .args(args(&stopped))
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut child = KillOnDrop(child);
    let started = Instant::now();
    while data_rows(&stopped.join("loads.csv")) < 5 {
        assert!(
            child.0.try_wait().unwrap().is_none(),
            "ended before the signal"
        );
        assert!(started.elapsed() < Duration::from_secs(60), "no loads");
        std::thread::sleep(Duration::from_millis(10));
    }
    // SAFETY: kill(2) on our own child, not yet waited for
    assert_eq!(
        unsafe { libc::kill(child.0.id() as libc::pid_t, libc::SIGINT) },
        0
    );
    let status = child.0.wait().unwrap();
    let mut stderr = String::new();
    std::io::Read::read_to_string(child.0.stderr.as_mut().unwrap(), &mut stderr).unwrap();
    assert_eq!(status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("--resume"),
        "the user is told how to go on: {stderr}"
    );
    assert!(stopped.join("checkpoint.bin").exists());
    let cut = data_rows(&stopped.join("loads.csv"));
    assert!(
        cut < data_rows(&whole.join("loads.csv")),
        "stopped before the end"
    );

    let resumed = mpsfsi(&["run", "--resume", stopped.to_str().unwrap()]);
    assert!(resumed.status.success(), "{}", text(&resumed.stderr));
    assert!(text(&resumed.stderr).contains("resuming tiny-water-block at step"));
    for file in ["loads.csv", "probes.csv", "loads_filtered.csv"] {
        let (a, b) = (
            std::fs::read(whole.join(file)),
            std::fs::read(stopped.join(file)),
        );
        assert!(
            a.unwrap() == b.unwrap(),
            "{file} differs from the uninterrupted run's"
        );
    }

    let again = mpsfsi(&["run", "--resume", stopped.to_str().unwrap()]);
    assert_eq!(again.status.code(), Some(3));
    assert!(text(&again.stderr).contains("finished: there is nothing to resume"));
    let empty = scratch("resume-empty");
    let none = mpsfsi(&["run", "--resume", empty.to_str().unwrap()]);
    assert_eq!(none.status.code(), Some(3));
    assert!(
        text(&none.stderr).contains("has no checkpoint.bin"),
        "{}",
        text(&none.stderr)
    );
    let both = mpsfsi(&[
        "run",
        tiny().to_str().unwrap(),
        "--resume",
        empty.to_str().unwrap(),
    ]);
    assert_eq!(
        both.status.code(),
        Some(2),
        "clap refuses CASE with --resume"
    );
}
