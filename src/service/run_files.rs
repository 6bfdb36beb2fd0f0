//! A running job's files in the shared store (Postgres): the CSV files uploaded as
//! they grow ([`SeriesUpload`]) and the checkpoints a later claim resumes from
//! ([`store_checkpoint`]).

use super::series::{self, SeriesFile};
use super::store::{JobStore, PgStore};
use crate::math::Real;
use crate::output::series::complete_lines;
use std::collections::BTreeMap;
use std::path::Path;
use uuid::Uuid;

/// The part of each run CSV file not yet in the shared store: complete lines are
/// appended at their byte offset, so a reader sees whole rows.
pub(super) struct SeriesUpload {
    dir: std::path::PathBuf,
    /// Each file and the bytes of it the store holds; `None` until the first upload
    /// asks the store (a resumed attempt continues after the checkpoint's rows).
    files: Option<Vec<(SeriesFile, u64)>>,
}

/// The run files a running job uploads.
const UPLOADED: [SeriesFile; 4] = [
    series::LOADS,
    series::BODIES,
    series::PROBES,
    series::LOADS_UNCERTAINTY,
];

impl SeriesUpload {
    pub(super) fn new(dir: std::path::PathBuf) -> Self {
        Self { dir, files: None }
    }

    /// Upload what the files gained; `Ok(false)` when the attempt lost the job.
    pub(super) async fn sync(
        &mut self,
        store: &JobStore,
        id: Uuid,
        attempt: i64,
    ) -> Result<bool, std::io::Error> {
        let JobStore::Postgres(pg) = store else {
            return Ok(true);
        };
        if self.files.is_none() {
            let mut files = Vec::new();
            for file in UPLOADED {
                let held = pg.series_length(id, file.file).await;
                files.push((file, held.map_err(std::io::Error::other)?));
            }
            self.files = Some(files);
        }
        for (file, offset) in self.files.iter_mut().flatten() {
            let bytes = match tokio::fs::read(self.dir.join(file.file)).await {
                Ok(b) => b,
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => continue,
                Err(e) => return Err(e),
            };
            let start = (*offset as usize).min(bytes.len());
            let new = complete_lines(&bytes[start..]);
            if new.is_empty() {
                continue;
            }
            match pg.append_series(id, attempt, file.file, *offset, new).await {
                Ok(true) => *offset += new.len() as u64,
                Ok(false) => return Ok(false),
                Err(e) => return Err(std::io::Error::other(e)),
            }
        }
        Ok(true)
    }
}

/// A checkpoint the run saved: its file, and the simulated time and steps it holds.
pub(super) struct Saved<'a> {
    pub path: &'a Path,
    pub time: Real,
    pub steps: u64,
}

/// Store a saved checkpoint with the length each run file of `dir` has at its step (the
/// rows after it are dropped when a claim resumes from it); `Ok(false)` when the attempt
/// no longer holds the job.
pub(super) async fn store_checkpoint(
    pg: &PgStore,
    id: Uuid,
    attempt: i64,
    dir: &Path,
    saved: Saved<'_>,
) -> std::io::Result<bool> {
    let data = tokio::fs::read(saved.path).await?;
    let mut lengths = BTreeMap::new();
    for file in UPLOADED {
        match tokio::fs::metadata(dir.join(file.file)).await {
            Ok(m) => {
                lengths.insert(file.file.to_string(), m.len());
            }
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
            Err(e) => return Err(e),
        }
    }
    pg.save_checkpoint(id, attempt, saved.time, saved.steps, &lengths, &data)
        .await
        .map_err(std::io::Error::other)
}
