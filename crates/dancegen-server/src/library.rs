//! "My dances": what the library's actions need beyond the job store. A name given to a
//! dance is checked in words; "again" makes a new job from a finished one, with its song, its
//! leader and its settings (another seed, or the same to try a failed job again).

use std::path::Path;

use crate::error::ApiError;
use crate::job::JobParams;
use crate::store::JobRow;

/// Most jobs the library lists (the newest).
pub const LIBRARY_LIMIT: usize = 200;
/// Longest name a dance may be given, in characters.
pub const MAX_NAME_CHARS: usize = 80;

/// The name as stored: trimmed, `None` when empty (the song's name shows again); refused in
/// words when too long or holding control characters.
pub fn checked_name(raw: Option<&str>) -> Result<Option<String>, ApiError> {
    let Some(name) = raw.map(str::trim).filter(|n| !n.is_empty()) else {
        return Ok(None);
    };
    if name.chars().count() > MAX_NAME_CHARS {
        return Err(ApiError::field(
            "name",
            format!("a name has at most {MAX_NAME_CHARS} characters"),
        ));
    }
    if name.chars().any(char::is_control) {
        return Err(ApiError::field(
            "name",
            "a name is one line of text, without control characters",
        ));
    }
    Ok(Some(name.to_string()))
}

/// The settings of a new job made from `row` ("again"): the same, with `seed` when given. An
/// edited version is made again from its dance (its edit needs the dance it edited as it was).
pub fn again_params(row: &JobRow, seed: Option<u64>) -> Result<JobParams, ApiError> {
    if row.params.edit.is_some() {
        return Err(ApiError::field(
            "again",
            "this is an edited version: open the dance it came from and change the part again",
        ));
    }
    let mut params = row.params.clone();
    if let Some(seed) = seed {
        params.seed = seed;
    }
    Ok(params)
}

/// Copies the song (and a duet's leader, and the character) of the job in `from` into the new
/// job's folder `to`.
pub fn copy_inputs(from: &Path, row: &JobRow, to: &Path) -> Result<(), ApiError> {
    std::fs::create_dir_all(to)
        .map_err(|e| ApiError::internal(format!("{}: {e}", to.display())))?;
    for name in std::iter::once(&row.song)
        .chain(row.leader.as_ref())
        .chain(row.params.character.as_ref())
    {
        std::fs::copy(from.join(name), to.join(name))
            .map_err(|e| ApiError::internal(format!("copying the song of job {}: {e}", row.id)))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_trimmed_and_checked_in_words() {
        assert_eq!(
            checked_name(Some("  Salsa take 2 ")).unwrap().as_deref(),
            Some("Salsa take 2")
        );
        assert_eq!(checked_name(Some("   ")).unwrap(), None);
        assert_eq!(checked_name(None).unwrap(), None);
        let long = "x".repeat(MAX_NAME_CHARS + 1);
        assert!(
            checked_name(Some(&long))
                .unwrap_err()
                .message
                .contains("at most 80")
        );
        let e = checked_name(Some("two\nlines")).unwrap_err();
        assert_eq!(e.field.as_deref(), Some("name"));
    }
}
