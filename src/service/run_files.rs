//! A running job's files in the shared store (Postgres): the CSV files uploaded as
//! they grow and the snapshots as they are written, and the checkpoints a later claim
//! resumes from ([`SeriesUpload`]), and an API node's copy of the
//! snapshots of a job whose worker's directory it cannot read ([`snapshot_dir`]).

use super::series::{self, SeriesFile};
use super::store::{JobStore, PgStore};
use crate::math::Real;
use crate::output::series::complete_lines;
use crate::output::snapshots::{PVD_NAME, SNAPSHOT_DIR};
use flate2::read::GzDecoder;
use flate2::write::GzEncoder;
use std::collections::BTreeMap;
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use uuid::Uuid;

/// The part of each run CSV file not yet in the shared store: complete lines are
/// appended at their byte offset, so a reader sees whole rows.
pub(super) struct SeriesUpload {
    dir: std::path::PathBuf,
    /// Each file and the bytes of it the store holds; `None` until the first upload
    /// asks the store (a resumed attempt continues after the checkpoint's rows).
    files: Option<Vec<(SeriesFile, u64)>>,
    /// The snapshot files uploaded, and the size each had.
    snapshots: BTreeMap<String, u64>,
}

/// The run files a running job uploads.
const UPLOADED: [SeriesFile; 6] = [
    series::LOADS,
    series::BODIES,
    series::PROBES,
    series::LOADS_UNCERTAINTY,
    series::LOADS_FILTERED,
    series::ENERGY,
];

impl SeriesUpload {
    pub(super) fn new(dir: std::path::PathBuf) -> Self {
        Self {
            dir,
            files: None,
            snapshots: BTreeMap::new(),
        }
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
        self.sync_snapshots(pg, id, attempt).await
    }

    /// Store a checkpoint the run saved, after what the run wrote up to it (a snapshot of
    /// the last second is in the store before the checkpoint that lists it), with the
    /// length each run file has at its step (a claim that resumes from it drops the rows
    /// after); `Ok(false)` when the attempt no longer holds the job.
    pub(super) async fn checkpoint(
        &mut self,
        store: &JobStore,
        id: Uuid,
        attempt: i64,
        saved: Saved<'_>,
    ) -> std::io::Result<bool> {
        let JobStore::Postgres(pg) = store else {
            return Ok(true);
        };
        if !self.sync(store, id, attempt).await? {
            return Ok(false);
        }
        let data = tokio::fs::read(saved.path).await?;
        let mut lengths = BTreeMap::new();
        for file in UPLOADED {
            match tokio::fs::metadata(self.dir.join(file.file)).await {
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

    /// Upload the snapshot files written or grown since the last call, gzip-compressed:
    /// the `.vtu` files first, then the collection that lists them.
    async fn sync_snapshots(
        &mut self,
        pg: &PgStore,
        id: Uuid,
        attempt: i64,
    ) -> Result<bool, std::io::Error> {
        let dir = self.dir.join(SNAPSHOT_DIR);
        let mut names = match std::fs::read_dir(&dir) {
            Ok(entries) => entries
                .filter_map(|e| e.ok()?.file_name().into_string().ok())
                .filter(|n| n.ends_with(".vtu") || n == PVD_NAME)
                .collect::<Vec<_>>(),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(true),
            Err(e) => return Err(e),
        };
        names.sort_by_key(|n| (n == PVD_NAME, n.clone()));
        for name in names {
            // a file is read only when it is new or grew (this runs every second, and a
            // job's snapshots are megabytes each)
            let size = match tokio::fs::metadata(dir.join(&name)).await {
                Ok(m) => m.len(),
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => continue,
                Err(e) => return Err(e),
            };
            if self.snapshots.get(&name) == Some(&size) {
                continue;
            }
            let bytes = match tokio::fs::read(dir.join(&name)).await {
                Ok(b) => b,
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => continue,
                Err(e) => return Err(e),
            };
            let key = format!("{SNAPSHOT_DIR}/{name}");
            match pg.put_file(id, attempt, &key, &gzip(&bytes)?).await {
                Ok(true) => {
                    self.snapshots.insert(name, bytes.len() as u64);
                }
                Ok(false) => return Ok(false),
                Err(e) => return Err(std::io::Error::other(e)),
            }
        }
        Ok(true)
    }
}

fn gzip(bytes: &[u8]) -> std::io::Result<Vec<u8>> {
    let mut gz = GzEncoder::new(Vec::new(), flate2::Compression::fast());
    gz.write_all(bytes)?;
    gz.finish()
}

/// Where this node reads a job's snapshots: the worker's run directory when this host
/// can read it (`run_dir`), else `local` (this node's directory of the job), which gets
/// the snapshot files the shared store holds and it lacks (the collection every time:
/// it grows while the job runs). Without a shared store, `local` as it is.
pub async fn snapshot_dir(
    store: &JobStore,
    id: Uuid,
    run_dir: Option<&str>,
    local: PathBuf,
) -> Result<PathBuf, sqlx::Error> {
    if let Some(dir) = run_dir.map(PathBuf::from).filter(|d| d.is_dir()) {
        return Ok(dir);
    }
    let JobStore::Postgres(pg) = store else {
        return Ok(local);
    };
    let stored = pg.file_names(id).await?;
    let dir = local.join(SNAPSHOT_DIR);
    for key in stored {
        let Some(name) = key.strip_prefix(&format!("{SNAPSHOT_DIR}/")) else {
            continue;
        };
        // names the worker wrote: plain file names, nothing that leaves the directory
        let plain = !name.is_empty() && !name.contains(['/', '\\']) && !name.starts_with('.');
        if !plain || (name != PVD_NAME && dir.join(name).is_file()) {
            continue;
        }
        let Some(data) = pg.file(id, &key).await? else {
            continue;
        };
        let written = (|| -> std::io::Result<()> {
            let mut text = Vec::new();
            GzDecoder::new(&data[..]).read_to_end(&mut text)?;
            std::fs::create_dir_all(&dir)?;
            let tmp = dir.join(format!(".{name}.tmp"));
            std::fs::write(&tmp, text)?;
            std::fs::rename(&tmp, dir.join(name))
        })();
        if let Err(e) = written {
            tracing::warn!(error = %e, file = %key, "cannot copy a stored snapshot file");
        }
    }
    Ok(local)
}

/// A checkpoint the run saved: its file, and the simulated time and steps it holds.
pub(super) struct Saved<'a> {
    pub path: &'a Path,
    pub time: Real,
    pub steps: u64,
}
