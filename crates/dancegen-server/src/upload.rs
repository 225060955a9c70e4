//! `POST /api/jobs`: reading the multipart upload, and checking the song, the leader and the
//! character before a job is queued, so a file that cannot be danced to is a 400 at once rather than a
//! failed job later.

use std::path::Path;
use std::sync::Arc;

use axum::extract::Multipart;
use axum::extract::multipart::MultipartError;
use axum::http::StatusCode;

use dancegen_generate::request::Character;
use dancegen_music::decode::{AudioSource, MonoDecoder};
use dancegen_music::error::MusicError;

use crate::error::ApiError;
use crate::files::extension_of;
use crate::job::JobParams;

/// The parts of an upload.
pub struct Upload {
    /// The song; `None` for an edit, which dances to the song of the job it edits.
    pub song: Option<UploadedFile>,
    pub leader: Option<UploadedFile>,
    /// The user's own humanoid (`.glb`/`.vrm`) that the job's `.glb` shows dancing.
    pub character: Option<UploadedFile>,
    pub params: JobParams,
}

pub struct UploadedFile {
    /// The name the client gave (only its extension is used).
    pub name: String,
    pub bytes: Vec<u8>,
}

/// Whether the body deadline ([`tower_http::timeout::RequestBodyDeadlineLayer`]) cut the
/// upload off.
fn hit_deadline(e: &MultipartError) -> bool {
    let mut source: Option<&(dyn std::error::Error + 'static)> = Some(e);
    while let Some(s) = source {
        if s.is::<tower_http::timeout::TimeoutError>() {
            return true;
        }
        source = s.source();
    }
    false
}

fn multipart_error(e: MultipartError, limit: usize) -> ApiError {
    let status = e.status();
    if hit_deadline(&e) {
        ApiError::new(
            StatusCode::REQUEST_TIMEOUT,
            "the upload took longer than the upload deadline; try again on a faster link or \
             with a compressed song",
        )
    } else if status.is_server_error() {
        // The body stream broke: the client went away or sent a broken stream.
        ApiError::new(
            StatusCode::BAD_REQUEST,
            format!("the upload was interrupted: {}", e.body_text()),
        )
    } else if status == StatusCode::PAYLOAD_TOO_LARGE {
        ApiError::new(
            status,
            format!(
                "upload larger than the limit of {} MB",
                limit as f64 / (1 << 20) as f64
            ),
        )
    } else {
        ApiError::new(status, format!("reading the upload: {}", e.body_text()))
    }
}

/// Reads `song`, `leader`, `character` and `params`; any other part is an error naming it.
pub async fn read(
    mut form: Multipart,
    upload_limit: usize,
    max_variations: usize,
) -> Result<Upload, ApiError> {
    let mut song = None;
    let mut leader = None;
    let mut character = None;
    let mut params_text = None;
    let mut form_fields = Vec::new();
    while let Some(field) = form
        .next_field()
        .await
        .map_err(|e| multipart_error(e, upload_limit))?
    {
        let name = field.name().unwrap_or("").to_string();
        match name.as_str() {
            "song" | "leader" | "character" => {
                let file_name = field.file_name().unwrap_or("").to_string();
                let bytes = field
                    .bytes()
                    .await
                    .map_err(|e| multipart_error(e, upload_limit))?;
                let f = UploadedFile {
                    name: file_name,
                    bytes: bytes.to_vec(),
                };
                match name.as_str() {
                    "song" => song = Some(f),
                    "leader" => leader = Some(f),
                    _ => character = Some(f),
                }
            }
            "params" => {
                let text = field
                    .text()
                    .await
                    .map_err(|e| multipart_error(e, upload_limit))?;
                params_text = Some(text);
            }
            other if JobParams::is_field(other) => {
                let text = field
                    .text()
                    .await
                    .map_err(|e| multipart_error(e, upload_limit))?;
                form_fields.push((other.to_string(), text));
            }
            other => {
                return Err(ApiError::field(
                    other,
                    format!(
                        "unknown part '{other}' (send song, leader, character and params, or \
                         the parameters as form fields)"
                    ),
                ));
            }
        }
    }
    let params = JobParams::parse_form(
        params_text.as_deref().unwrap_or(""),
        &form_fields,
        max_variations,
    )?;
    if params.edit.is_some() {
        // The song, the leader and the character are the edited job's.
        for (part, given) in [
            ("song", song.is_some()),
            ("leader", leader.is_some()),
            ("character", character.is_some()),
        ] {
            if given {
                return Err(ApiError::field(
                    part,
                    "an edit dances to the song (and leader) of the job it edits, on its \
                     character; send none",
                ));
            }
        }
        return Ok(Upload {
            song: None,
            leader: None,
            character: None,
            params,
        });
    }
    let song = song.ok_or_else(|| ApiError::field("song", "missing: attach the song file"))?;
    if song.bytes.is_empty() {
        return Err(ApiError::field("song", "the file is empty"));
    }
    match (params.system.as_str(), &leader) {
        ("duet", None) => {
            return Err(ApiError::field(
                "leader",
                "the duet system dances with a leader: attach the leader's motion (.bvh)",
            ));
        }
        ("duet", Some(l)) if l.bytes.is_empty() => {
            return Err(ApiError::field("leader", "the file is empty"));
        }
        ("duet", Some(_)) => {}
        (system, Some(_)) => {
            return Err(ApiError::field(
                "leader",
                format!("a leader makes a duet; the {system} system takes none"),
            ));
        }
        _ => {}
    }
    if let Some(c) = &character {
        check_character_part(c, &params)?;
    }
    Ok(Upload {
        song: Some(song),
        leader,
        character,
        params,
    })
}

/// The song's file name in the job folder (`song.<ext>`: the extension is the decoder's
/// format hint).
pub fn song_file_name(upload_name: &str) -> String {
    match extension_of(upload_name) {
        Some(ext) => format!("song.{ext}"),
        None => "song".into(),
    }
}

/// The leader's file name in the job folder (`leader.<ext>`, BVH when the client gave none).
pub fn leader_file_name(upload_name: &str) -> String {
    format!(
        "leader.{}",
        extension_of(upload_name).unwrap_or_else(|| "bvh".into())
    )
}

/// The character's file name in the job folder (`character.glb` or `character.vrm`).
pub fn character_file_name(upload_name: &str) -> String {
    format!(
        "character.{}",
        extension_of(upload_name).unwrap_or_else(|| "glb".into())
    )
}

/// Formats a character may come in: one file holding everything (a `.gltf` names its buffers
/// and textures as files beside it, which an upload does not bring).
const CHARACTER_FORMATS: [&str; 2] = ["glb", "vrm"];

/// What can be said of an uploaded character before reading it: a file, of a one-file glTF
/// format, for a dance of one dancer (as `generate --character` refuses a group and a duet
/// whose leader is in the file).
fn check_character_part(c: &UploadedFile, params: &JobParams) -> Result<(), ApiError> {
    if c.bytes.is_empty() {
        return Err(ApiError::field("character", "the file is empty"));
    }
    let ext = extension_of(&c.name).unwrap_or_default();
    if !CHARACTER_FORMATS.contains(&ext.as_str()) {
        return Err(ApiError::field(
            "character",
            format!(
                "a character is a humanoid glTF in one file (.glb or .vrm), not {}; export it \
                 as .glb with its skin",
                if ext.is_empty() {
                    "a file without an extension".to_string()
                } else {
                    format!("a .{ext} file")
                }
            ),
        ));
    }
    if params.dancer_count() != 1 {
        return Err(ApiError::field(
            "character",
            format!(
                "a character dances alone, and a {} dance has {} dancers in its .glb; choose \
                 the solo or holistic system",
                params.system,
                params.dancer_count()
            ),
        ));
    }
    Ok(())
}

/// Reads the character (blocking) as the job will ([`load_character`]), with `generate
/// --character`'s words: a file that is not glTF, has no skin, or whose bones are not a
/// humanoid's is refused now.
pub fn check_character(path: &Path) -> Result<(), ApiError> {
    load_character(path).map(|_| ())
}

/// The job folder's character, read from its own bytes only: a URI naming a file (which could
/// be any file on the server) is refused. Errors name the field, not the server's path.
pub fn load_character(path: &Path) -> Result<Character, ApiError> {
    let bytes = std::fs::read(path)
        .map_err(|e| ApiError::internal(format!("reading the character: {e}")))?;
    Character::from_self_contained_bytes(path, &bytes).map_err(|e| {
        // The field names the character already: the server's path is left out.
        let shown = path.display().to_string();
        let text = crate::error::chain(&e)
            .replace(&format!("{shown}: "), "")
            .replace(&shown, "the character");
        ApiError::field("character", crate::user_words::unflag(&text))
    })
}

/// Decodes the whole song (blocking; run it off the async threads): a file the decoder
/// cannot read is refused with the decoder's words, a song longer than `max_seconds` with
/// the limit. Returns its length in seconds.
pub fn check_song(name: &str, bytes: Arc<[u8]>, max_seconds: f64) -> Result<f64, ApiError> {
    let source = AudioSource::Bytes {
        name: Path::new(name).to_path_buf(),
        bytes,
    };
    let bad = |e: MusicError| ApiError::field("song", audio_fault(&e));
    let too_long = |seconds: f64| {
        ApiError::field(
            "song",
            format!(
                "{seconds:.0} s long; this server takes songs up to {max_seconds:.0} s \
                 (the song duration limit); cut it or use start/end on a shorter file"
            ),
        )
    };
    let mut decoder = MonoDecoder::open_source(&source).map_err(bad)?;
    let rate = decoder.sample_rate();
    if let Some(frames) = decoder.total_frames()
        && rate > 0
        && frames as f64 / f64::from(rate) > max_seconds
    {
        return Err(too_long(frames as f64 / f64::from(rate)));
    }
    // Decode it all: the declared length may be missing or wrong, and a broken stream must be
    // found now rather than in the job.
    let mut block = Vec::new();
    let mut samples = 0usize;
    while decoder.next_block(&mut block).map_err(bad)? {
        samples += block.len();
        block.clear();
        let rate = decoder.sample_rate().max(1);
        if samples as f64 / f64::from(rate) > max_seconds {
            return Err(too_long(samples as f64 / f64::from(rate)));
        }
    }
    let rate = decoder.sample_rate();
    if samples == 0 || rate == 0 {
        return Err(ApiError::field("song", "the file holds no audio samples"));
    }
    Ok(samples as f64 / f64::from(rate))
}

/// What is wrong with an uploaded song the decoder refused, in a user's words: what the file
/// is and what to do, without the decoder's internals ("unsupported feature: core (probe):
/// no suitable format reader found" said that a text file named `.mp3` is not audio).
pub fn audio_fault(e: &MusicError) -> String {
    const FORMATS: &str = "WAV, MP3, OGG (Vorbis) or FLAC";
    match e {
        MusicError::EmptyFile { .. } => "the file is empty (0 bytes); choose a music file".into(),
        MusicError::UnknownFormat { .. } | MusicError::NoAudioTrack { .. } => {
            format!(
                "this file is not audio, or not in a format this server reads ({FORMATS}); choose a music file"
            )
        }
        MusicError::UnsupportedCodec { reason, .. } => format!(
            "the audio is in a codec this server cannot decode ({reason}); convert it to {FORMATS}"
        ),
        MusicError::Corrupt { .. } | MusicError::Truncated { .. } => {
            "the audio is damaged or cut short; upload it again or use another copy of the song"
                .into()
        }
        MusicError::NoSamples { .. } => "the file holds no audio samples".into(),
        MusicError::BadSampleRate { rate, .. } => {
            format!("the audio's sample rate ({rate} Hz) is not valid; convert it to {FORMATS}")
        }
        MusicError::Open { .. } | MusicError::Resample(_) | MusicError::InvalidParameter(_) => {
            "the audio could not be read; upload it again".into()
        }
    }
}

/// The danced span of a song `seconds` long, checked at upload as the job would find it, in
/// words that name the field and say what to do: a song shorter than the system's least
/// music, a start at or after the song's end, an end after it, or too little music between
/// start and end. (Found by the job, the same faults failed it after queueing, with the
/// server's path to the song and the command line's flags in the message.)
pub fn check_span(params: &JobParams, seconds: f64) -> Result<(), ApiError> {
    let system = &params.system;
    let least = dancegen_generate::systems::by_name(system)
        .map_err(|e| ApiError::field("system", e))?
        .min_seconds;
    if seconds < least {
        return Err(ApiError::field(
            "song",
            format!(
                "the song is {seconds:.1} s long; a {system} dance needs at least {least:.1} s \
                 of music. Choose a longer song"
            ),
        ));
    }
    let start = params.start.unwrap_or(0.0);
    if start + least > seconds {
        return Err(ApiError::field(
            "start",
            format!(
                "start {start} s leaves {:.1} s of the {seconds:.1} s song; a {system} dance \
                 needs at least {least:.1} s of music, so start at {:.1} s or earlier",
                (seconds - start).max(0.0),
                seconds - least
            ),
        ));
    }
    if let Some(end) = params.end {
        if end > seconds + END_SLACK_SECONDS {
            return Err(ApiError::field(
                "end",
                format!(
                    "end {end} s is after the song's end ({seconds:.1} s); give an end of at \
                     most {seconds:.1} s, or leave it empty to dance to the end of the song"
                ),
            ));
        }
        if end - start < least {
            return Err(ApiError::field(
                "end",
                format!(
                    "from start {start} s to end {end} s is {:.1} s; a {system} dance needs at \
                     least {least:.1} s of music, so end at {:.1} s or later",
                    end - start,
                    start + least
                ),
            ));
        }
    }
    Ok(())
}

/// How far past the decoded length an `end` may be (the page rounds the song's length it
/// shows; the job clamps to the last frame).
const END_SLACK_SECONDS: f64 = 0.05;

/// Reads the leader as the duet job will (blocking): an unreadable one is refused now.
pub fn check_leader(path: &Path) -> Result<(), ApiError> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    if !LEADER_FORMATS.contains(&ext.as_str()) {
        return Err(ApiError::field(
            "leader",
            format!(
                "the leader must be a dance motion file ({}), not a .{ext} file",
                LEADER_FORMATS.map(|f| format!(".{f}")).join(", ")
            ),
        ));
    }
    dancegen_generate::systems::duet::load_leader(path)
        .map(|_| ())
        .map_err(|e| {
            // The field names the leader already: the file's path is left out, not doubled.
            let shown = path.display().to_string();
            let text = crate::error::chain(&e)
                .replace(&format!("{shown}: "), "")
                .replace(&shown, "the leader");
            ApiError::field("leader", text)
        })
}

/// Motion formats a duet's leader may come in (the formats `dancegen convert` reads).
const LEADER_FORMATS: [&str; 6] = ["bvh", "npz", "npy", "pkl", "glb", "fbx"];
