//! The particle limit in force is the service's own (`max_particles`), at submission and
//! when a worker runs the job: `run_case` does not validate again against other limits.

use crate::helpers::{fresh_data_dir, long_case, spawn_app, spawn_app_on, tiny_case};
use mpsfsi::case::{estimated_particles, parse_case_value, Limits};
use serde_json::{json, Value};

/// The tiny tank with its one fluid block repeated `copies` times: the estimate
/// (block areas / l0²) counts every copy, the scene fills each lattice site once.
fn overlapping_blocks_case(copies: usize) -> Value {
    let mut case = tiny_case(0.001);
    let block = case["fluid_blocks"][0].clone();
    case["fluid_blocks"] = json!(vec![block; copies]);
    case
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_service_with_a_limit_above_the_default_runs_what_it_accepts() {
    let case = overlapping_blocks_case(7_000);
    let estimate = estimated_particles(&parse_case_value(case.clone()).unwrap()).unwrap();
    let default_limit = Limits::default().max_particles;
    assert!(
        estimate > default_limit as f64,
        "the estimate {estimate} is above the default limit {default_limit}"
    );

    let app = spawn_app("limit-above-default", |c| c.max_particles = 3_000_000).await;
    let id = app.submit(&case).await;
    let job = app.wait_finished(&id).await;
    assert_eq!(job["status"], "succeeded", "{job:#}");
    let particles = job["particles"].as_u64().unwrap();
    assert!(
        (1..=300).contains(&particles),
        "one particle per lattice site of the single block: {particles}"
    );
    app.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_job_queued_under_a_higher_limit_fails_as_invalid_after_a_restart_with_a_lower_one() {
    let data = fresh_data_dir("limit-lowered");
    let app = spawn_app_on(data.clone(), |c| c.workers = 1).await;
    // the one worker is busy, so the tiny job stays queued through the shutdown
    let running = app.submit(&long_case()).await;
    app.wait_running(&running).await;
    let waiting = app.submit(&tiny_case(0.002)).await;
    app.stop().await;

    // the tiny tank estimates 300 particles
    let app = spawn_app_on(data, |c| {
        c.workers = 1;
        c.max_particles = 100;
    })
    .await;
    let job = app.wait_finished(&waiting).await;
    assert_eq!(job["status"], "failed", "{job:#}");
    let reason = job["reason"].as_str().unwrap();
    assert!(
        reason.starts_with("invalid case: particle_spacing") && reason.contains("limit of 100"),
        "{reason}"
    );
    assert_eq!(job["progress"]["step"], 0, "nothing ran: {job:#}");
    app.stop().await;
}
