//! What a batch leaves behind: per song `DIR/<id>/done.json` (written atomically after its
//! outputs, so its presence means the song is complete) and one line per song and run in
//! `DIR/results.jsonl`, appended under an exclusive file lock so shards sharing `DIR` never
//! interleave their lines.

use std::fs::{File, OpenOptions, TryLockError};
use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use serde::Serialize;

/// The marker of a finished song.
pub const DONE_FILE: &str = "done.json";
/// The batch's log of songs, one JSON object per line.
pub const RESULTS_FILE: &str = "results.jsonl";
/// Held (by an OS file lock) while a process generates the song, so two processes given the
/// same shard never generate one song twice at once.
const LOCK_FILE: &str = ".batch.lock";

/// `done.json`: enough to find and reproduce the song.
#[derive(Serialize)]
pub struct Done<'a> {
    pub id: &'a str,
    /// The manifest line (1-based).
    pub line: usize,
    pub seed: u64,
    /// Files written, as names in the song's folder.
    pub outputs: Vec<String>,
    /// The `dancegen generate` call that gives the same bytes.
    pub command: Vec<String>,
    pub seconds: f64,
}

/// One line of `results.jsonl`.
#[derive(Serialize)]
pub struct Outcome<'a> {
    /// `null` for a line whose id could not be read.
    pub id: Option<&'a str>,
    pub line: usize,
    pub error: Option<String>,
    pub skipped: bool,
    pub seconds: f64,
}

pub fn done_path(song_dir: &Path) -> PathBuf {
    song_dir.join(DONE_FILE)
}

pub fn write_done(song_dir: &Path, done: &Done<'_>) -> Result<()> {
    let path = done_path(song_dir);
    let json = serde_json::to_vec_pretty(done)?;
    dancegen_io::write_atomic(&path, |w| {
        w.write_all(&json)?;
        w.write_all(b"\n")
    })?;
    Ok(())
}

/// Appends `outcome` to `DIR/results.jsonl` as one write under an exclusive lock.
pub fn append_outcome(out_dir: &Path, outcome: &Outcome<'_>) -> Result<()> {
    let path = out_dir.join(RESULTS_FILE);
    let mut line = serde_json::to_vec(outcome)?;
    line.push(b'\n');
    let mut file = OpenOptions::new()
        .create(true)
        .append(true)
        .open(&path)
        .with_context(|| format!("{}: cannot open", path.display()))?;
    file.lock()
        .with_context(|| format!("{}: cannot lock", path.display()))?;
    let written = file.write_all(&line).and_then(|()| file.sync_data());
    let _ = file.unlock();
    written.with_context(|| format!("{}: cannot append", path.display()))
}

/// The song's lock, held until dropped; `None` when another process holds it.
pub struct SongLock {
    _file: File,
}

pub fn try_lock_song(song_dir: &Path) -> Result<Option<SongLock>> {
    let path = song_dir.join(LOCK_FILE);
    let file = OpenOptions::new()
        .create(true)
        .truncate(false)
        .write(true)
        .open(&path)
        .with_context(|| format!("{}: cannot open", path.display()))?;
    match file.try_lock() {
        Ok(()) => Ok(Some(SongLock { _file: file })),
        Err(TryLockError::WouldBlock) => Ok(None),
        Err(TryLockError::Error(e)) => {
            Err(e).with_context(|| format!("{}: cannot lock", path.display()))
        }
    }
}
