//! Checkpoint files: the complete state of a run at the end of a step, from which
//! [`super::run_case_with`] continues exactly as if it had not stopped (the loads of a
//! resumed run are byte-identical to an uninterrupted run's).
//!
//! Layout: an 8-byte tag, then a gzip stream (fast level: the state is mostly f64
//! arrays, which compress to about half, and the compression then costs about as much
//! as the encoding) of postcard pieces: the [`Header`] (case, time, what summary.json
//! needs), the simulation ([`crate::engine::Simulation::save_state`]), the coupling when
//! there are bodies, the run writer (with the CSV rows so far) and the snapshot writer.
//! Written through a temporary file and a rename, so a run killed while it writes one
//! keeps the previous checkpoint.

use crate::case::Case;
use crate::math::Real;
use crate::state_io::{StateError, StateReader, StateWriter};
use flate2::read::GzDecoder;
use flate2::write::GzEncoder;
use serde::{Deserialize, Serialize};
use std::io::{Read, Write};
use std::path::Path;

/// The checkpoint's name in the run directory.
pub const FILE: &str = "checkpoint.bin";

/// The file's first bytes; the last two count layout changes (a checkpoint of another
/// layout is refused, not misread).
const TAG: &[u8; 8] = b"mpsfsi\x00\x01";

/// What a checkpoint says about itself, and the totals summary.json needs.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Header {
    /// The case, as `serde_json` writes the parsed case (resuming checks it is the same).
    pub case_json: String,
    /// Lattice placement ([`crate::engine::Simulation::placed`]).
    pub phase: Option<Real>,
    /// Simulated time and steps taken at the checkpoint.
    pub time: Real,
    pub steps: u64,
    /// Wall-clock seconds of the run before the checkpoint.
    pub wall_time_s: f64,
    /// Extremes of the steps so far (summary.json).
    pub min_dt: Real,
    pub max_dt: Real,
    pub max_velocity: Real,
}

/// The canonical text of a case, as a checkpoint stores it.
pub fn case_text(case: &Case) -> String {
    serde_json::to_string(case).expect("a case serialises")
}

/// A checkpoint read into memory: its header and the rest of the state, unread.
pub struct Checkpoint {
    pub header: Header,
    state: Vec<u8>,
    /// Where the state starts in `state` (after the header).
    start: usize,
}

impl Checkpoint {
    /// Read a checkpoint file.
    pub fn read(path: &Path) -> Result<Self, StateError> {
        Self::from_bytes(&std::fs::read(path)?)
    }

    pub fn from_bytes(bytes: &[u8]) -> Result<Self, StateError> {
        let Some(body) = bytes.strip_prefix(TAG) else {
            return Err(StateError::Mismatch(
                "not a checkpoint of this version of mpsfsi".into(),
            ));
        };
        let mut state = Vec::new();
        GzDecoder::new(body).read_to_end(&mut state)?;
        let (header, rest): (Header, &[u8]) = postcard::take_from_bytes(&state)?;
        let start = state.len() - rest.len();
        Ok(Self {
            header,
            state,
            start,
        })
    }

    /// The case the checkpoint was taken of.
    pub fn case(&self) -> Result<Case, StateError> {
        serde_json::from_str(&self.header.case_json)
            .map_err(|e| StateError::Mismatch(format!("its case does not parse: {e}")))
    }

    /// The pieces after the header, in the order they were written.
    pub fn state(&self) -> StateReader<'_> {
        StateReader::new(&self.state[self.start..])
    }
}

/// Write a checkpoint to `path`: the header, then what `pieces` puts. Returns the
/// file's size in bytes.
pub fn write(
    path: &Path,
    header: &Header,
    pieces: impl FnOnce(&mut StateWriter) -> std::io::Result<()>,
) -> std::io::Result<u64> {
    let mut w = StateWriter::default();
    w.put(header)?;
    pieces(&mut w)?;
    let tmp = path.with_extension("tmp");
    let mut file = std::io::BufWriter::new(std::fs::File::create(&tmp)?);
    file.write_all(TAG)?;
    let mut gz = GzEncoder::new(file, flate2::Compression::fast());
    gz.write_all(w.bytes())?;
    gz.finish()?
        .into_inner()
        .map_err(|e| e.into_error())?
        .sync_all()?;
    std::fs::rename(&tmp, path)?;
    Ok(std::fs::metadata(path)?.len())
}
