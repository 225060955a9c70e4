//! A job that edits another job's dance ([`EditParams`]): the checks when it is submitted,
//! the files it takes from the edited job, and the library edit the worker runs.
//!
//! The new job's folder gets its own copy of the edited job's song, leader and the edited
//! variation's `.npz` ([`EDITED_DANCE`]; a group's `edited_K.npz`, one per dancer), so it runs,
//! and can run again after a restart, whatever happens to the job it edits.

use std::path::Path;

use dancegen_generate::GenerateError;
use dancegen_generate::edit::{self, Edit, GivenMotion, KeepJoints, parse_joint_set};
use dancegen_generate::systems;

use crate::edit_params::EditParams;
use crate::error::ApiError;
use crate::job::{JobState, variation_stem};
use crate::jobs::Jobs;
use crate::store::JobRow;

/// The edited dance, in the new job's folder.
pub const EDITED_DANCE: &str = "edited.npz";

/// The job `e` edits, if it can be edited: it exists, is done, has the variation, and its
/// system edits (`--regenerate`). Errors name the `edit` field.
pub fn edited_job(jobs: &Jobs, e: &EditParams) -> Result<JobRow, ApiError> {
    let row = jobs
        .store
        .get(&e.of)
        .map_err(|err| ApiError::internal(format!("reading job {}: {err}", e.of)))?
        .ok_or_else(|| ApiError::field("edit.of", format!("there is no job {}", e.of)))?;
    if row.state != JobState::Done {
        return Err(ApiError::field(
            "edit.of",
            format!(
                "job {} is {}; only a finished dance can be edited",
                e.of,
                row.state.as_str()
            ),
        ));
    }
    if e.variation >= row.params.variations.max(1) {
        return Err(ApiError::field(
            "edit.variation",
            format!(
                "{}: job {} has {} variation(s), 0 to {}",
                e.variation,
                e.of,
                row.params.variations,
                row.params.variations.max(1) - 1
            ),
        ));
    }
    let info = systems::by_name(&row.params.system).map_err(|m| ApiError::field("edit.of", m))?;
    if !info.edits.contains(&edit::REGENERATE) {
        return Err(ApiError::field(
            "edit.of",
            format!(
                "job {} is a {} dance; editing it is not supported yet",
                e.of, row.params.system
            ),
        ));
    }
    if e.extend && !info.edits.contains(&edit::EXTEND) {
        return Err(ApiError::field(
            "edit.continue",
            format!(
                "job {} is a {} dance, which cannot be continued yet",
                e.of, row.params.system
            ),
        ));
    }
    if e.keep.is_some() && !info.edits.contains(&edit::KEEP_JOINTS) {
        return Err(ApiError::field(
            "edit.keep",
            format!(
                "job {} is a {} dance, which keeps no joints in an edit; leave keep out",
                e.of, row.params.system
            ),
        ));
    }
    Ok(row)
}

/// Copies what the edit needs from the edited job's folder `from` into the new job's folder
/// `to` (its song, leader, character and the dance), and checks the ranges against the dance and, for a
/// continuation, its new `end` (the song's end when `None`) against the dance's end.
pub fn take_files(
    from: &Path,
    row: &JobRow,
    e: &EditParams,
    end: Option<f64>,
    to: &Path,
) -> Result<(), ApiError> {
    let copy = |name: &str, as_name: &str| {
        std::fs::copy(from.join(name), to.join(as_name))
            .map(|_| ())
            .map_err(|err| {
                ApiError::field(
                    "edit.of",
                    format!("job {}: its file {name} cannot be read: {err}", e.of),
                )
            })
    };
    copy(&row.song, &row.song)?;
    for name in row.leader.iter().chain(&row.params.character) {
        copy(name, name)?;
    }
    let stem = variation_stem(e.variation);
    if from.join(format!("{stem}.npz")).is_file() {
        copy(&format!("{stem}.npz"), EDITED_DANCE)?;
    } else {
        // A group wrote one file per dancer, STEM_0.npz …; the copies keep the numbering, and
        // their records name the group.
        let group = EDITED_DANCE.trim_end_matches(".npz");
        let dancers = row.params.dancers.unwrap_or(1).max(1);
        for k in 0..dancers {
            copy(&format!("{stem}_{k}.npz"), &format!("{group}_{k}.npz"))?;
        }
    }
    let base = load_dance(to).map_err(|err| ApiError::field("edit.of", err.to_string()))?;
    if e.extend {
        let bytes: std::sync::Arc<[u8]> = std::fs::read(to.join(&row.song))
            .map_err(|err| ApiError::internal(format!("reading the song: {err}")))?
            .into();
        let song = crate::upload::check_song(&row.song, bytes, f64::INFINITY)?;
        let dance_end = row.params.start.unwrap_or(0.0) + base.seconds();
        let new_end = end.unwrap_or(song).min(song);
        if new_end < dance_end + edit::MIN_RANGE_SECONDS {
            return Err(ApiError::field(
                if end.is_some() {
                    "end"
                } else {
                    "edit.continue"
                },
                format!(
                    "the dance ends at {dance_end:.1} s of the song; a continuation needs an \
                     end at least {} s later (the song is {song:.1} s)",
                    edit::MIN_RANGE_SECONDS
                ),
            ));
        }
    }
    Edit {
        base: Some(base),
        regenerate: e.regenerate.clone(),
        extend: e.extend,
        ..Edit::default()
    }
    .check()
    .map_err(|err| ApiError::field("edit.regenerate", err.to_string()))
}

fn load_dance(dir: &Path) -> Result<GivenMotion, GenerateError> {
    GivenMotion::load_dance(
        &dir.join(EDITED_DANCE),
        "the dance to edit",
        None,
        "(a dance the server wrote has its rate)",
    )
}

/// The library edit of the job in `dir` (its copy of the edited dance).
pub fn library_edit(dir: &Path, e: &EditParams) -> Result<Edit, GenerateError> {
    let base = load_dance(dir)?;
    let keep_joints = match &e.keep {
        None => None,
        Some(spec) => {
            let (joints, root) =
                parse_joint_set("edit.keep", spec).map_err(GenerateError::Invalid)?;
            Some(KeepJoints {
                spec: spec.clone(),
                joints,
                root,
                from: base.clone(),
            })
        }
    };
    Ok(Edit {
        base: Some(base),
        regenerate: e.regenerate.clone(),
        extend: e.extend,
        keep_joints,
        ..Edit::default()
    })
}
