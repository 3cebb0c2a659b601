//! `--checkpoint FILE` and `--resume FILE`: a render's checkpoints on disk. A checkpoint
//! (`session::checkpoint`) is written atomically every `--checkpoint-interval` seconds (checked
//! after each pass) and when the render is interrupted; it is removed once the image is
//! written. `--resume` reads one, which must be of the same run (stage, options), and the
//! render continues from it to the same image as an uninterrupted one.

use crate::error::{Error, Result};
use crate::output::atomic::write_atomically;
use crate::session::checkpoint::Checkpoint;
use crate::session::ImageSession;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// Default seconds between checkpoints.
pub const DEFAULT_INTERVAL: f64 = 60.0;

/// Where and how often a render saves its state.
pub struct Checkpoints {
    path: Option<PathBuf>,
    interval: Duration,
    last: Instant,
}

impl Checkpoints {
    pub fn new(path: Option<PathBuf>, interval_s: f64) -> Checkpoints {
        Checkpoints {
            path,
            interval: Duration::from_secs_f64(interval_s),
            last: Instant::now(),
        }
    }

    /// Writes a checkpoint when one is asked for and the interval has passed.
    pub fn after_pass(&mut self, session: &ImageSession) -> Result<()> {
        if self.path.is_some() && self.last.elapsed() >= self.interval {
            self.write(session)?;
        }
        Ok(())
    }

    /// Writes a checkpoint now (when one is asked for); returns its path.
    pub fn write(&mut self, session: &ImageSession) -> Result<Option<&Path>> {
        let Some(path) = &self.path else {
            return Ok(None);
        };
        let bytes = session.checkpoint().encode();
        write_atomically(path, |f| f.write_all(&bytes))
            .map_err(|e| Error::io(path, format!("cannot write the checkpoint: {e}")))?;
        self.last = Instant::now();
        Ok(Some(path))
    }

    /// Removes the checkpoint once the render's outputs are written.
    pub fn finished(&self) {
        if let Some(path) = &self.path {
            let _ = std::fs::remove_file(path);
        }
    }
}

/// Reads a checkpoint file (a regular file in the checkpoint format).
pub fn read(path: &Path) -> Result<Checkpoint> {
    let fail = |reason: String| Error::io(path, format!("--resume: {reason}"));
    let meta = std::fs::metadata(path).map_err(|e| fail(e.to_string()))?;
    if !meta.is_file() {
        return Err(fail("not a regular file".into()));
    }
    let bytes = std::fs::read(path).map_err(|e| fail(e.to_string()))?;
    Checkpoint::decode(&bytes).map_err(fail)
}
