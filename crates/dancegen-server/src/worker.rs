//! The worker pool: a fixed number of OS threads (never the async runtime's) that take queued
//! jobs from the store, one at a time each, and run them through the generation library —
//! the same [`Generator`] and [`Request`] the CLI builds, so a job's files are the bytes
//! `dancegen generate` writes for the same song, options and seed.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use dancegen_formats::rig::Rig;
use dancegen_generate::progress::stage::WRITE_OUTPUTS;
use dancegen_generate::request::{CommonOptions, DancerSelection, OutputRequest, VideoSize};
use dancegen_generate::systems::duet::{DuetOptions, load_leader};
use dancegen_generate::systems::group::GroupOptions;
use dancegen_generate::{
    CancelToken, GenerateError, Generator, Progress, Request, Song, SystemRequest,
};

use crate::error::chain;
use crate::job::{
    FACE_FORMATS, FACE_SYSTEM, JobParams, JobState, LEADER_NPY, MOTION_FORMATS, variation_stem,
};
use crate::jobs::Jobs;
use crate::store::JobRow;
use crate::user_words;

/// How often a running job's progress is written to the database (listeners hear every
/// report at once; the database only needs it for a status after a restart).
const STORE_PROGRESS_EVERY: Duration = Duration::from_millis(500);
/// Longest an idle worker sleeps before looking at the queue again on its own.
const IDLE_POLL: Duration = Duration::from_secs(2);

/// Running worker threads; [`Workers::stop`] lets each finish its job's current step.
pub struct Workers {
    stop: Arc<AtomicBool>,
    threads: Vec<std::thread::JoinHandle<()>>,
}

impl Workers {
    /// Starts `n` workers over `jobs`; `models` overrides the model folder per system name.
    pub fn start(
        n: usize,
        jobs: Arc<Jobs>,
        generator: Arc<Generator>,
        models: Vec<(String, PathBuf)>,
    ) -> Result<Self, String> {
        let stop = Arc::new(AtomicBool::new(false));
        let mut workers = Workers {
            stop: stop.clone(),
            threads: Vec::new(),
        };
        for i in 0..n.max(1) {
            let (j, generator, stop, models) = (
                jobs.clone(),
                generator.clone(),
                stop.clone(),
                models.clone(),
            );
            match std::thread::Builder::new()
                .name(format!("dancegen-worker-{i}"))
                .spawn(move || work(&j, &generator, &stop, &models))
            {
                Ok(t) => workers.threads.push(t),
                Err(e) => {
                    workers.stop(&jobs);
                    return Err(format!("starting worker thread {i}: {e}"));
                }
            }
        }
        Ok(workers)
    }

    /// Stops taking jobs; a running job is cancelled and goes back to the queue on the next
    /// start (its state stays `running` in the store, which a restart requeues).
    pub fn stop(self, jobs: &Jobs) {
        self.stop.store(true, Ordering::SeqCst);
        jobs.cancel_all();
        jobs.notify_work();
        for t in self.threads {
            let _ = t.join();
        }
    }
}

fn work(jobs: &Jobs, generator: &Generator, stop: &AtomicBool, models: &[(String, PathBuf)]) {
    let mut seen = jobs.work_counter();
    while !stop.load(Ordering::SeqCst) {
        match jobs.store.claim() {
            Ok(Some(row)) => run_job(jobs, generator, stop, models, &row),
            Ok(None) => seen = jobs.wait_for_work(seen, IDLE_POLL),
            Err(e) => {
                tracing::error!("job database: {e}");
                std::thread::sleep(IDLE_POLL);
            }
        }
    }
}

fn run_job(
    jobs: &Jobs,
    generator: &Generator,
    stop: &AtomicBool,
    models: &[(String, PathBuf)],
    row: &JobRow,
) {
    let id = row.id.as_str();
    let cancel = jobs.cancel_token(id);
    jobs.publish(id);
    jobs.publish_queue();
    tracing::info!("job {id}: {} started", row.params.system);
    let started = Instant::now();
    let result = generate(jobs, generator, models, row, &cancel);
    jobs.forget_cancel_token(id);
    let (state, error, warnings) = match result {
        Ok(warnings) => (JobState::Done, None, warnings),
        Err(GenerateError::Cancelled) if stop.load(Ordering::SeqCst) => {
            // The server is shutting down: leave it `running`, so the next start runs it.
            tracing::info!("job {id}: interrupted by shutdown, runs again on the next start");
            return;
        }
        Err(GenerateError::Cancelled) => (JobState::Cancelled, None, Vec::new()),
        Err(e) => {
            let words = user_words::for_user(
                &chain(&e),
                &jobs.job_dir(id),
                &row.song,
                row.leader.as_deref(),
            );
            (JobState::Failed, Some(words), Vec::new())
        }
    };
    tracing::info!(
        "job {id}: {} in {:.1} s{}",
        state.as_str(),
        started.elapsed().as_secs_f64(),
        error
            .as_deref()
            .map(|e| format!(": {e}"))
            .unwrap_or_default()
    );
    if state == JobState::Done
        && let Err(e) = crate::thumbnail::write_thumbnail(&jobs.job_dir(id))
    {
        tracing::warn!("job {id}: no picture for the library: {e}");
    }
    record_end(jobs, stop, id, state, error.as_deref(), &warnings);
    jobs.publish(id);
}

/// How often the end of a job is written again while the database cannot take it.
const RECORD_RETRY: Duration = Duration::from_secs(2);

/// Writes the job's end to the store. When that fails (a full disk: SQLite cannot grow its
/// log), the end is shown from memory at once, so clients see the job finish, and written
/// again every [`RECORD_RETRY`] until it is stored: this worker takes no other job meanwhile
/// (none could write its files either). On shutdown it gives up; the job, still `running` in
/// the store, runs again on the next start.
fn record_end(
    jobs: &Jobs,
    stop: &AtomicBool,
    id: &str,
    state: JobState,
    error: Option<&str>,
    warnings: &[String],
) {
    let mut said = false;
    while let Err(e) = jobs.store.finish(id, state, error, warnings) {
        if !said {
            tracing::error!(
                "job {id}: recording its end: {e}; trying again every {RECORD_RETRY:?}"
            );
            jobs.show_end(id, state, error);
            said = true;
        }
        if stop.load(Ordering::SeqCst) {
            return;
        }
        std::thread::sleep(RECORD_RETRY);
    }
    if said {
        tracing::info!("job {id}: its end is recorded");
    }
}

/// Every variation of the job, in order; progress is spread evenly over them.
fn generate(
    jobs: &Jobs,
    generator: &Generator,
    models: &[(String, PathBuf)],
    row: &JobRow,
    cancel: &CancelToken,
) -> Result<Vec<String>, GenerateError> {
    let dir = jobs.job_dir(&row.id);
    let mut warnings: Vec<String> = Vec::new();
    let p = &row.params;
    let system = system_request(p, &dir, row.leader.as_deref())?;
    let model = models
        .iter()
        .find(|(name, _)| *name == p.system)
        .map(|(_, d)| d.clone());
    let edit = match &p.edit {
        Some(e) => crate::edit_job::library_edit(&dir, e)?,
        None => Default::default(),
    };
    // The user's character: the .glb shows it dancing (read once for every variation).
    let character = match &p.character {
        Some(name) => Some(Arc::new(
            crate::upload::load_character(&dir.join(name))
                .map_err(|e| GenerateError::Invalid(e.message))?,
        )),
        None => None,
    };
    let variations = p.variations.max(1);
    let last_store = std::sync::Mutex::new(Instant::now() - STORE_PROGRESS_EVERY);
    for k in 0..variations {
        if cancel.is_cancelled() {
            return Err(GenerateError::Cancelled);
        }
        let stem = variation_stem(k);
        // Checked when the job was made; an unreadable value in an old row is SMPL's names.
        let rig = p
            .rig
            .as_deref()
            .and_then(|r| Rig::from_name(r).ok())
            .unwrap_or_default();
        let mut outputs: Vec<OutputRequest> = MOTION_FORMATS
            .iter()
            .map(|ext| OutputRequest {
                rig,
                character: (*ext == "glb").then(|| character.clone()).flatten(),
                ..OutputRequest::new(dir.join(format!("{stem}.{ext}")))
            })
            .collect();
        if p.mp4 {
            // Checked when the job was made; an unreadable value in an old row is 640x480.
            let video = p
                .video_size
                .as_deref()
                .and_then(|v| VideoSize::parse(v).ok())
                .unwrap_or_default();
            outputs.push(OutputRequest {
                video,
                ..OutputRequest::new(dir.join(format!("{stem}.mp4")))
            });
        }
        if p.system == FACE_SYSTEM {
            outputs.extend(
                FACE_FORMATS
                    .iter()
                    .map(|ext| OutputRequest::new(dir.join(format!("{stem}.{ext}")))),
            );
        }
        if p.system == "duet" && k == 0 {
            outputs.push(OutputRequest {
                path: dir.join(LEADER_NPY),
                dancers: DancerSelection::Given,
                rig: Default::default(),
                character: None,
                video: Default::default(),
            });
        }
        let request = Request {
            song: Song::File(dir.join(&row.song)),
            system: system.clone(),
            common: CommonOptions {
                seed: p.seed_of(k),
                steps: p.steps,
                guidance: None,
                genre: p.genre.clone(),
                start: p.start,
                end: p.end,
                edit: edit.clone(),
            },
            model: model.clone(),
            outputs,
        };
        let on_progress = |q: &Progress| {
            let whole = (k as f64 + q.fraction) / variations as f64;
            // The ETA of this variation plus the whole time of those still to come.
            let eta = q.eta_s.map(|e| {
                let per = if q.fraction > 0.0 && q.fraction < 1.0 {
                    e / (1.0 - q.fraction)
                } else {
                    e
                };
                e + per * (variations - k - 1) as f64
            });
            jobs.publish_progress(&row.id, q.stage, whole, eta);
            let mut last = last_store.lock().unwrap_or_else(|e| e.into_inner());
            if last.elapsed() >= STORE_PROGRESS_EVERY {
                *last = Instant::now();
                if let Err(e) = jobs.store.progress(&row.id, q.stage, whole, eta) {
                    tracing::warn!("job {}: recording progress: {e}", row.id);
                }
            }
        };
        let done = generator.run(&request, &on_progress, cancel)?;
        if k == 0
            && let Err(e) = crate::timeline::write_timeline(
                &dir,
                &dir.join(&row.song),
                (done.start_s, done.end_s),
                &done.beat_times_s,
                done.tempo_bpm,
            )
        {
            tracing::warn!("job {}: no timeline for the viewer: {e}", row.id);
        }
        // Variations share the song: a warning about it is said once.
        for w in done.warnings {
            if !warnings.contains(&w) {
                warnings.push(w);
            }
        }
        // The store's progress lags (written every STORE_PROGRESS_EVERY); bring it level before
        // the files are published, so the object listeners get does not step back.
        let whole = (k + 1) as f64 / variations as f64;
        if let Err(e) = jobs.store.progress(&row.id, WRITE_OUTPUTS, whole, None) {
            tracing::warn!("job {}: recording progress: {e}", row.id);
        }
        // The variation's files are in place: listeners see them appear one variation at a time.
        jobs.publish(&row.id);
    }
    Ok(warnings)
}

/// The system and its options for `p`, as `dancegen generate` builds them from its flags.
fn system_request(
    p: &JobParams,
    dir: &Path,
    leader: Option<&str>,
) -> Result<SystemRequest, GenerateError> {
    Ok(match p.system.as_str() {
        "solo" => SystemRequest::Solo(Default::default()),
        "duet" => {
            let name = leader
                .ok_or_else(|| GenerateError::Invalid("the duet job has no leader file".into()))?;
            let path = dir.join(name);
            let motion = load_leader(&path)?;
            SystemRequest::Duet(DuetOptions::new(motion, path.display().to_string()))
        }
        "group" => SystemRequest::Group(GroupOptions::new(p.dancer_count())),
        "holistic" => SystemRequest::Holistic(Default::default()),
        other => {
            return Err(GenerateError::Invalid(format!(
                "the {other} system is not served"
            )));
        }
    })
}
