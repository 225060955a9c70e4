//! The job table, in an embedded SQLite database (`DATA_DIR/jobs.sqlite3`, WAL): every job's
//! parameters and state survive a crash, a `kill -9` or a restart. A job's files live next to
//! it under `DATA_DIR/jobs/<id>/` ([`crate::files`]).
//!
//! One connection behind a mutex: every statement is a single-row read or write that takes
//! microseconds, far below the time of a generation job, so a pool would buy nothing.

use std::path::Path;
use std::sync::{Mutex, MutexGuard};

use rusqlite::{Connection, OptionalExtension, params};

use crate::job::{JobParams, JobState};

/// A job's row.
#[derive(Clone, Debug)]
pub struct JobRow {
    pub id: String,
    pub state: JobState,
    pub stage: Option<String>,
    pub progress: f64,
    pub eta_s: Option<f64>,
    pub error: Option<String>,
    pub params: JobParams,
    /// The uploaded song's file name in the job folder.
    pub song: String,
    /// The uploaded leader's file name (duets).
    pub leader: Option<String>,
    pub created: f64,
    pub finished: Option<f64>,
    /// Times a worker has started it (1 for a job that ran once; more after restarts).
    pub attempts: u32,
    /// What the user should know about the finished dance (a song without a beat).
    pub warnings: Vec<String>,
    /// The name the user gave the dance in the library (`None`: the song's).
    pub name: Option<String>,
    /// SHA-256 of the owner secret the job was made with ([`crate::owner`]); `None` for jobs
    /// the administrator made and jobs from before owners.
    pub owner: Option<String>,
}

pub struct Store {
    conn: Mutex<Connection>,
}

/// Seconds since the Unix epoch.
pub fn now() -> f64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs_f64())
        .unwrap_or(0.0)
}

const SCHEMA: &str = "
CREATE TABLE IF NOT EXISTS jobs (
    seq      INTEGER PRIMARY KEY AUTOINCREMENT,
    id       TEXT NOT NULL UNIQUE,
    state    TEXT NOT NULL,
    stage    TEXT,
    progress REAL NOT NULL DEFAULT 0,
    eta_s    REAL,
    error    TEXT,
    params   TEXT NOT NULL,
    song     TEXT NOT NULL,
    leader   TEXT,
    created  REAL NOT NULL,
    started  REAL,
    finished REAL,
    attempts INTEGER NOT NULL DEFAULT 0
);
CREATE INDEX IF NOT EXISTS jobs_state ON jobs(state, seq);
";

const COLUMNS: &str = "id, state, stage, progress, eta_s, error, params, song, leader, created, \
     finished, attempts, warnings, name, owner";

/// Columns added after the first release, with their types: a database an older server made
/// gets them when it is opened (`ALTER TABLE ... ADD COLUMN`; old rows read them as NULL).
/// `owner` is the owner key ([`crate::owner`]); jobs an older server made have none, and only
/// the administrator may change or list them.
const ADDED_COLUMNS: [(&str, &str); 3] =
    [("warnings", "TEXT"), ("name", "TEXT"), ("owner", "TEXT")];

fn row_of(r: &rusqlite::Row<'_>) -> rusqlite::Result<JobRow> {
    let state: String = r.get(1)?;
    let params: String = r.get(6)?;
    let bad = |what: String| {
        rusqlite::Error::FromSqlConversionFailure(0, rusqlite::types::Type::Text, what.into())
    };
    Ok(JobRow {
        id: r.get(0)?,
        state: JobState::parse(&state).ok_or_else(|| bad(format!("unknown state {state}")))?,
        stage: r.get(2)?,
        progress: r.get(3)?,
        eta_s: r.get(4)?,
        error: r.get(5)?,
        params: serde_json::from_str(&params).map_err(|e| bad(format!("params: {e}")))?,
        song: r.get(7)?,
        leader: r.get(8)?,
        created: r.get(9)?,
        finished: r.get(10)?,
        attempts: r.get(11)?,
        warnings: match r.get::<_, Option<String>>(12)? {
            None => Vec::new(),
            Some(text) => serde_json::from_str(&text).map_err(|e| bad(format!("warnings: {e}")))?,
        },
        name: r.get(13)?,
        owner: r.get(14)?,
    })
}

impl Store {
    /// Opens (creating) the database at `path` and puts every job a previous process left
    /// `running` back in the queue: it died with them, and their outputs were never renamed
    /// into place, so they simply run again.
    pub fn open(path: &Path) -> rusqlite::Result<(Self, Vec<String>)> {
        let conn = Connection::open(path)?;
        conn.pragma_update(None, "journal_mode", "WAL")?;
        // WAL + NORMAL: a committed job survives a process crash; only an OS crash may lose the
        // last transactions (which then run again).
        conn.pragma_update(None, "synchronous", "NORMAL")?;
        conn.busy_timeout(std::time::Duration::from_secs(5))?;
        conn.execute_batch(SCHEMA)?;
        for (name, kind) in ADDED_COLUMNS {
            let has: bool = conn.query_row(
                "SELECT count(*) > 0 FROM pragma_table_info('jobs') WHERE name = ?1",
                [name],
                |r| r.get(0),
            )?;
            if !has {
                conn.execute_batch(&format!("ALTER TABLE jobs ADD COLUMN {name} {kind}"))?;
            }
        }
        let requeued: Vec<String> = {
            let mut st = conn.prepare(
                "UPDATE jobs SET state = 'queued', stage = NULL, progress = 0, eta_s = NULL
                 WHERE state = 'running' RETURNING id",
            )?;
            st.query_map([], |r| r.get(0))?
                .collect::<rusqlite::Result<_>>()?
        };
        Ok((
            Store {
                conn: Mutex::new(conn),
            },
            requeued,
        ))
    }

    fn conn(&self) -> MutexGuard<'_, Connection> {
        self.conn.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Adds a queued job (its files are already in place), owned by the owner key `owner`.
    pub fn insert(
        &self,
        id: &str,
        params: &JobParams,
        song: &str,
        leader: Option<&str>,
        owner: Option<&str>,
    ) -> rusqlite::Result<()> {
        let params = serde_json::to_string(params).expect("params serialise");
        self.conn().execute(
            "INSERT INTO jobs (id, state, params, song, leader, created, owner)
             VALUES (?1, 'queued', ?2, ?3, ?4, ?5, ?6)",
            params![id, params, song, leader, now(), owner],
        )?;
        Ok(())
    }

    pub fn get(&self, id: &str) -> rusqlite::Result<Option<JobRow>> {
        self.conn()
            .query_row(
                &format!("SELECT {COLUMNS} FROM jobs WHERE id = ?1"),
                [id],
                row_of,
            )
            .optional()
    }

    /// The jobs that edit job `id` (`params.edit.of`), oldest first.
    pub fn edits_of(&self, id: &str) -> rusqlite::Result<Vec<JobRow>> {
        let conn = self.conn();
        let mut st = conn.prepare(&format!(
            "SELECT {COLUMNS} FROM jobs WHERE json_extract(params, '$.edit.of') = ?1 ORDER BY seq"
        ))?;
        st.query_map([id], row_of)?.collect()
    }

    /// Jobs queued or running (the queue-length limit counts these).
    pub fn active_count(&self) -> rusqlite::Result<usize> {
        self.conn().query_row(
            "SELECT COUNT(*) FROM jobs WHERE state IN ('queued', 'running')",
            [],
            |r| r.get::<_, i64>(0).map(|n| n as usize),
        )
    }

    /// Ids of the jobs in `state`, oldest first.
    pub fn ids_in(&self, state: JobState) -> rusqlite::Result<Vec<String>> {
        let conn = self.conn();
        let mut st = conn.prepare("SELECT id FROM jobs WHERE state = ?1 ORDER BY seq")?;
        st.query_map([state.as_str()], |r| r.get(0))?.collect()
    }

    /// Takes the oldest queued job for a worker (atomically: two workers never get the same).
    pub fn claim(&self) -> rusqlite::Result<Option<JobRow>> {
        let conn = self.conn();
        let id: Option<String> = conn
            .query_row(
                "UPDATE jobs SET state = 'running', started = ?1, attempts = attempts + 1,
                     stage = NULL, progress = 0, eta_s = NULL, error = NULL
                 WHERE seq = (SELECT seq FROM jobs WHERE state = 'queued' ORDER BY seq LIMIT 1)
                 RETURNING id",
                [now()],
                |r| r.get(0),
            )
            .optional()?;
        match id {
            None => Ok(None),
            Some(id) => conn
                .query_row(
                    &format!("SELECT {COLUMNS} FROM jobs WHERE id = ?1"),
                    [&id],
                    row_of,
                )
                .optional(),
        }
    }

    /// Records a running job's progress.
    pub fn progress(
        &self,
        id: &str,
        stage: &str,
        progress: f64,
        eta_s: Option<f64>,
    ) -> rusqlite::Result<()> {
        self.conn().execute(
            "UPDATE jobs SET stage = ?2, progress = ?3, eta_s = ?4
             WHERE id = ?1 AND state = 'running'",
            params![id, stage, progress, eta_s],
        )?;
        Ok(())
    }

    /// Ends a running job in `state` (done, failed or cancelled).
    pub fn finish(
        &self,
        id: &str,
        state: JobState,
        error: Option<&str>,
        warnings: &[String],
    ) -> rusqlite::Result<()> {
        let done = state == JobState::Done;
        let warnings = (!warnings.is_empty())
            .then(|| serde_json::to_string(warnings).expect("strings serialise"));
        self.conn().execute(
            "UPDATE jobs SET state = ?2, error = ?3, finished = ?4, eta_s = NULL,
                 progress = CASE WHEN ?5 THEN 1.0 ELSE progress END,
                 stage = CASE WHEN ?5 THEN 'done' ELSE stage END,
                 warnings = ?6
             WHERE id = ?1",
            params![id, state.as_str(), error, now(), done, warnings],
        )?;
        Ok(())
    }

    /// Cancels `id` if it is still queued; `true` when it was.
    pub fn cancel_queued(&self, id: &str) -> rusqlite::Result<bool> {
        let n = self.conn().execute(
            "UPDATE jobs SET state = 'cancelled', finished = ?2 WHERE id = ?1 AND state = 'queued'",
            params![id, now()],
        )?;
        Ok(n == 1)
    }

    /// Removes a job's row; `true` when there was one.
    pub fn delete(&self, id: &str) -> rusqlite::Result<bool> {
        Ok(self
            .conn()
            .execute("DELETE FROM jobs WHERE id = ?1", [id])?
            == 1)
    }

    /// The newest `limit` jobs, newest first (the library): every job for `None` (the
    /// administrator), those of the owner key `Some(key)` otherwise.
    pub fn newest(&self, limit: usize, owner: Option<&str>) -> rusqlite::Result<Vec<JobRow>> {
        let conn = self.conn();
        match owner {
            None => {
                let mut st = conn.prepare(&format!(
                    "SELECT {COLUMNS} FROM jobs ORDER BY seq DESC LIMIT ?1"
                ))?;
                st.query_map([limit as i64], row_of)?.collect()
            }
            Some(key) => {
                let mut st = conn.prepare(&format!(
                    "SELECT {COLUMNS} FROM jobs WHERE owner = ?2 ORDER BY seq DESC LIMIT ?1"
                ))?;
                st.query_map(params![limit as i64, key], row_of)?.collect()
            }
        }
    }

    /// Gives job `id` the library name `name` (`None` clears it); `true` when there is a job.
    pub fn rename(&self, id: &str, name: Option<&str>) -> rusqlite::Result<bool> {
        Ok(self
            .conn()
            .execute("UPDATE jobs SET name = ?2 WHERE id = ?1", params![id, name])?
            == 1)
    }

    /// Finished jobs (done, failed, cancelled) that ended before `cutoff` (seconds since the
    /// epoch; a job without an end time counts from its creation), oldest first.
    pub fn finished_before(&self, cutoff: f64) -> rusqlite::Result<Vec<String>> {
        let conn = self.conn();
        let mut st = conn.prepare(
            "SELECT id FROM jobs WHERE state IN ('done', 'failed', 'cancelled')
                 AND COALESCE(finished, created) < ?1 ORDER BY seq",
        )?;
        st.query_map([cutoff], |r| r.get(0))?.collect()
    }

    /// Queued jobs before `id` (its place in the queue, 0 = next).
    pub fn queue_position(&self, id: &str) -> rusqlite::Result<Option<usize>> {
        self.conn()
            .query_row(
                "SELECT COUNT(*) FROM jobs WHERE state = 'queued'
                     AND seq < (SELECT seq FROM jobs WHERE id = ?1 AND state = 'queued')",
                [id],
                |r| r.get::<_, Option<i64>>(0),
            )
            .map(|n| n.map(|n| n as usize))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params() -> JobParams {
        JobParams::parse("", 4).unwrap()
    }

    #[test]
    fn claim_takes_the_oldest_once_and_a_reopen_requeues_running_jobs() {
        let dir = tempfile::tempdir().unwrap();
        let db = dir.path().join("jobs.sqlite3");
        {
            let (s, requeued) = Store::open(&db).unwrap();
            assert!(requeued.is_empty());
            s.insert("a", &params(), "song.ogg", None, None).unwrap();
            s.insert("b", &params(), "song.ogg", None, None).unwrap();
            assert_eq!(s.active_count().unwrap(), 2);
            assert_eq!(s.claim().unwrap().unwrap().id, "a");
            assert_eq!(s.queue_position("b").unwrap(), Some(0));
            assert!(s.cancel_queued("b").unwrap());
            assert!(s.claim().unwrap().is_none());
            // "a" is left running, as a killed process leaves it.
        }
        let (s, requeued) = Store::open(&db).unwrap();
        assert_eq!(requeued, vec!["a".to_string()]);
        let a = s.get("a").unwrap().unwrap();
        assert_eq!(a.state, JobState::Queued);
        assert_eq!(s.get("b").unwrap().unwrap().state, JobState::Cancelled);
        assert_eq!(s.claim().unwrap().unwrap().id, "a");
        s.finish("a", JobState::Done, None, &[]).unwrap();
        let a = s.get("a").unwrap().unwrap();
        assert_eq!((a.state, a.progress), (JobState::Done, 1.0));
        assert!(s.delete("a").unwrap());
        assert!(s.get("a").unwrap().is_none());
    }

    /// Only finished jobs count for expiry, by their end (or, without one, their creation).
    #[test]
    fn finished_before_lists_only_finished_jobs_that_ended_before() {
        let dir = tempfile::tempdir().unwrap();
        let (s, _) = Store::open(&dir.path().join("jobs.sqlite3")).unwrap();
        for id in ["q", "r", "d", "f"] {
            s.insert(id, &params(), "song.ogg", None, None).unwrap();
        }
        for (id, state) in [("q", None), ("r", None), ("d", Some(JobState::Done))] {
            let claimed = s.claim().unwrap().unwrap();
            assert_eq!(claimed.id, id);
            if let Some(state) = state {
                s.finish(id, state, None, &[]).unwrap();
            }
        }
        s.cancel_queued("f").unwrap();
        // "q" and "r" are running, "d" done and "f" cancelled, all just now.
        let later = now() + 10.0;
        assert_eq!(s.finished_before(later).unwrap(), ["d", "f"]);
        assert!(s.finished_before(now() - 10.0).unwrap().is_empty());
        s.conn()
            .execute("UPDATE jobs SET finished = NULL WHERE id = 'd'", [])
            .unwrap();
        assert_eq!(s.finished_before(later).unwrap(), ["d", "f"], "by creation");
    }

    /// A database an older server made (no `warnings` or `owner` column) opens, its jobs read
    /// with no warnings and no owner, the library filters by owner, and a job finished now
    /// keeps its warnings across a reopen.
    #[test]
    fn an_older_database_gets_the_warnings_column() {
        let dir = tempfile::tempdir().unwrap();
        let db = dir.path().join("jobs.sqlite3");
        {
            let conn = Connection::open(&db).unwrap();
            conn.execute_batch(SCHEMA).unwrap();
            conn.execute(
                "INSERT INTO jobs (id, state, params, song, created) VALUES ('old', 'done', ?1, \
                 'song.ogg', 0)",
                [serde_json::to_string(&params()).unwrap()],
            )
            .unwrap();
        }
        let (s, _) = Store::open(&db).unwrap();
        assert!(s.get("old").unwrap().unwrap().warnings.is_empty());
        // A job from before owners has none: only the administrator lists it.
        assert_eq!(s.get("old").unwrap().unwrap().owner, None);
        s.insert("new", &params(), "song.ogg", None, Some("key-a"))
            .unwrap();
        s.insert("other", &params(), "song.ogg", None, Some("key-b"))
            .unwrap();
        let listed = |owner| -> Vec<String> {
            s.newest(10, owner)
                .unwrap()
                .into_iter()
                .map(|r| r.id)
                .collect()
        };
        assert_eq!(listed(Some("key-a")), ["new"]);
        assert_eq!(listed(None), ["other", "new", "old"]);
        assert!(listed(Some("nobody")).is_empty());
        s.claim().unwrap();
        let said = vec!["no beat was found".to_string()];
        s.finish("new", JobState::Done, None, &said).unwrap();
        drop(s);
        let (s, _) = Store::open(&db).unwrap();
        assert_eq!(s.get("new").unwrap().unwrap().warnings, said);
    }
}
