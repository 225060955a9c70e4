//! The jobs service shared by the HTTP handlers and the workers: the SQLite store, each job's
//! latest [`JobView`] in a `watch` channel (status requests and SSE streams read it; a
//! reconnecting client gets the current state at once), the cancel tokens of running jobs and
//! the signal that wakes idle workers.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{Condvar, Mutex, MutexGuard};
use std::time::Duration;

use dancegen_generate::CancelToken;
use tokio::sync::watch;

use crate::download_names::download_name;
use crate::error::ApiError;
use crate::files;
use crate::job::{
    FACE_FORMATS, JobState, JobView, LEADER_NPY, MOTION_FORMATS, VariationView, variation_stem,
};
use crate::store::{JobRow, Store};

pub struct Jobs {
    pub store: Store,
    data_dir: PathBuf,
    live: Mutex<HashMap<String, watch::Sender<JobView>>>,
    cancels: Mutex<HashMap<String, CancelToken>>,
    /// Bumped on every submission; idle workers wait for it to change.
    work: (Mutex<u64>, Condvar),
}

fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

impl Jobs {
    /// Opens the store in `data_dir` (creating both), requeues jobs a dead process left
    /// running and clears their half-written staging files.
    pub fn open(data_dir: &Path) -> Result<Self, String> {
        let jobs = files::jobs_dir(data_dir);
        std::fs::create_dir_all(&jobs)
            .map_err(|e| format!("cannot create the data folder {}: {e}", jobs.display()))?;
        let db = data_dir.join("jobs.sqlite3");
        let (store, requeued) =
            Store::open(&db).map_err(|e| format!("job database {}: {e}", db.display()))?;
        for id in &requeued {
            tracing::info!("job {id} was running when the server stopped: queued again");
            files::clean_staging(&jobs.join(id));
        }
        // Submissions that never reached the database (a crash mid-upload).
        if let Ok(entries) = std::fs::read_dir(&jobs) {
            for e in entries.flatten() {
                if e.file_name().to_string_lossy().starts_with(".incoming-") {
                    let _ = std::fs::remove_dir_all(e.path());
                }
            }
        }
        Ok(Jobs {
            store,
            data_dir: data_dir.to_path_buf(),
            live: Mutex::new(HashMap::new()),
            cancels: Mutex::new(HashMap::new()),
            work: (Mutex::new(0), Condvar::new()),
        })
    }

    pub fn data_dir(&self) -> &Path {
        &self.data_dir
    }

    pub fn job_dir(&self, id: &str) -> PathBuf {
        files::jobs_dir(&self.data_dir).join(id)
    }

    /// A new job id: the clock (so ids read in order of creation) and 64 random bits, 32 hex
    /// digits. The id is all one needs to read a job and its files, so it must not be guessed
    /// from another id or from the time: the random half makes that a 1 in 2^64 chance per try.
    /// Checked against the store and the job folders.
    pub fn new_id(&self) -> Result<String, ApiError> {
        loop {
            let nanos = std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map(|d| d.as_nanos() as u64)
                .unwrap_or(0);
            let mut random = [0u8; 8];
            getrandom::fill(&mut random).map_err(|e| {
                ApiError::internal(format!("the system's random source failed: {e}"))
            })?;
            let id = format!("{nanos:016x}{:016x}", u64::from_le_bytes(random));
            if !self.job_dir(&id).exists() && !matches!(self.store.get(&id), Ok(Some(_))) {
                return Ok(id);
            }
        }
    }

    /// The job object of `row` (its files listed from disk).
    fn view_of(&self, row: &JobRow) -> JobView {
        let dir = self.job_dir(&row.id);
        let files = files::urls(&row.id, &dir);
        let mut variations = Vec::with_capacity(row.params.variations);
        for k in 0..row.params.variations {
            let stem = variation_stem(k);
            let mut by_kind = std::collections::BTreeMap::new();
            for ext in MOTION_FORMATS.iter().chain(&FACE_FORMATS).chain(&["mp4"]) {
                let name = format!("{stem}.{ext}");
                if let Some(u) = files.get(&name) {
                    by_kind.insert(ext.to_string(), u.clone());
                }
            }
            // A group's single-dancer formats come one file per dancer (`dance_0.bvh`, …).
            for ext in ["bvh", "npz"] {
                for d in 0..row.params.dancer_count() {
                    if let Some(u) = files.get(&format!("{stem}_{d}.{ext}")) {
                        by_kind.insert(format!("{ext}_{d}"), u.clone());
                    }
                }
            }
            if let Some(u) = files.get(LEADER_NPY) {
                by_kind.insert("leader_npy".into(), u.clone());
            }
            let seed = row.params.seed_of(k);
            let title = row.params.song_title.as_deref().unwrap_or("song");
            let names = by_kind
                .keys()
                .map(|kind| {
                    let name = download_name(title, &row.params.system, seed, kind);
                    (kind.clone(), name)
                })
                .collect();
            variations.push(VariationView {
                seed,
                files: by_kind,
                names,
            });
        }
        JobView {
            id: row.id.clone(),
            state: row.state,
            stage: row.stage.clone(),
            progress: row.progress,
            eta_s: row.eta_s,
            error: row.error.clone(),
            warnings: row.warnings.clone(),
            song: files.get(&row.song).cloned(),
            name: row.name.clone(),
            thumbnail: files.get(crate::thumbnail::THUMBNAIL).cloned(),
            timeline: files.get(crate::timeline::TIMELINE).cloned(),
            files,
            system: row.params.system.clone(),
            dancers: row.params.dancer_count(),
            params: row.params.clone(),
            variations,
            created: row.created,
            finished: row.finished,
            attempts: row.attempts,
            queue_position: match row.state {
                JobState::Queued => self.store.queue_position(&row.id).ok().flatten(),
                _ => None,
            },
        }
    }

    /// The library: the newest `limit` jobs' objects, newest first; every job's for `None`
    /// (the administrator), the owner key's otherwise.
    pub fn library(&self, limit: usize, owner: Option<&str>) -> Result<Vec<JobView>, ApiError> {
        Ok(self
            .store
            .newest(limit, owner)?
            .iter()
            .map(|row| self.view_of(row))
            .collect())
    }

    /// The job's current object, `None` when there is no such job.
    pub fn view(&self, id: &str) -> Result<Option<JobView>, ApiError> {
        if !files::valid_id(id) {
            return Ok(None);
        }
        if let Some(tx) = lock(&self.live).get(id) {
            return Ok(Some(tx.borrow().clone()));
        }
        Ok(self.store.get(id)?.map(|r| self.view_of(&r)))
    }

    /// A receiver of the job's objects (the current one first), `None` when there is no job.
    pub fn subscribe(&self, id: &str) -> Result<Option<watch::Receiver<JobView>>, ApiError> {
        if !files::valid_id(id) {
            return Ok(None);
        }
        let mut live = lock(&self.live);
        if let Some(tx) = live.get(id) {
            return Ok(Some(tx.subscribe()));
        }
        let Some(row) = self.store.get(id)? else {
            return Ok(None);
        };
        let (tx, rx) = watch::channel(self.view_of(&row));
        live.insert(id.to_string(), tx);
        Ok(Some(rx))
    }

    /// Re-reads the job from the store and tells every listener (after a state change).
    pub fn publish(&self, id: &str) {
        let row = match self.store.get(id) {
            Ok(Some(r)) => r,
            Ok(None) => {
                lock(&self.live).remove(id);
                return;
            }
            Err(e) => {
                tracing::error!("job {id}: reading its state: {e}");
                return;
            }
        };
        let mut view = self.view_of(&row);
        let finished = view.state.is_final();
        let mut live = lock(&self.live);
        if let Some(tx) = live.get(id) {
            let old = tx.borrow();
            // The store's progress of a running job lags the live one: never step back.
            if view.state == JobState::Running
                && old.state == JobState::Running
                && old.progress > view.progress
            {
                view.progress = old.progress;
                view.stage.clone_from(&old.stage);
                view.eta_s = old.eta_s;
            }
        }
        match live.get(id) {
            // A finished job nobody listens to is read from the store from now on, so the
            // map holds only jobs in flight and the streams open on finished ones.
            Some(tx) if finished && tx.receiver_count() == 0 => {
                live.remove(id);
            }
            Some(tx) => {
                tx.send_replace(view);
            }
            None if finished => {}
            None => {
                live.insert(id.to_string(), watch::channel(view).0);
            }
        }
    }

    /// Shows listeners and status requests that job `id` ended (`state`, `error`) before the
    /// store has it (the store could not be written; [`crate::worker`] retries).
    pub fn show_end(&self, id: &str, state: JobState, error: Option<&str>) {
        let Ok(Some(row)) = self.store.get(id) else {
            return;
        };
        let mut view = self.view_of(&row);
        view.state = state;
        view.error = error.map(str::to_string);
        view.eta_s = None;
        let mut live = lock(&self.live);
        match live.get(id) {
            Some(tx) => {
                tx.send_replace(view);
            }
            None => {
                live.insert(id.to_string(), watch::channel(view).0);
            }
        }
    }

    /// Re-publishes every queued job (their places in the queue moved up).
    pub fn publish_queue(&self) {
        match self.store.ids_in(JobState::Queued) {
            Ok(ids) => ids.iter().for_each(|id| self.publish(id)),
            Err(e) => tracing::error!("job database: {e}"),
        }
    }

    /// Tells listeners of a running job's progress without touching the disk.
    pub fn publish_progress(&self, id: &str, stage: &str, progress: f64, eta_s: Option<f64>) {
        if let Some(tx) = lock(&self.live).get(id) {
            tx.send_if_modified(|v| {
                let changed =
                    v.stage.as_deref() != Some(stage) || v.progress != progress || v.eta_s != eta_s;
                v.stage = Some(stage.to_string());
                v.progress = progress;
                v.eta_s = eta_s;
                changed
            });
        }
    }

    /// Wakes a worker: a job was queued.
    pub fn notify_work(&self) {
        let (m, cv) = &self.work;
        *lock(m) += 1;
        cv.notify_all();
    }

    /// Waits until a job may have been queued (or `timeout`).
    pub fn wait_for_work(&self, seen: u64, timeout: Duration) -> u64 {
        let (m, cv) = &self.work;
        let g = lock(m);
        let (g, _) = cv
            .wait_timeout_while(g, timeout, |n| *n == seen)
            .unwrap_or_else(|e| e.into_inner());
        *g
    }

    pub fn work_counter(&self) -> u64 {
        *lock(&self.work.0)
    }

    /// The cancel token of job `id` (made on first use by either the worker or a DELETE, so a
    /// cancel that arrives as the job starts is not lost).
    pub fn cancel_token(&self, id: &str) -> CancelToken {
        lock(&self.cancels)
            .entry(id.to_string())
            .or_default()
            .clone()
    }

    /// Stops every running job at its next step (server shutdown).
    pub fn cancel_all(&self) {
        for t in lock(&self.cancels).values() {
            t.cancel();
        }
    }

    pub fn forget_cancel_token(&self, id: &str) {
        lock(&self.cancels).remove(id);
    }

    /// Removes, with their files, the finished jobs that ended more than `keep` ago
    /// (`serve --keep-days`); queued and running jobs stay whatever their age. Returns how
    /// many went.
    pub fn expire(&self, keep: Duration) -> Result<usize, ApiError> {
        let cutoff = crate::store::now() - keep.as_secs_f64();
        let mut removed = 0;
        for id in self.store.finished_before(cutoff)? {
            if let Some(None) = self.cancel_or_remove(&id)? {
                removed += 1;
            }
        }
        Ok(removed)
    }

    /// `DELETE /api/jobs/{id}`: a queued job is cancelled at once, a running one is asked to
    /// stop (it becomes `cancelled` at its next step), a finished one is removed with its
    /// files. `Ok(None)`: no such job; `Ok(Some(None))`: removed.
    pub fn cancel_or_remove(&self, id: &str) -> Result<Option<Option<JobView>>, ApiError> {
        if !files::valid_id(id) {
            return Ok(None);
        }
        let Some(row) = self.store.get(id)? else {
            return Ok(None);
        };
        match row.state {
            JobState::Queued | JobState::Running => {
                if !self.store.cancel_queued(id)? {
                    // Running (or claimed just now): its worker stops at the next step.
                    self.cancel_token(id).cancel();
                }
                self.publish(id);
                Ok(Some(self.view(id)?))
            }
            _ => {
                self.store.delete(id)?;
                lock(&self.live).remove(id);
                let dir = self.job_dir(id);
                if let Err(e) = std::fs::remove_dir_all(&dir)
                    && e.kind() != std::io::ErrorKind::NotFound
                {
                    tracing::warn!("job {id}: removing {}: {e}", dir.display());
                }
                Ok(Some(None))
            }
        }
    }
}
