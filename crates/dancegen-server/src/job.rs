//! A job as the API speaks of it: the parameters a user submits (checked field by field, so
//! a bad one gets a 400 that names it) and the job object every status request and SSE event
//! carries.

use std::collections::BTreeMap;

use serde::Serialize;
use serde_json::{Map, Value};

use dancegen_generate::request::VideoSize;
use dancegen_generate::systems::{self, group};

use crate::edit_params::EditParams;
use crate::error::ApiError;

/// Where a job is in its life. Stored in SQLite by [`JobState::as_str`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum JobState {
    Queued,
    Running,
    Done,
    Failed,
    Cancelled,
}

impl JobState {
    pub fn as_str(self) -> &'static str {
        match self {
            JobState::Queued => "queued",
            JobState::Running => "running",
            JobState::Done => "done",
            JobState::Failed => "failed",
            JobState::Cancelled => "cancelled",
        }
    }

    pub fn parse(s: &str) -> Option<Self> {
        Some(match s {
            "queued" => JobState::Queued,
            "running" => JobState::Running,
            "done" => JobState::Done,
            "failed" => JobState::Failed,
            "cancelled" => JobState::Cancelled,
            _ => return None,
        })
    }

    /// Whether the job will not change any more.
    pub fn is_final(self) -> bool {
        matches!(
            self,
            JobState::Done | JobState::Failed | JobState::Cancelled
        )
    }
}

/// What a user asks for (`params` of `POST /api/jobs`); `None` = the model's default.
#[derive(Clone, Debug, PartialEq, Serialize, serde::Deserialize)]
pub struct JobParams {
    pub system: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dancers: Option<usize>,
    pub seed: u64,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub genre: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub steps: Option<usize>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub start: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub end: Option<f64>,
    /// Dances made from the same song with seeds `seed`, `seed + 1`, …
    pub variations: usize,
    /// Also render an `.mp4` preview with the song (takes as long as the dance itself).
    pub mp4: bool,
    /// The `.mp4`'s picture size, `640x480` (the default) or `1280x720`
    /// ([`dancegen_generate::request::VideoSize`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub video_size: Option<String>,
    /// Bone names of the `.glb`, `.fbx` and `.bvh`: `smpl` (the default), `mixamo`, `ue5` or
    /// `vrm`, as `generate --rig` ([`dancegen_formats::rig::Rig`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rig: Option<String>,
    /// A new version of a finished job's dance ([`EditParams`]); the song, system, dancers,
    /// start and end are that job's.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub edit: Option<EditParams>,
    /// The uploaded song's name made safe ([`crate::download_names::song_title`]); set by the
    /// server, not a parameter. Downloads are named after it; an edit keeps its job's.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub song_title: Option<String>,
    /// The uploaded character's file in the job folder (`character.glb` or `character.vrm`,
    /// [`crate::upload::character_file_name`]): the job's `.glb` is it dancing. Set by the
    /// server from the `character` part, not a parameter; an edit and "again" keep their
    /// job's.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub character: Option<String>,
}

/// Most denoising steps a user may ask for (the models are trained with 1000 timesteps).
pub const MAX_STEPS: usize = 1000;

/// The fields `params` may have, for the error about an unknown one.
const FIELDS: &str =
    "system, dancers, seed, genre, steps, start, end, variations, mp4, video_size, rig, edit";

/// The parameters an edit takes from the job it edits, not from its own params.
const FROM_THE_EDITED_JOB: [&str; 5] = ["system", "dancers", "genre", "start", "end"];

impl JobParams {
    /// Parses and checks `params` (a JSON object; empty text = every default). `max_variations`
    /// bounds `variations`.
    pub fn parse(text: &str, max_variations: usize) -> Result<Self, ApiError> {
        Self::from_object(object_of(text)?, max_variations)
    }

    /// Parses `params` plus any parameter sent as a form field of its own (`seed=3`, as an
    /// HTML form sends it); one given both ways is an error.
    pub fn parse_form(
        text: &str,
        fields: &[(String, String)],
        max_variations: usize,
    ) -> Result<Self, ApiError> {
        let mut obj = object_of(text)?;
        for (k, v) in fields {
            if obj.insert(k.clone(), Value::String(v.clone())).is_some() {
                return Err(ApiError::field(
                    k,
                    format!("'{k}' is given twice (in params and as a form field)"),
                ));
            }
        }
        Self::from_object(obj, max_variations)
    }

    /// Whether `name` is a parameter (a form field of that name joins `params`).
    pub fn is_field(name: &str) -> bool {
        FIELDS.split(", ").any(|f| f == name)
    }

    fn from_object(obj: Map<String, Value>, max_variations: usize) -> Result<Self, ApiError> {
        if let Some(k) = obj
            .keys()
            .find(|k| !FIELDS.split(", ").any(|f| f == k.as_str()))
        {
            return Err(ApiError::field(
                k,
                format!("unknown parameter '{k}' (known: {FIELDS})"),
            ));
        }
        let edit = match obj.get("edit") {
            None | Some(Value::Null) => None,
            Some(v) => Some(EditParams::parse(v)?),
        };
        // A continued dance goes on to its own end.
        let own = |k: &&&str| **k == "end" && edit.as_ref().is_some_and(|e| e.extend);
        if edit.is_some()
            && let Some(k) = FROM_THE_EDITED_JOB
                .iter()
                .find(|k| obj.contains_key(**k) && !own(k))
        {
            return Err(ApiError::field(
                k,
                "an edit dances with the system, dancers, genre, start and end of the job \
                 it edits; leave this out",
            ));
        }
        let system = opt_str(&obj, "system")?.unwrap_or_else(|| "solo".into());
        let info = systems::by_name(&system).map_err(|e| ApiError::field("system", e))?;
        let dancers = opt_uint(&obj, "dancers")?.map(|n| n as usize);
        match (info.name, dancers) {
            ("group", None) => {
                return Err(ApiError::field(
                    "dancers",
                    format!(
                        "the group system needs dancers ({} to {})",
                        group::MIN_DANCERS,
                        group::MAX_DANCERS
                    ),
                ));
            }
            ("group", Some(n)) if !(group::MIN_DANCERS..=group::MAX_DANCERS).contains(&n) => {
                return Err(ApiError::field(
                    "dancers",
                    format!(
                        "{n} dancers: the group system dances {} to {}",
                        group::MIN_DANCERS,
                        group::MAX_DANCERS
                    ),
                ));
            }
            ("solo", Some(n)) if n != 1 => {
                return Err(ApiError::field(
                    "dancers",
                    format!("{n} dancers: solo is one dancer; use system group for 2 to 5"),
                ));
            }
            ("duet", Some(n)) if n != 2 => {
                return Err(ApiError::field(
                    "dancers",
                    format!("{n} dancers: a duet is two; use system group for 2 to 5"),
                ));
            }
            _ => {}
        }
        let seed = opt_uint(&obj, "seed")?.unwrap_or(0);
        let genre = opt_str(&obj, "genre")?;
        if genre.is_some() && info.name != "solo" {
            return Err(ApiError::field(
                "genre",
                format!("genre applies to solo dances, not to {}", info.name),
            ));
        }
        let steps = opt_uint(&obj, "steps")?.map(|n| n as usize);
        if let Some(s) = steps
            && !(1..=MAX_STEPS).contains(&s)
        {
            return Err(ApiError::field(
                "steps",
                format!("{s}: need 1 to {MAX_STEPS}"),
            ));
        }
        let start = opt_seconds(&obj, "start")?;
        let end = opt_seconds(&obj, "end")?;
        if let (Some(a), Some(b)) = (start, end)
            && a >= b
        {
            return Err(ApiError::field(
                "end",
                format!("end {b} s is not after start {a} s"),
            ));
        }
        if end.is_some() && info.name == "duet" {
            return Err(ApiError::field(
                "end",
                "a duet is as long as its leader; give start only",
            ));
        }
        let variations = opt_uint(&obj, "variations")?.unwrap_or(1) as usize;
        if !(1..=max_variations).contains(&variations) {
            return Err(ApiError::field(
                "variations",
                format!("{variations}: need 1 to {max_variations}"),
            ));
        }
        let video_size = opt_str(&obj, "video_size")?;
        if let Some(v) = &video_size {
            VideoSize::parse(v).map_err(|e| ApiError::field("video_size", e))?;
        }
        let rig = opt_str(&obj, "rig")?;
        if let Some(r) = &rig {
            dancegen_formats::rig::Rig::from_name(r)
                .map_err(|e| ApiError::field("rig", e.to_string()))?;
        }
        let mp4 = match obj.get("mp4") {
            None | Some(Value::Null) => false,
            Some(Value::Bool(b)) => *b,
            // Form fields arrive as text (a checkbox sends "on").
            Some(Value::String(t)) if ["true", "on", "1"].contains(&t.trim()) => true,
            Some(Value::String(t)) if ["false", "off", "0", ""].contains(&t.trim()) => false,
            Some(v) => return Err(ApiError::field("mp4", format!("{v}: need true or false"))),
        };
        Ok(JobParams {
            system: info.name.to_string(),
            dancers,
            seed,
            genre,
            steps,
            start,
            end,
            variations,
            mp4,
            video_size,
            rig,
            edit,
            song_title: None,
            character: None,
        })
    }

    /// These params as an edit of the job whose params are `edited`: its system, dancers,
    /// genre, start and end (a continuation keeps its own end).
    pub fn editing(mut self, edited: &JobParams) -> Self {
        self.system = edited.system.clone();
        self.dancers = edited.dancers;
        self.genre = edited.genre.clone();
        self.start = edited.start;
        self.song_title = edited.song_title.clone();
        self.character = edited.character.clone();
        // Files named for the same tool as the dance it edits, unless asked otherwise.
        if self.rig.is_none() {
            self.rig = edited.rig.clone();
        }
        if !self.edit.as_ref().is_some_and(|e| e.extend) {
            self.end = edited.end;
        }
        self
    }

    /// Dancers in the finished dance.
    pub fn dancer_count(&self) -> usize {
        match self.system.as_str() {
            "duet" => 2,
            "group" => self.dancers.unwrap_or(group::MIN_DANCERS),
            _ => 1,
        }
    }

    /// The seed of variation `k`.
    pub fn seed_of(&self, k: usize) -> u64 {
        self.seed.wrapping_add(k as u64)
    }
}

/// `params` as a JSON object (empty text = no parameter).
fn object_of(text: &str) -> Result<Map<String, Value>, ApiError> {
    let text = text.trim();
    if text.is_empty() {
        return Ok(Map::new());
    }
    match serde_json::from_str::<Value>(text) {
        Ok(Value::Object(o)) => Ok(o),
        Ok(_) => Err(ApiError::field("params", "must be a JSON object")),
        Err(e) => Err(ApiError::field("params", format!("not valid JSON: {e}"))),
    }
}

fn opt_str(obj: &Map<String, Value>, key: &str) -> Result<Option<String>, ApiError> {
    match obj.get(key) {
        None | Some(Value::Null) => Ok(None),
        Some(Value::String(s)) if s.trim().is_empty() => Ok(None),
        Some(Value::String(s)) => Ok(Some(s.trim().to_string())),
        Some(v) => Err(ApiError::field(key, format!("{v}: need a string"))),
    }
}

fn opt_uint(obj: &Map<String, Value>, key: &str) -> Result<Option<u64>, ApiError> {
    match obj.get(key) {
        None | Some(Value::Null) => Ok(None),
        Some(Value::Number(n)) => n
            .as_u64()
            .map(Some)
            .ok_or_else(|| ApiError::field(key, format!("{n}: need a whole number ≥ 0"))),
        // Form fields arrive as text.
        Some(Value::String(s)) if s.trim().is_empty() => Ok(None),
        Some(Value::String(s)) => s
            .trim()
            .parse()
            .map(Some)
            .map_err(|_| ApiError::field(key, format!("'{s}': need a whole number ≥ 0"))),
        Some(v) => Err(ApiError::field(
            key,
            format!("{v}: need a whole number ≥ 0"),
        )),
    }
}

fn opt_seconds(obj: &Map<String, Value>, key: &str) -> Result<Option<f64>, ApiError> {
    let bad = |v: &dyn std::fmt::Display| {
        ApiError::field(key, format!("{v}: need seconds, a number ≥ 0"))
    };
    let x = match obj.get(key) {
        None | Some(Value::Null) => return Ok(None),
        Some(Value::Number(n)) => n.as_f64().ok_or_else(|| bad(n))?,
        Some(Value::String(s)) if s.trim().is_empty() => return Ok(None),
        Some(Value::String(s)) => s.trim().parse().map_err(|_| bad(&format!("'{s}'")))?,
        Some(v) => return Err(bad(v)),
    };
    if !(x.is_finite() && x >= 0.0) {
        return Err(bad(&x));
    }
    Ok(Some(x))
}

/// One variation's files by kind (`glb`, `fbx`, `bvh`, `npz`, `npy`, `json`, `mp4`, and a duet's
/// `leader_npy`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct VariationView {
    pub seed: u64,
    pub files: BTreeMap<String, String>,
    /// The name each of `files` downloads as (same keys): `<song>-<system>-seed<k>.<ext>`
    /// ([`crate::download_names`]).
    pub names: BTreeMap<String, String>,
}

/// The job object of `GET /api/jobs/{id}` and of every SSE event.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct JobView {
    pub id: String,
    pub state: JobState,
    /// What the running job is doing (`load_model`, `analyse_song`, `denoising`, …).
    pub stage: Option<String>,
    /// Share of the whole job done, 0..=1 (all variations).
    pub progress: f64,
    /// Estimated seconds left (`null` while unknown).
    pub eta_s: Option<f64>,
    /// Why the job failed, in words.
    pub error: Option<String>,
    /// What the user should know about the finished dance, in words (a song in which no beat
    /// was found); empty when there is nothing to say.
    pub warnings: Vec<String>,
    /// Every file of the job (the uploaded song included), name → URL.
    pub files: BTreeMap<String, String>,
    /// URL of the uploaded song (the viewer's clock).
    pub song: Option<String>,
    pub system: String,
    pub dancers: usize,
    pub params: JobParams,
    pub variations: Vec<VariationView>,
    /// Seconds since the Unix epoch.
    pub created: f64,
    pub finished: Option<f64>,
    /// Times a worker started the job (more than 1 only when a server stopped during it).
    pub attempts: u32,
    /// Queued jobs ahead of this one (0 = next), while it waits.
    pub queue_position: Option<usize>,
    /// The name the user gave it in the library (`null`: none; the page shows the song's).
    pub name: Option<String>,
    /// URL of its picture in the library (a finished dance's first variation), if drawn.
    pub thumbnail: Option<String>,
    /// URL of the viewer's timeline (`timeline.json`: the danced part's waveform and beats).
    pub timeline: Option<String>,
}

/// The stem of variation `k`'s files: `dance` (what the CLI's examples write), then
/// `dance-2`, `dance-3`, …
pub fn variation_stem(k: usize) -> String {
    if k == 0 {
        "dance".into()
    } else {
        format!("dance-{}", k + 1)
    }
}

/// Name of a duet's leader joints file (the leader as the dance used it).
pub const LEADER_NPY: &str = "leader.npy";

/// Formats every job writes (`mp4` only when asked), as the issue's contract lists them.
pub const MOTION_FORMATS: [&str; 6] = ["glb", "fbx", "bvh", "npz", "npy", "json"];

/// Formats only a dance with a face writes (the holistic system's): the face as Live Link Face
/// CSV. Its motion files hold the fingers too (52 SMPL-H joints).
pub const FACE_FORMATS: [&str; 1] = ["csv"];

/// The system whose dances have a face (and fingers).
pub const FACE_SYSTEM: &str = "holistic";

#[cfg(test)]
mod tests {
    use super::*;

    fn err(text: &str) -> ApiError {
        JobParams::parse(text, 4).unwrap_err()
    }

    #[test]
    fn the_face_system_is_a_known_system() {
        assert!(systems::SYSTEMS.iter().any(|s| s.name == FACE_SYSTEM));
        assert!(FACE_FORMATS.iter().all(|f| !MOTION_FORMATS.contains(f)));
    }

    #[test]
    fn defaults_and_form_text() {
        let p = JobParams::parse("", 4).unwrap();
        assert_eq!((p.system.as_str(), p.seed, p.variations), ("solo", 0, 1));
        let p = JobParams::parse(
            r#"{"system":"group","dancers":"3","seed":7,"start":"1.5","end":9,"variations":2}"#,
            4,
        )
        .unwrap();
        assert_eq!(p.dancers, Some(3));
        assert_eq!((p.start, p.end), (Some(1.5), Some(9.0)));
        assert_eq!(p.seed_of(1), 8);
    }

    #[test]
    fn each_bad_field_is_named() {
        assert_eq!(err("[1]").field.as_deref(), Some("params"));
        assert_eq!(err("{").field.as_deref(), Some("params"));
        assert_eq!(err(r#"{"colour":1}"#).field.as_deref(), Some("colour"));
        assert_eq!(
            err(r#"{"system":"ballet"}"#).field.as_deref(),
            Some("system")
        );
        assert_eq!(
            err(r#"{"system":"group"}"#).field.as_deref(),
            Some("dancers")
        );
        assert_eq!(
            err(r#"{"system":"group","dancers":6}"#).field.as_deref(),
            Some("dancers")
        );
        assert_eq!(err(r#"{"seed":-1}"#).field.as_deref(), Some("seed"));
        assert_eq!(err(r#"{"steps":0}"#).field.as_deref(), Some("steps"));
        assert_eq!(err(r#"{"start":"soon"}"#).field.as_deref(), Some("start"));
        assert_eq!(err(r#"{"start":5,"end":2}"#).field.as_deref(), Some("end"));
        assert_eq!(
            err(r#"{"variations":9}"#).field.as_deref(),
            Some("variations")
        );
        assert_eq!(err(r#"{"mp4":"yes"}"#).field.as_deref(), Some("mp4"));
        let e = err(r#"{"mp4":true,"video_size":"4k"}"#);
        assert_eq!(e.field.as_deref(), Some("video_size"));
        assert!(e.to_string().contains("choose 640x480 or 1280x720"), "{e}");
        let p = JobParams::parse(r#"{"mp4":true,"video_size":"1280x720"}"#, 4).unwrap();
        assert_eq!(p.video_size.as_deref(), Some("1280x720"));
        let e = err(r#"{"rig":"maya"}"#);
        assert_eq!(e.field.as_deref(), Some("rig"));
        assert!(
            e.message.contains("smpl, mixamo, ue5 or vrm"),
            "{}",
            e.message
        );
        let p = JobParams::parse(r#"{"rig":"ue5"}"#, 4).unwrap();
        assert_eq!(p.rig.as_deref(), Some("ue5"));
        assert_eq!(
            err(r#"{"system":"duet","genre":"salsa"}"#).field.as_deref(),
            Some("genre")
        );
        assert!(err(r#"{"system":"ballet"}"#).message.contains("solo"));
        let edit = r#""edit":{"of":"j1","regenerate":[[1,2]]}"#;
        for field in ["system", "start", "end"] {
            let value = if field == "system" { "\"solo\"" } else { "1" };
            let text = format!("{{\"{field}\":{value},{edit}}}");
            assert_eq!(err(&text).field.as_deref(), Some(field), "{text}");
        }
        assert_eq!(
            err(r#"{"edit":{"of":"j1"}}"#).field.as_deref(),
            Some("edit.regenerate")
        );
        let ok = JobParams::parse(&format!("{{\"seed\":3,{edit}}}"), 4).unwrap();
        assert_eq!(ok.edit.unwrap().regenerate, vec![[1.0, 2.0]]);
    }

    #[test]
    fn form_fields_join_params() {
        let f = |k: &str, v: &str| (k.to_string(), v.to_string());
        let p =
            JobParams::parse_form(r#"{"seed": 3}"#, &[f("end", "8"), f("mp4", "on")], 4).unwrap();
        assert_eq!((p.seed, p.end, p.mp4), (3, Some(8.0), true));
        let e = JobParams::parse_form(r#"{"seed": 3}"#, &[f("seed", "4")], 4).unwrap_err();
        assert_eq!(e.field.as_deref(), Some("seed"));
        assert!(JobParams::is_field("variations") && !JobParams::is_field("song"));
    }
}
