//! What made a dance, stored in the `.npz` files dancegen writes (member
//! [`dancegen_formats::smpl_npz::RECORD_MEMBER`], JSON), so that `generate --edit DANCE.npz`
//! finds the song, the start, the system, the model and the seed without being told.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::error::GenerateError;

/// The record of one dancer's file (see the module documentation). Unknown keys are ignored on
/// reading, so later versions may add some.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DanceRecord {
    /// The song file as the job was given it (absolute where it was a file path), or
    /// `"demo"` for the bundled song, or the uploaded file's name.
    pub song: String,
    /// Seconds of the song the dance starts and ends at.
    pub start_s: f64,
    pub end_s: f64,
    /// `solo`, `duet`, `group`, `holistic`.
    pub system: String,
    /// The model folder used.
    pub model: String,
    pub seed: u64,
    /// Dancers of the whole dance, and which of them this file holds.
    pub dancers: usize,
    pub dancer: usize,
    pub fps: u32,
    /// The dancegen version that wrote it.
    pub version: String,
}

/// The song name recorded for the bundled demo song.
pub const DEMO_SONG: &str = "demo";

impl DanceRecord {
    pub fn to_json(&self) -> String {
        serde_json::to_string(self).expect("a record serialises")
    }

    /// The record in `path` (an `.npz`), `None` when the file has none (a foreign dance).
    pub fn read(path: &Path) -> Result<Option<Self>, GenerateError> {
        let bad = |why: String| GenerateError::Invalid(format!("{}: {why}", path.display()));
        let is_npz = path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("npz"));
        if !is_npz {
            return Ok(None);
        }
        let Some(text) = dancegen_formats::smpl_npz::read_record(path)
            .map_err(|e| GenerateError::Invalid(e.to_string()))?
        else {
            return Ok(None);
        };
        serde_json::from_str(&text)
            .map(Some)
            .map_err(|e| bad(format!("its dancegen record is not readable ({e})")))
    }

    /// The recorded song as a path, `None` for the demo song.
    pub fn song_path(&self) -> Option<PathBuf> {
        (self.song != DEMO_SONG).then(|| PathBuf::from(&self.song))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_record_round_trips_through_an_npz_and_foreign_files_have_none() {
        let dir = tempfile::tempdir().unwrap();
        let m =
            dancegen_motion::repr::SmplMotion::new(30.0, vec![0.0; 72 * 3], vec![0.0; 9]).unwrap();
        let r = DanceRecord {
            song: "/music/a song.ogg".into(),
            start_s: 12.5,
            end_s: 22.5,
            system: "solo".into(),
            model: "models/lodgepp-small".into(),
            seed: 7,
            dancers: 1,
            dancer: 0,
            fps: 30,
            version: "0.1.0".into(),
        };
        let with = dir.path().join("with.npz");
        let opts = dancegen_formats::smpl_npz::SmplNpzOptions::default();
        dancegen_formats::smpl_npz::write_smpl_npz_recorded(&with, &m, &opts, Some(&r.to_json()))
            .unwrap();
        assert_eq!(DanceRecord::read(&with).unwrap(), Some(r.clone()));
        let without = dir.path().join("without.npz");
        dancegen_formats::smpl_npz::write_smpl_npz(&without, &m, &opts).unwrap();
        assert_eq!(DanceRecord::read(&without).unwrap(), None);
        assert_eq!(DanceRecord::read(&dir.path().join("x.bvh")).unwrap(), None);
        assert_eq!(r.song_path(), Some(PathBuf::from("/music/a song.ogg")));
    }
}
