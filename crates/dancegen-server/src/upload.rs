//! `POST /api/jobs`: reading the multipart upload, and checking the song and the leader
//! before a job is queued, so a file that cannot be danced to is a 400 at once rather than a
//! failed job later.

use std::path::Path;
use std::sync::Arc;

use axum::extract::Multipart;
use axum::extract::multipart::MultipartError;
use axum::http::StatusCode;

use dancegen_music::decode::{AudioSource, MonoDecoder};

use crate::error::ApiError;
use crate::files::extension_of;
use crate::job::JobParams;

/// The parts of an upload.
pub struct Upload {
    /// The song; `None` for an edit, which dances to the song of the job it edits.
    pub song: Option<UploadedFile>,
    pub leader: Option<UploadedFile>,
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

/// Reads `song`, `leader` and `params`; any other part is an error naming it.
pub async fn read(
    mut form: Multipart,
    upload_limit: usize,
    max_variations: usize,
) -> Result<Upload, ApiError> {
    let mut song = None;
    let mut leader = None;
    let mut params_text = None;
    let mut form_fields = Vec::new();
    while let Some(field) = form
        .next_field()
        .await
        .map_err(|e| multipart_error(e, upload_limit))?
    {
        let name = field.name().unwrap_or("").to_string();
        match name.as_str() {
            "song" | "leader" => {
                let file_name = field.file_name().unwrap_or("").to_string();
                let bytes = field
                    .bytes()
                    .await
                    .map_err(|e| multipart_error(e, upload_limit))?;
                let f = UploadedFile {
                    name: file_name,
                    bytes: bytes.to_vec(),
                };
                if name == "song" {
                    song = Some(f);
                } else {
                    leader = Some(f);
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
                        "unknown part '{other}' (send song, leader and params, or the \
                         parameters as form fields)"
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
        // The song and the leader are the edited job's.
        for (part, given) in [("song", song.is_some()), ("leader", leader.is_some())] {
            if given {
                return Err(ApiError::field(
                    part,
                    "an edit dances to the song (and leader) of the job it edits; send none",
                ));
            }
        }
        return Ok(Upload {
            song: None,
            leader: None,
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
    Ok(Upload {
        song: Some(song),
        leader,
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

/// Decodes the whole song (blocking; run it off the async threads): a file the decoder
/// cannot read is refused with the decoder's words, a song longer than `max_seconds` with
/// the limit. Returns its length in seconds.
pub fn check_song(name: &str, bytes: Arc<[u8]>, max_seconds: f64) -> Result<f64, ApiError> {
    let source = AudioSource::Bytes {
        name: Path::new(name).to_path_buf(),
        bytes,
    };
    let bad = |e: dancegen_music::error::MusicError| {
        ApiError::field("song", format!("cannot read the audio: {e}"))
    };
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

/// Reads the leader as the duet job will (blocking): an unreadable one is refused now.
pub fn check_leader(path: &Path) -> Result<(), ApiError> {
    dancegen_generate::systems::duet::load_leader(path)
        .map(|_| ())
        .map_err(|e| {
            let text = crate::error::chain(&e).replace(&path.display().to_string(), "leader");
            ApiError::field("leader", text)
        })
}
