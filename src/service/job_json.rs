//! The JSON form of a job record (`Job` in api/openapi.yaml).

use super::store::{JobRow, JobStatus};
use serde_json::{json, Value};

/// The JSON form of a job record.
pub fn job_json(row: &JobRow) -> Value {
    // a ladder's parts count equally: k coarser parts ended and the user's level at
    // fraction f of its end time is (k + f) / parts
    let parts = row.parts.max(1) as f64;
    let fraction = match row.status {
        JobStatus::Succeeded => 1.0,
        _ if row.end_time > 0.0 => {
            (row.part as f64 + (row.simulated_time / row.end_time).clamp(0.0, 1.0)) / parts
        }
        _ => 0.0,
    };
    let summary = row
        .summary
        .as_deref()
        .and_then(|s| serde_json::from_str::<Value>(s).ok());
    let base = format!("/v1/jobs/{}", row.id);
    json!({
        "id": row.id.to_string(),
        "name": row.name,
        "status": row.status.as_str(),
        "created_at": row.created_at,
        "started_at": row.started_at,
        "finished_at": row.finished_at,
        "progress": {
            "step": row.step,
            "simulated_time": row.simulated_time,
            "end_time": row.end_time,
            "fraction": fraction.clamp(0.0, 1.0),
            "part": row.part,
            "parts": row.parts,
        },
        "particles": row.particles,
        "reason": row.reason,
        "summary": summary,
        "attempts": row.attempts,
        "worker": row.worker,
        "run_dir": row.run_dir,
        "uncertainty": row.uncertainty,
        "resumed_from": row.resumed_from,
        "links": {
            "self": base,
            "loads": format!("{base}/loads"),
            "loads_uncertainty": format!("{base}/loads_uncertainty"),
            "loads_filtered": format!("{base}/loads_filtered"),
            "loads_svg": format!("{base}/loads.svg"),
            "snapshot_svg": format!("{base}/snapshot.svg"),
            "surface_svg": format!("{base}/surface.svg"),
            "bodies": format!("{base}/bodies"),
            "probes": format!("{base}/probes"),
            "cancel": format!("{base}/cancel"),
        },
    })
}
