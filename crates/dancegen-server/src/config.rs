//! What a server is started with: where it listens and keeps its jobs, how many jobs run at
//! once, and the limits that keep one user or a broken client from taking the machine.

use std::net::SocketAddr;
use std::path::PathBuf;
use std::time::Duration;

/// Largest upload (song + leader + params) in bytes, the 64 MB: a 10-minute song fits
/// compressed (OGG/MP3, ~10 MB) or as a mono 16-bit 22.05 kHz WAV (26 MB), not as a
/// CD-quality stereo WAV (106 MB).
pub const DEFAULT_UPLOAD_BYTES: usize = 64 << 20;
/// Longest song accepted, seconds (10 minutes).
pub const DEFAULT_SONG_SECONDS: f64 = 600.0;
/// Jobs waiting or running before new submissions get 429.
pub const DEFAULT_QUEUE_LENGTH: usize = 100;
/// Time a client has to send a whole request body (a slow-trickling upload is cut off).
pub const DEFAULT_BODY_DEADLINE: Duration = Duration::from_secs(60);
/// Time to the response headers of any request (SSE streams only need their headers in time).
pub const DEFAULT_REQUEST_TIMEOUT: Duration = Duration::from_secs(30);
/// Variations of one job (each a full dance with its own seed).
pub const MAX_VARIATIONS: usize = 8;
/// Interval between SSE keep-alive comments (proxies close idle streams after ~60 s).
pub const SSE_KEEP_ALIVE: Duration = Duration::from_secs(15);

/// Limits applied to every request and job; each produces its own JSON error.
#[derive(Clone, Debug)]
pub struct Limits {
    pub upload_bytes: usize,
    pub song_seconds: f64,
    pub queue_length: usize,
    pub body_deadline: Duration,
    pub request_timeout: Duration,
    pub max_variations: usize,
    /// Jobs one client address may have accepted in any minute.
    pub jobs_per_minute: usize,
    /// Progress streams one client address may hold open.
    pub streams_per_client: usize,
    /// Most bytes the job folders may hold before new jobs are refused (507); `None`: no
    /// limit. Nothing is deleted to make room (`--keep-days` removes old jobs).
    pub disk_bytes: Option<u64>,
}

impl Default for Limits {
    fn default() -> Self {
        Limits {
            upload_bytes: DEFAULT_UPLOAD_BYTES,
            song_seconds: DEFAULT_SONG_SECONDS,
            queue_length: DEFAULT_QUEUE_LENGTH,
            body_deadline: DEFAULT_BODY_DEADLINE,
            request_timeout: DEFAULT_REQUEST_TIMEOUT,
            max_variations: MAX_VARIATIONS,
            jobs_per_minute: crate::client_limits::DEFAULT_JOBS_PER_MINUTE,
            streams_per_client: crate::client_limits::DEFAULT_STREAMS_PER_CLIENT,
            disk_bytes: None,
        }
    }
}

/// A server's settings (`dancegen serve` flags).
#[derive(Clone, Debug)]
pub struct ServeConfig {
    /// Where to listen; loopback unless the user asks otherwise (put a reverse proxy with TLS
    /// and authentication in front to expose it; see the README).
    pub addr: SocketAddr,
    /// Holds `jobs.sqlite3` and `jobs/<id>/`.
    pub data_dir: PathBuf,
    /// Jobs generated at once (each uses every core through the tensor kernels, so one is
    /// right for a laptop).
    pub workers: usize,
    pub limits: Limits,
    /// A model folder per system name, overriding the search path (tests, custom models).
    pub models: Vec<(String, PathBuf)>,
    /// How long a finished job (done, failed, cancelled) is kept after it ended: older ones
    /// are removed with their files when the server starts and once a day while it runs
    /// (`--keep-days`). `None` keeps every job until it is deleted.
    pub keep: Option<Duration>,
    /// The administrator's token (`--admin-token-file`): every right over every job.
    pub admin: crate::owner::AdminKey,
}

impl ServeConfig {
    pub fn new(data_dir: impl Into<PathBuf>) -> Self {
        ServeConfig {
            addr: SocketAddr::from(([127, 0, 0, 1], 8080)),
            data_dir: data_dir.into(),
            workers: 1,
            limits: Limits::default(),
            models: Vec::new(),
            keep: None,
            admin: crate::owner::AdminKey::none(),
        }
    }
}
