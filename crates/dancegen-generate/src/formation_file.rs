//! A FORMATION.json file as front ends hand it over: read, but checked against the song only
//! once the song is known. The group's `--formation` and the solo dancer's `--path` share it.

use std::path::Path;

use dancegen_refine::formation::keyframes::Formation;

use crate::error::GenerateError;

/// A song length no real song reaches: checks a file's keyframes on their own, before the
/// song is analysed.
pub const ANY_SONG_SECONDS: f64 = 1e9;

/// A formation file, read but not yet checked against the song.
#[derive(Clone, Debug)]
pub struct FormationFile {
    /// The file, as named in messages.
    pub label: String,
    pub json: String,
}

impl FormationFile {
    /// Reads `path`; `what` says what the file is for in the error ("the formation").
    pub fn read(path: &Path, what: &str) -> Result<Self, GenerateError> {
        let json = std::fs::read_to_string(path).map_err(|e| {
            GenerateError::Invalid(format!("{}: cannot read {what}: {e}", path.display()))
        })?;
        Ok(FormationFile {
            label: path.display().to_string(),
            json,
        })
    }

    /// The keyframes for `dancers` dancers, checked against a song of `song_seconds`
    /// ([`ANY_SONG_SECONDS`] before the song is known); errors name the file and field.
    pub fn parse(&self, dancers: usize, song_seconds: f64) -> Result<Formation, GenerateError> {
        Formation::parse(&self.label, &self.json, dancers, song_seconds)
            .map_err(|e| GenerateError::Invalid(e.to_string()))
    }
}
