//! What this server offers (`GET /api/systems`): every system with the model it would use,
//! its genres and dancer counts — found once at start, so a request for a system without a
//! model or for a genre the model does not know is refused at submit time.

use std::path::{Path, PathBuf};

use dancegen_generate::ModelLocator;
use dancegen_generate::edit;
use dancegen_generate::systems::{self, group};
use serde_json::{Value, json};

use crate::config::Limits;
use crate::error::ApiError;
use crate::job::{JobParams, MAX_STEPS};

/// One system as served.
#[derive(Clone, Debug)]
pub struct SystemEntry {
    pub name: &'static str,
    pub method: &'static str,
    /// Its model folder, or why there is none.
    pub model: Result<PathBuf, String>,
    pub genres: Vec<String>,
    pub default_genre: Option<String>,
    pub min_dancers: usize,
    pub max_dancers: usize,
    pub needs_leader: bool,
    /// The edit operations its sampler applies (`DanceSystem::EDITS`).
    pub edits: &'static [&'static str],
}

pub struct Catalog {
    pub systems: Vec<SystemEntry>,
}

/// The `genres` and `default_genre` of a model's `model.toml` (solo models have them).
fn genres_of(dir: &Path) -> (Vec<String>, Option<String>) {
    let Ok(text) = std::fs::read_to_string(dir.join("model.toml")) else {
        return (Vec::new(), None);
    };
    let Ok(v) = text.parse::<toml::Table>() else {
        return (Vec::new(), None);
    };
    let genres = v
        .get("genres")
        .and_then(|g| g.as_array())
        .map(|a| {
            a.iter()
                .filter_map(|g| g.as_str().map(str::to_string))
                .collect()
        })
        .unwrap_or_default();
    let default = v
        .get("default_genre")
        .and_then(|g| g.as_str())
        .map(str::to_string);
    (genres, default)
}

impl Catalog {
    /// Every shipped system, with the model in `overrides` or else the one `locator` finds.
    pub fn discover(locator: &ModelLocator, overrides: &[(String, PathBuf)]) -> Self {
        let systems = systems::SYSTEMS
            .iter()
            .filter(|s| s.available)
            .map(|s| {
                let model = match overrides.iter().find(|(n, _)| n == s.name) {
                    Some((_, d)) if d.join("model.toml").is_file() => Ok(d.clone()),
                    Some((_, d)) => Err(format!("{}: no model.toml there", d.display())),
                    None => locator
                        .find(s.default_model, s.name)
                        .map_err(|e| e.to_string()),
                };
                let (genres, default_genre) = match &model {
                    Ok(d) => genres_of(d),
                    Err(_) => (Vec::new(), None),
                };
                let (min_dancers, max_dancers) = match s.name {
                    "duet" => (2, 2),
                    "group" => (group::MIN_DANCERS, group::MAX_DANCERS),
                    _ => (1, 1),
                };
                SystemEntry {
                    name: s.name,
                    method: s.method,
                    model,
                    genres,
                    default_genre,
                    min_dancers,
                    max_dancers,
                    needs_leader: s.name == "duet",
                    edits: s.edits,
                }
            })
            .collect();
        Catalog { systems }
    }

    /// Refuses a job this server cannot run: no model for the system, an unknown genre.
    pub fn check(&self, p: &JobParams) -> Result<(), ApiError> {
        let Some(s) = self.systems.iter().find(|s| s.name == p.system) else {
            return Err(ApiError::field(
                "system",
                format!("{} is not served here", p.system),
            ));
        };
        if let Err(why) = &s.model {
            return Err(ApiError::field(
                "system",
                format!("no {} model on this server: {why}", s.name),
            ));
        }
        if let Some(g) = &p.genre
            && !s.genres.iter().any(|x| x == g)
        {
            return Err(ApiError::field(
                "genre",
                format!(
                    "'{g}' is not a genre of the {} model (choose one of: {})",
                    s.name,
                    s.genres.join(", ")
                ),
            ));
        }
        Ok(())
    }

    /// The body of `GET /api/systems`.
    pub fn json(&self, limits: &Limits) -> Value {
        let systems: Vec<Value> = self
            .systems
            .iter()
            .map(|s| {
                json!({
                    "name": s.name,
                    "method": s.method,
                    "available": s.model.is_ok(),
                    "model": s.model.as_ref().ok().and_then(|d| d.file_name()).map(|n| n.to_string_lossy()),
                    "error": s.model.as_ref().err(),
                    "genres": s.genres,
                    "default_genre": s.default_genre,
                    "dancers": {"min": s.min_dancers, "max": s.max_dancers},
                    "needs_leader": s.needs_leader,
                    // What `params.edit` can ask of its dances: regenerate ranges, and keep
                    // joints of the old dance in them.
                    "edit": {
                        "regenerate": s.edits.contains(&edit::REGENERATE),
                        "keep": s.edits.contains(&edit::KEEP_JOINTS),
                        "continue": s.edits.contains(&edit::EXTEND),
                    },
                })
            })
            .collect();
        json!({
            "systems": systems,
            // `csv` (the face, Live Link Face) comes with holistic dances only.
            "formats": ["glb", "fbx", "bvh", "npz", "npy", "json", "mp4", "csv"],
            "limits": {
                "upload_bytes": limits.upload_bytes,
                "song_seconds": limits.song_seconds,
                "queue_length": limits.queue_length,
                "body_deadline_s": limits.body_deadline.as_secs_f64(),
                "variations": limits.max_variations,
                "steps": MAX_STEPS,
            },
        })
    }
}
