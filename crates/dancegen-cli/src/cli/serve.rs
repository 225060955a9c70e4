//! `dancegen serve`: the web app's address, data folder, workers, limits and models.

use std::path::PathBuf;

use clap::Args;

#[derive(Args, Debug)]
pub struct ServeArgs {
    /// Address to listen on. Loopback by default: to offer it to others, put a reverse proxy
    /// with TLS and authentication in front (see the README), or give 0.0.0.0:PORT knowingly.
    #[arg(long, default_value = "127.0.0.1:8080")]
    pub addr: std::net::SocketAddr,
    /// Folder for the job database and the jobs' files (default: the platform's data folder,
    /// e.g. ~/.local/share/dancegen/serve).
    #[arg(long, value_name = "DIR")]
    pub data_dir: Option<PathBuf>,
    /// Jobs generated at once (each already uses every core).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u16).range(1..=64))]
    pub workers: u16,
    /// Longest song accepted, seconds.
    #[arg(long, default_value_t = 600.0, value_name = "SECONDS")]
    pub max_song_seconds: f64,
    /// Largest upload, MB.
    #[arg(long, default_value_t = 64, value_name = "MB")]
    pub max_upload_mb: usize,
    /// Jobs waiting or running before new ones are refused (HTTP 429).
    #[arg(long, default_value_t = 100, value_name = "N")]
    pub max_queue: usize,
    /// Jobs one client address may start in any minute (more → HTTP 429 naming the limit).
    /// Behind a reverse proxy every client has the proxy's address: limit there instead.
    #[arg(long, default_value_t = 10, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=100_000))]
    pub max_jobs_per_minute: u32,
    /// Progress streams (a page showing a job) one client address may hold open (more → 429).
    #[arg(long, default_value_t = 16, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=100_000))]
    pub max_streams_per_client: u32,
    /// Most gigabytes the jobs' files may take; when they do, new jobs get HTTP 507 until some
    /// are deleted (nothing is deleted to make room; see --keep-days). Default: no limit.
    #[arg(long, value_name = "GB")]
    pub max_disk_gb: Option<f64>,
    /// Remove finished jobs (done, failed, cancelled) and their files N days after they ended,
    /// when the server starts and once a day while it runs. Default: keep every job until it is
    /// deleted.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=36500))]
    pub keep_days: Option<u32>,
    /// A file holding the administrator's token (one line, at least 16 characters; e.g.
    /// `openssl rand -hex 32 > admin.token`). Sent as `Authorization: Bearer TOKEN`, it gives
    /// every right over every job: list, delete, rename and edit them. Without it, a job can
    /// be changed only with the owner secret its creation returned.
    #[arg(long, value_name = "FILE")]
    pub admin_token_file: Option<PathBuf>,
    /// A model folder to serve instead of the installed default (`--model DIR`, repeatable;
    /// its system comes from its model.toml).
    #[arg(long = "model", value_name = "DIR")]
    pub models: Vec<PathBuf>,
}
