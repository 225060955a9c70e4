//! The versions of a dance: a job and the jobs that edit it, and the jobs that edit those
//! (`GET /api/jobs/{id}/versions`), so the page can list them, open each and compare them.
//!
//! The family is found from any of its jobs: up the `edit.of` links to the first job, then
//! down every edit of it, oldest first. A job whose edited job was deleted starts a family of
//! its own.

use serde::Serialize;

use crate::edit_params::EditParams;
use crate::error::ApiError;
use crate::jobs::Jobs;
use crate::store::JobRow;

/// Most jobs one family lists (and most links followed up it).
pub const MAX_VERSIONS: usize = 200;

/// One version as the list shows it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Version {
    pub id: String,
    /// 1 for the first job, then in the order the versions were made.
    pub number: usize,
    pub state: &'static str,
    pub seed: u64,
    /// What this version changed of the one it edits; `None` for the first.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub edit: Option<EditParams>,
    pub created: f64,
}

/// The versions of the dance `id` belongs to, or `None` when there is no job `id`.
pub fn versions(jobs: &Jobs, id: &str) -> Result<Option<Vec<Version>>, ApiError> {
    let store = |e: rusqlite::Error| ApiError::internal(format!("reading the jobs: {e}"));
    let Some(mut first) = jobs.store.get(id).map_err(store)? else {
        return Ok(None);
    };
    for _ in 0..MAX_VERSIONS {
        let Some(up) = first.params.edit.as_ref().map(|e| e.of.clone()) else {
            break;
        };
        match jobs.store.get(&up).map_err(store)? {
            Some(row) => first = row,
            None => break,
        }
    }
    let mut family: Vec<JobRow> = vec![first];
    let mut next = 0;
    while next < family.len() && family.len() < MAX_VERSIONS {
        let edits = jobs.store.edits_of(&family[next].id).map_err(store)?;
        family.extend(edits.into_iter().take(MAX_VERSIONS - family.len()));
        next += 1;
    }
    family.sort_by(|a, b| a.created.total_cmp(&b.created));
    Ok(Some(
        family
            .into_iter()
            .enumerate()
            .map(|(i, r)| Version {
                number: i + 1,
                state: r.state.as_str(),
                seed: r.params.seed,
                edit: r.params.edit.clone(),
                created: r.created,
                id: r.id,
            })
            .collect(),
    ))
}
