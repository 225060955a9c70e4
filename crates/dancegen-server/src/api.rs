//! The HTTP API: routes, handlers and the limits around them.
//!
//! - `POST /api/jobs` (multipart `song`, `leader`, `character`, `params`) → `202 {"id"}`
//! - `GET /api/jobs/{id}` → the job object ([`crate::job::JobView`])
//! - `GET /api/jobs/{id}/events` → Server-Sent Events, the job object on every change
//! - `GET /api/jobs/{id}/files/{name}` → a job file, with HTTP Range (the viewer seeks the song)
//! - `DELETE /api/jobs/{id}` → cancels a queued or running job, removes a finished one
//! - `GET /api/jobs` → `{"jobs": [...]}`, the library: the newest jobs' objects, newest first
//! - `PATCH /api/jobs/{id}` (JSON `{"name"}`) → names the dance in the library
//! - `POST /api/jobs/{id}/again` (JSON `{"seed"}`, optional) → `202 {"id"}`: a new job with the
//!   job's song, leader, character and settings
//! - `GET /api/systems` → the systems, their genres and the limits
//! - anything else → the embedded viewer ([`crate::web`])

use std::convert::Infallible;
use std::net::{IpAddr, Ipv4Addr, SocketAddr};
use std::sync::{Arc, Mutex};

use axum::body::Body;
use axum::extract::multipart::MultipartRejection;
use axum::extract::{ConnectInfo, DefaultBodyLimit, FromRequest, Multipart, Path, Request, State};
use axum::http::{HeaderMap, HeaderValue, StatusCode, header};
use axum::middleware::{self, Next};
use axum::response::sse::{Event, KeepAlive, Sse};
use axum::response::{IntoResponse, Response};
use axum::routing::{get, post};
use axum::{Json, Router};
use tokio_stream::StreamExt;
use tokio_stream::wrappers::WatchStream;
use tower::ServiceExt;
use tower_http::services::ServeFile;
use tower_http::timeout::{RequestBodyDeadlineLayer, TimeoutLayer};

use crate::catalog::Catalog;
use crate::client_limits::ClientLimits;
use crate::config::{Limits, SSE_KEEP_ALIVE};
use crate::edit_job;
use crate::error::ApiError;
use crate::files;
use crate::job::{JobParams, JobState};
use crate::jobs::Jobs;
use crate::library;
use crate::owner::{self, AdminKey, Caller};
use crate::upload;
use crate::{download_all, download_names};

/// What every handler shares.
#[derive(Clone)]
pub struct AppState {
    pub jobs: Arc<Jobs>,
    pub limits: Limits,
    pub catalog: Arc<Catalog>,
    /// Makes "count the queue, then add a job" one step, so the queue limit holds under
    /// concurrent submissions.
    pub submit_lock: Arc<Mutex<()>>,
    /// The administrator's token ([`crate::owner`]).
    pub admin: AdminKey,
    /// Jobs per minute and open streams per client address.
    pub clients: Arc<ClientLimits>,
}

/// The client's address (the TCP peer), for the per-client limits; unspecified when the
/// server was not started with connection info (never in `serve`).
fn peer_of(extensions: &axum::http::Extensions) -> IpAddr {
    extensions
        .get::<ConnectInfo<SocketAddr>>()
        .map_or(IpAddr::V4(Ipv4Addr::UNSPECIFIED), |c| c.0.ip())
}

/// Room for the multipart framing and the params part on top of the upload limit.
const FORM_OVERHEAD: usize = 64 << 10;

pub fn router(state: AppState) -> Router {
    let limits = state.limits.clone();
    let upload = Router::new()
        .route("/api/jobs", post(submit).get(library))
        .layer(DefaultBodyLimit::max(limits.upload_bytes + FORM_OVERHEAD))
        .layer(TimeoutLayer::with_status_code(
            StatusCode::REQUEST_TIMEOUT,
            limits.body_deadline + limits.request_timeout,
        ))
        .layer(RequestBodyDeadlineLayer::new(limits.body_deadline));
    let rest = Router::new()
        .route("/api/systems", get(systems))
        .route("/api/jobs/{id}", get(status).delete(delete).patch(rename))
        .route("/api/jobs/{id}/again", post(again))
        .route("/api/jobs/{id}/events", get(events))
        .route("/api/jobs/{id}/versions", get(versions))
        .route("/api/jobs/{id}/files/{name}", get(file))
        .route("/api/jobs/{id}/zip", get(zip_all))
        .route("/api/{*rest}", get(unknown_api))
        .fallback(crate::web::asset)
        // Only up to the response headers: an SSE stream lives on after them.
        .layer(TimeoutLayer::with_status_code(
            StatusCode::REQUEST_TIMEOUT,
            limits.request_timeout,
        ))
        .layer(DefaultBodyLimit::max(FORM_OVERHEAD));
    let policy = HeaderValue::from_str(&crate::headers::content_security_policy(
        crate::web::import_map().as_deref(),
    ))
    .expect("the policy is ASCII");
    upload
        .merge(rest)
        .with_state(state)
        .layer(middleware::from_fn(json_errors))
        .layer(middleware::from_fn(move |req, next| {
            crate::headers::add(policy.clone(), req, next)
        }))
}

/// Errors made by the layers (a timeout, a body over the limit) get the same JSON body as
/// the handlers' own.
async fn json_errors(req: Request, next: Next) -> Response {
    let res = next.run(req).await;
    let status = res.status();
    let is_json = res
        .headers()
        .get(header::CONTENT_TYPE)
        .is_some_and(|v| v.as_bytes().starts_with(b"application/json"));
    if status.is_client_error() && !is_json && status != StatusCode::RANGE_NOT_SATISFIABLE {
        let words = match status {
            StatusCode::REQUEST_TIMEOUT => "the request took too long (the upload deadline or \
                                            the request timeout passed)"
                .to_string(),
            StatusCode::PAYLOAD_TOO_LARGE => {
                return ApiError::limit(
                    status,
                    "max-upload-mb",
                    "the request body is larger than the limit (--max-upload-mb)",
                )
                .into_response();
            }
            s => s.canonical_reason().unwrap_or("bad request").to_string(),
        };
        return ApiError::new(status, words).into_response();
    }
    res
}

async fn systems(State(s): State<AppState>) -> Json<serde_json::Value> {
    Json(s.catalog.json(&s.limits))
}

async fn unknown_api() -> ApiError {
    ApiError::not_found("no such API route")
}

/// Most bytes of an upload over the limit that are read and dropped before the 413: a client
/// that sends its whole body before reading the answer (a plain HTTP client; browsers and curl
/// read early) otherwise got a reset connection instead of the JSON. Beyond this the
/// connection is closed; the body deadline bounds the time.
const DRAIN_MAX_BYTES: usize = 1 << 30;

async fn submit(
    State(s): State<AppState>,
    req: Request,
) -> Result<(StatusCode, Json<serde_json::Value>), ApiError> {
    let caller = owner::caller(req.headers(), &s.admin)?;
    let peer = peer_of(req.extensions());
    let limit = s.limits.upload_bytes;
    let declared = req
        .headers()
        .get(header::CONTENT_LENGTH)
        .and_then(|v| v.to_str().ok())
        .and_then(|v| v.parse::<usize>().ok());
    if let Some(n) = declared.filter(|&n| n > limit + FORM_OVERHEAD) {
        // Answer at once (a client that waits for it reads it before sending), and read the
        // body on, dropping it, for a client that sends it all first.
        if n <= DRAIN_MAX_BYTES {
            let mut body = req.into_body().into_data_stream();
            tokio::spawn(async move {
                let mut read = 0usize;
                while let Some(Ok(chunk)) = body.next().await {
                    read += chunk.len();
                    if read >= n {
                        break;
                    }
                }
            });
        }
        return Err(ApiError::limit(
            StatusCode::PAYLOAD_TOO_LARGE,
            "max-upload-mb",
            format!(
                "upload of {:.1} MB is larger than the limit of {} MB",
                n as f64 / (1 << 20) as f64,
                limit >> 20
            ),
        ));
    }
    let form = Multipart::from_request(req, &s)
        .await
        .map_err(|e: MultipartRejection| ApiError::new(e.status(), e.body_text()))?;
    let up = upload::read(form, limit, s.limits.max_variations).await?;
    // After the body is read, so the client (a browser still sending the song) gets the 429
    // rather than a connection closed under it; before the song is decoded, so a full queue
    // costs no decoding. Checked again when the job is added.
    check_queue(&s, peer)?;
    check_disk(&s).await?;
    // An edit takes its song, leader, system and span from the job it edits.
    let edited = match &up.params.edit {
        Some(e) => {
            let row = edit_job::edited_job(&s.jobs, e)?;
            owner::may_change(&caller, &row, "edit this dance")?;
            Some((row, e.clone()))
        }
        None => None,
    };
    let params = match &edited {
        Some((row, _)) => up.params.clone().editing(&row.params),
        None => JobParams {
            song_title: up
                .song
                .as_ref()
                .map(|f| download_names::song_title(&f.name)),
            character: up
                .character
                .as_ref()
                .map(|c| upload::character_file_name(&c.name)),
            ..up.params.clone()
        },
    };
    if let Some(song) = &up.song
        && song.bytes.len() > limit
    {
        return Err(ApiError::limit(
            StatusCode::PAYLOAD_TOO_LARGE,
            "max-upload-mb",
            format!("the song is larger than the limit of {} MB", limit >> 20),
        ));
    }
    s.catalog.check(&params)?;

    // Files first, in a hidden folder renamed into place, then the row: a crash in between
    // leaves no half job.
    let id = s.jobs.new_id()?;
    let jobs_dir = files::jobs_dir(s.jobs.data_dir());
    let incoming = jobs_dir.join(format!(".incoming-{id}"));
    let (song_name, leader_name) = match (&edited, &up.song) {
        (Some((row, _)), _) => (row.song.clone(), row.leader.clone()),
        (None, song) => (
            upload::song_file_name(song.as_ref().map_or("", |f| f.name.as_str())),
            up.leader
                .as_ref()
                .map(|l| upload::leader_file_name(&l.name)),
        ),
    };
    let song_bytes: Option<Arc<[u8]>> = up.song.map(|f| Arc::from(f.bytes));
    let leader_bytes = up.leader.map(|l| l.bytes);
    let character_bytes = up.character.map(|c| c.bytes);
    let character_name = params.character.clone();
    let max_seconds = s.limits.song_seconds;
    let edited_dir = edited.as_ref().map(|(row, _)| s.jobs.job_dir(&row.id));
    let end = params.end;
    let prepared = {
        let (incoming, song_name, leader_name) =
            (incoming.clone(), song_name.clone(), leader_name.clone());
        let asked = params.clone();
        tokio::task::spawn_blocking(move || -> Result<(), ApiError> {
            if let Some(bytes) = &song_bytes {
                let seconds = upload::check_song(&song_name, bytes.clone(), max_seconds)?;
                upload::check_span(&asked, seconds)?;
            }
            std::fs::create_dir_all(&incoming)
                .map_err(|e| ApiError::internal(format!("{}: {e}", incoming.display())))?;
            if let (Some((row, e)), Some(from)) = (&edited, &edited_dir) {
                return edit_job::take_files(from, row, e, end, &incoming);
            }
            let write = |name: &str, bytes: &[u8]| {
                std::fs::write(incoming.join(name), bytes)
                    .map_err(|e| ApiError::internal(format!("saving the upload: {e}")))
            };
            if let Some(bytes) = &song_bytes {
                write(&song_name, bytes)?;
            }
            if let (Some(name), Some(bytes)) = (&leader_name, &leader_bytes) {
                write(name, bytes)?;
                upload::check_leader(&incoming.join(name))?;
            }
            if let (Some(name), Some(bytes)) = (&character_name, &character_bytes) {
                write(name, bytes)?;
                upload::check_character(&incoming.join(name))?;
            }
            Ok(())
        })
        .await
        .map_err(|e| ApiError::internal(format!("checking the upload: {e}")))?
    };
    let job = NewJob {
        id,
        incoming,
        params,
        song: song_name,
        leader: leader_name,
        owner: NewOwner::of(&caller)?,
        peer,
    };
    enqueue(&s, job, prepared)
}

/// Who a new job belongs to: the caller's owner secret, a new one for a caller without, none
/// for the administrator.
struct NewOwner {
    key: Option<String>,
    secret: Option<String>,
}

impl NewOwner {
    fn of(caller: &Caller) -> Result<Self, ApiError> {
        let secret = match caller {
            Caller::Admin => None,
            Caller::Owner { secret, .. } => Some(secret.clone()),
            Caller::Anonymous => Some(owner::new_secret()?),
        };
        Ok(NewOwner {
            key: secret.as_deref().map(owner::owner_key),
            secret,
        })
    }
}

/// A job whose files are ready in its hidden `incoming` folder.
struct NewJob {
    id: String,
    incoming: std::path::PathBuf,
    params: JobParams,
    song: String,
    leader: Option<String>,
    owner: NewOwner,
    /// The client address it counts against ([`ClientLimits`]).
    peer: IpAddr,
}

/// Moves a prepared job's folder into place and queues it (`202 {"id", "owner"}`), or, when preparing
/// it failed or the queue is full, removes what was prepared.
fn enqueue(
    s: &AppState,
    job: NewJob,
    prepared: Result<(), ApiError>,
) -> Result<(StatusCode, Json<serde_json::Value>), ApiError> {
    let queued = prepared.and_then(|()| {
        let _one_at_a_time = s.submit_lock.lock().unwrap_or_else(|e| e.into_inner());
        check_queue(s, job.peer).and_then(|()| {
            std::fs::rename(&job.incoming, s.jobs.job_dir(&job.id))
                .map_err(|e| ApiError::internal(format!("saving the upload: {e}")))?;
            s.jobs.store.insert(
                &job.id,
                &job.params,
                &job.song,
                job.leader.as_deref(),
                job.owner.key.as_deref(),
            )?;
            Ok(())
        })
    });
    let id = job.id;
    if let Err(e) = queued {
        let _ = std::fs::remove_dir_all(&job.incoming);
        let _ = std::fs::remove_dir_all(s.jobs.job_dir(&id));
        return Err(e);
    }
    s.clients.count_job(job.peer);
    tracing::info!("job {id}: queued ({})", job.params.system);
    s.jobs.publish(&id);
    s.jobs.notify_work();
    let reply = match job.owner.secret {
        Some(secret) => serde_json::json!({ "id": id, "owner": secret }),
        None => serde_json::json!({ "id": id }),
    };
    Ok((StatusCode::ACCEPTED, Json(reply)))
}

/// `GET /api/jobs`: the library: the caller's jobs (every job for the administrator, none
/// without an owner secret).
async fn library(
    State(s): State<AppState>,
    headers: HeaderMap,
) -> Result<Json<serde_json::Value>, ApiError> {
    let owner = match owner::caller(&headers, &s.admin)? {
        Caller::Anonymous => return Ok(Json(serde_json::json!({ "jobs": [] }))),
        Caller::Owner { key, .. } => Some(key),
        Caller::Admin => None,
    };
    let jobs = tokio::task::spawn_blocking(move || {
        s.jobs.library(library::LIBRARY_LIMIT, owner.as_deref())
    })
    .await
    .map_err(|e| ApiError::internal(format!("listing the jobs: {e}")))??;
    Ok(Json(serde_json::json!({ "jobs": jobs })))
}

#[derive(serde::Deserialize)]
struct Rename {
    name: Option<String>,
}

/// `PATCH /api/jobs/{id}` `{"name"}`: the dance's name in the library.
async fn rename(
    State(s): State<AppState>,
    Path(id): Path<String>,
    headers: HeaderMap,
    body: Result<Json<Rename>, axum::extract::rejection::JsonRejection>,
) -> Result<Json<crate::job::JobView>, ApiError> {
    let caller = owner::caller(&headers, &s.admin)?;
    let Json(body) = body.map_err(|e| {
        ApiError::field(
            "name",
            format!("send JSON {{\"name\": \"...\"}}: {}", e.body_text()),
        )
    })?;
    let name = library::checked_name(body.name.as_deref())?;
    let row = existing(&s, &id)?;
    owner::may_change(&caller, &row, "rename this dance")?;
    if !s.jobs.store.rename(&id, name.as_deref())? {
        return Err(no_job(&id));
    }
    s.jobs.publish(&id);
    s.jobs.view(&id)?.map(Json).ok_or_else(|| no_job(&id))
}

#[derive(serde::Deserialize)]
struct Again {
    seed: Option<u64>,
}

/// `POST /api/jobs/{id}/again` `{"seed"}`: a new job with this one's song, leader and
/// settings (another seed when given).
async fn again(
    State(s): State<AppState>,
    Path(id): Path<String>,
    ConnectInfo(peer): ConnectInfo<SocketAddr>,
    headers: HeaderMap,
    body: axum::body::Bytes,
) -> Result<(StatusCode, Json<serde_json::Value>), ApiError> {
    let caller = owner::caller(&headers, &s.admin)?;
    let peer = peer.ip();
    // No body, or JSON `{"seed": N}`; anything else is said in words.
    let seed = if body.iter().all(u8::is_ascii_whitespace) {
        None
    } else {
        serde_json::from_slice::<Again>(&body)
            .map_err(|e| {
                ApiError::field(
                    "seed",
                    format!("send JSON {{\"seed\": N}} with N a whole number from 0 ({e})"),
                )
            })?
            .seed
    };
    let row = existing(&s, &id)?;
    owner::may_change(&caller, &row, "make this dance again")?;
    let params = library::again_params(&row, seed)?;
    s.catalog.check(&params)?;
    check_queue(&s, peer)?;
    check_disk(&s).await?;
    let new_id = s.jobs.new_id()?;
    let incoming = files::jobs_dir(s.jobs.data_dir()).join(format!(".incoming-{new_id}"));
    let from = s.jobs.job_dir(&id);
    let job = NewJob {
        id: new_id,
        incoming: incoming.clone(),
        params,
        song: row.song.clone(),
        leader: row.leader.clone(),
        owner: NewOwner::of(&caller)?,
        peer,
    };
    let copied = tokio::task::spawn_blocking(move || library::copy_inputs(&from, &row, &incoming))
        .await
        .map_err(|e| ApiError::internal(format!("copying the song: {e}")))?;
    enqueue(&s, job, copied)
}

/// The queue's room and the client's jobs per minute.
fn check_queue(s: &AppState, peer: IpAddr) -> Result<(), ApiError> {
    s.clients.check_job(peer)?;
    let active = s.jobs.store.active_count()?;
    if active >= s.limits.queue_length {
        return Err(ApiError::limit(
            StatusCode::TOO_MANY_REQUESTS,
            "max-queue",
            format!(
                "the queue is full ({active} jobs waiting or running, the limit is {}); \
                 try again when some have finished",
                s.limits.queue_length
            ),
        ));
    }
    Ok(())
}

/// 507 when the job folders hold `--max-disk-gb` or more. Nothing is removed to make room:
/// old jobs go only by `--keep-days` or by their owners.
async fn check_disk(s: &AppState) -> Result<(), ApiError> {
    let Some(max) = s.limits.disk_bytes else {
        return Ok(());
    };
    let dir = files::jobs_dir(s.jobs.data_dir());
    let used = tokio::task::spawn_blocking(move || files::dir_bytes(&dir))
        .await
        .map_err(|e| ApiError::internal(format!("measuring the job folders: {e}")))?;
    if used >= max {
        return Err(ApiError::limit(
            StatusCode::INSUFFICIENT_STORAGE,
            "max-disk-gb",
            format!(
                "the dances on this server use {:.2} GB, the limit (--max-disk-gb {:.2}); \
                 delete some in My dances, or ask whoever runs it for room",
                used as f64 / 1e9,
                max as f64 / 1e9
            ),
        ));
    }
    Ok(())
}

fn no_job(id: &str) -> ApiError {
    ApiError::not_found(format!("no job {id}"))
}

/// The row of job `id`, or the 404.
fn existing(s: &AppState, id: &str) -> Result<crate::store::JobRow, ApiError> {
    if !files::valid_id(id) {
        return Err(no_job(id));
    }
    s.jobs.store.get(id)?.ok_or_else(|| no_job(id))
}

async fn status(
    State(s): State<AppState>,
    Path(id): Path<String>,
) -> Result<Json<crate::job::JobView>, ApiError> {
    s.jobs.view(&id)?.map(Json).ok_or_else(|| no_job(&id))
}

/// `{"versions": [...]}`: the dance `id` belongs to, every version of it ([`crate::versions`]).
async fn versions(
    State(s): State<AppState>,
    Path(id): Path<String>,
) -> Result<Json<serde_json::Value>, ApiError> {
    if !files::valid_id(&id) {
        return Err(no_job(&id));
    }
    let list = crate::versions::versions(&s.jobs, &id)?.ok_or_else(|| no_job(&id))?;
    Ok(Json(serde_json::json!({ "versions": list })))
}

async fn delete(
    State(s): State<AppState>,
    Path(id): Path<String>,
    headers: HeaderMap,
) -> Result<Response, ApiError> {
    let caller = owner::caller(&headers, &s.admin)?;
    let row = existing(&s, &id)?;
    let action = if row.state.is_final() {
        "delete this dance"
    } else {
        "cancel this job"
    };
    owner::may_change(&caller, &row, action)?;
    match s.jobs.cancel_or_remove(&id)? {
        None => Err(no_job(&id)),
        Some(Some(view)) => Ok((StatusCode::ACCEPTED, Json(view)).into_response()),
        Some(None) => Ok(StatusCode::NO_CONTENT.into_response()),
    }
}

async fn events(
    State(s): State<AppState>,
    Path(id): Path<String>,
    ConnectInfo(peer): ConnectInfo<SocketAddr>,
) -> Result<Sse<impl tokio_stream::Stream<Item = Result<Event, Infallible>>>, ApiError> {
    let rx = s.jobs.subscribe(&id)?.ok_or_else(|| no_job(&id))?;
    // Held by the stream: the slot comes back when the client goes.
    let slot = s.clients.open_stream(peer.ip())?;
    // A watch stream yields the current object first, then every change (intermediate ones
    // are skipped when the client is slower than the job, which is what a progress bar wants).
    let stream = WatchStream::new(rx).map(move |view| {
        let _held = &slot;
        Ok(Event::default()
            .json_data(&view)
            .unwrap_or_else(|_| Event::default().comment("unserialisable job")))
    });
    Ok(Sse::new(stream).keep_alive(KeepAlive::new().interval(SSE_KEEP_ALIVE)))
}

async fn file(
    State(s): State<AppState>,
    Path((id, name)): Path<(String, String)>,
    req: Request,
) -> Result<Response, ApiError> {
    let not_found = || ApiError::not_found(format!("job {id} has no file '{name}'"));
    if !files::valid_id(&id) || s.jobs.store.get(&id)?.is_none() {
        return Err(no_job(&id));
    }
    let path = files::resolve(&s.jobs.job_dir(&id), &name).ok_or_else(not_found)?;
    // A dance file is saved under its download name (`<song>-<system>-seed<k>.<ext>`).
    let download = s.jobs.view(&id)?.and_then(|view| {
        let url = files::url(&id, &name);
        view.variations.iter().find_map(|v| {
            let kind = v.files.iter().find(|(_, u)| **u == url)?.0;
            v.names.get(kind).cloned()
        })
    });
    let res = ServeFile::new(path)
        .oneshot(req)
        .await
        .map_err(|e| ApiError::internal(format!("reading {name}: {e}")))?;
    let mut res = res.map(Body::new);
    // Always an attachment: a file from a job is downloaded, never shown as a page of this
    // site (the viewer's `fetch` and `<audio>` ignore the header). Dance files under their
    // download name, the others (song, thumbnail, timeline) under their own.
    let shown = download.unwrap_or_else(|| name.clone());
    if let Ok(v) = HeaderValue::from_str(&download_names::content_disposition("attachment", &shown))
    {
        res.headers_mut().insert(header::CONTENT_DISPOSITION, v);
    }
    Ok(res)
}

/// `GET /api/jobs/{id}/zip`: every dance file of a finished job in one zip
/// ([`crate::download_all`]).
async fn zip_all(State(s): State<AppState>, Path(id): Path<String>) -> Result<Response, ApiError> {
    let view = s.jobs.view(&id)?.ok_or_else(|| no_job(&id))?;
    if view.state != JobState::Done {
        return Err(ApiError::new(
            StatusCode::CONFLICT,
            "the dance is not finished yet; its files can be downloaded together once it is",
        ));
    }
    let dir = s.jobs.job_dir(&id);
    let name = download_all::zip_name(&view);
    let bytes = tokio::task::spawn_blocking(move || download_all::zip_of(&view, &dir))
        .await
        .map_err(|e| ApiError::internal(format!("zipping the files: {e}")))?
        .map_err(ApiError::internal)?;
    let disposition = download_names::content_disposition("attachment", &name);
    Ok((
        [
            (header::CONTENT_TYPE, "application/zip".to_string()),
            (header::CONTENT_DISPOSITION, disposition),
        ],
        bytes,
    )
        .into_response())
}
