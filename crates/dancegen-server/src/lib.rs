//! `dancegen serve`: the web app. An animator drops in a song, picks a system and a few
//! knobs, follows the progress, watches the dance in 3D in time with the music and downloads
//! it.
//!
//! - [`api`]: the HTTP API (axum + tower-http), with every limit as a JSON error.
//! - [`jobs`] / [`store`]: jobs in SQLite in the data dir, files under `jobs/<id>/`; a job
//!   left `running` by a crash or `kill -9` is queued again on the next start.
//! - [`worker`]: a bounded pool of OS threads running jobs through the generation library
//!   (never on the async threads), one [`dancegen_generate::Generator`] keeping models loaded.
//! - [`web`]: the embedded three.js viewer, driven by the song's `<audio>` clock.
//!
//! [`run`] serves until Ctrl-C / SIGTERM; [`spawn`] starts a server on a background thread
//! (tests, embedding).

pub mod api;
pub mod catalog;
pub mod client;
pub mod client_limits;
pub mod config;
pub mod download_all;
pub mod download_names;
pub mod edit_job;
pub mod edit_params;
pub mod error;
pub mod files;
pub mod headers;
pub mod job;
pub mod jobs;
pub mod library;
pub mod owner;
pub mod store;
pub mod thumbnail;
pub mod timeline;
pub mod upload;
pub mod user_words;
pub mod versions;
pub mod web;
pub mod worker;

use std::net::SocketAddr;
use std::sync::{Arc, Mutex};

use dancegen_generate::{Generator, ModelLocator};
use tokio::sync::oneshot;

pub use config::{Limits, ServeConfig};

use crate::api::AppState;
use crate::catalog::Catalog;
use crate::jobs::Jobs;
use crate::worker::Workers;

/// Opens the data dir and starts the workers: everything but the HTTP listener.
fn start_app(config: &ServeConfig) -> Result<(AppState, Workers), String> {
    let jobs = Arc::new(Jobs::open(&config.data_dir)?);
    if let Some(keep) = config.keep {
        expire(&jobs, keep);
    }
    let locator = ModelLocator::from_environment();
    let catalog = Arc::new(Catalog::discover(&locator, &config.models));
    for s in &catalog.systems {
        match &s.model {
            Ok(d) => tracing::info!("{} ({}): model {}", s.name, s.method, d.display()),
            Err(e) => tracing::warn!("{} is not offered: {e}", s.name),
        }
    }
    let generator = Arc::new(Generator::new(locator));
    let models: Vec<_> = catalog
        .systems
        .iter()
        .filter_map(|s| {
            s.model
                .as_ref()
                .ok()
                .map(|d| (s.name.to_string(), d.clone()))
        })
        .collect();
    let workers = Workers::start(config.workers, jobs.clone(), generator, models)?;
    let state = AppState {
        jobs,
        limits: config.limits.clone(),
        catalog,
        submit_lock: Arc::new(Mutex::new(())),
        admin: config.admin.clone(),
        clients: client_limits::ClientLimits::new(
            config.limits.jobs_per_minute,
            config.limits.streams_per_client,
        ),
    };
    Ok((state, workers))
}

/// How often finished jobs are checked against `--keep-days` while the server runs.
const EXPIRY_INTERVAL: std::time::Duration = std::time::Duration::from_secs(24 * 3600);

/// Removes the finished jobs older than `keep` ([`Jobs::expire`]) and says how many went.
fn expire(jobs: &Jobs, keep: std::time::Duration) {
    match jobs.expire(keep) {
        Ok(0) => {}
        Ok(n) => tracing::info!(
            "removed {n} finished job(s) older than {:.0} days",
            keep.as_secs_f64() / 86400.0
        ),
        Err(e) => tracing::warn!("removing old jobs: {e}"),
    }
}

/// Checks for expired jobs every [`EXPIRY_INTERVAL`] (the start has checked already), on a
/// blocking thread: removing a job's files is file-system work. Ends with the runtime.
fn spawn_daily_expiry(jobs: &Arc<Jobs>, keep: Option<std::time::Duration>) {
    let Some(keep) = keep else { return };
    let jobs = jobs.clone();
    tokio::spawn(async move {
        loop {
            tokio::time::sleep(EXPIRY_INTERVAL).await;
            let j = jobs.clone();
            let _ = tokio::task::spawn_blocking(move || expire(&j, keep)).await;
        }
    });
}

async fn bind(addr: SocketAddr) -> Result<tokio::net::TcpListener, String> {
    tokio::net::TcpListener::bind(addr)
        .await
        .map_err(|e| format!("cannot listen on {addr}: {e}"))
}

/// Serves until Ctrl-C or SIGTERM, then lets the running job stop at its next step (it runs
/// again on the next start). `on_ready` hears the bound address.
pub fn run(config: ServeConfig, on_ready: impl FnOnce(SocketAddr)) -> Result<(), String> {
    let rt = tokio::runtime::Builder::new_multi_thread()
        // HTTP only: the generation runs on the worker threads, so two async threads serve
        // hundreds of status requests and streams.
        .worker_threads(2)
        .enable_all()
        .build()
        .map_err(|e| format!("starting the async runtime: {e}"))?;
    let (state, workers) = start_app(&config)?;
    let jobs = state.jobs.clone();
    rt.block_on(async move {
        let listener = bind(config.addr).await?;
        let addr = listener.local_addr().map_err(|e| e.to_string())?;
        on_ready(addr);
        spawn_daily_expiry(&state.jobs, config.keep);
        serve_until(listener, api::router(state), shutdown_signal()).await
    })?;
    workers.stop(&jobs);
    Ok(())
}

/// How long open requests get to finish after a stop signal (SSE streams never finish on
/// their own, so they are then dropped).
const SHUTDOWN_GRACE: std::time::Duration = std::time::Duration::from_secs(2);

/// Serves `router` until `stop` resolves, then for at most [`SHUTDOWN_GRACE`].
async fn serve_until(
    listener: tokio::net::TcpListener,
    router: axum::Router,
    stop: impl std::future::Future<Output = ()> + Send + 'static,
) -> Result<(), String> {
    let stopping = Arc::new(tokio::sync::Notify::new());
    let told = stopping.clone();
    // The peer's address feeds the per-client limits (`client_limits`).
    let app = router.into_make_service_with_connect_info::<std::net::SocketAddr>();
    let server = axum::serve(listener, app).with_graceful_shutdown(async move {
        stop.await;
        told.notify_one();
    });
    tokio::select! {
        r = server => r.map_err(|e| format!("serving: {e}")),
        () = async {
            stopping.notified().await;
            tokio::time::sleep(SHUTDOWN_GRACE).await;
        } => Ok(()),
    }
}

async fn shutdown_signal() {
    let ctrl_c = async {
        let _ = tokio::signal::ctrl_c().await;
    };
    #[cfg(unix)]
    let term = async {
        match tokio::signal::unix::signal(tokio::signal::unix::SignalKind::terminate()) {
            Ok(mut s) => {
                s.recv().await;
            }
            Err(_) => std::future::pending::<()>().await,
        }
    };
    #[cfg(not(unix))]
    let term = std::future::pending::<()>();
    tokio::select! {
        () = ctrl_c => {},
        () = term => {},
    }
    tracing::info!("shutting down");
}

/// A server running on a background thread ([`spawn`]).
pub struct RunningServer {
    pub addr: SocketAddr,
    stop: Option<oneshot::Sender<()>>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl RunningServer {
    /// `http://ADDR`.
    pub fn url(&self) -> String {
        format!("http://{}", self.addr)
    }

    /// Stops serving and the workers (a running job stays queued for the next start).
    pub fn stop(mut self) {
        self.shutdown();
    }

    fn shutdown(&mut self) {
        if let Some(tx) = self.stop.take() {
            let _ = tx.send(());
        }
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

impl Drop for RunningServer {
    fn drop(&mut self) {
        self.shutdown();
    }
}

/// Starts a server on its own thread and returns once it listens (use port 0 for any free
/// port; [`RunningServer::addr`] says which).
pub fn spawn(config: ServeConfig) -> Result<RunningServer, String> {
    let (state, workers) = start_app(&config)?;
    let (ready_tx, ready_rx) = std::sync::mpsc::channel();
    let (stop_tx, stop_rx) = oneshot::channel::<()>();
    let thread = std::thread::Builder::new()
        .name("dancegen-serve".into())
        .spawn(move || {
            let jobs = state.jobs.clone();
            let rt = match tokio::runtime::Builder::new_multi_thread()
                .worker_threads(2)
                .enable_all()
                .build()
            {
                Ok(rt) => rt,
                Err(e) => {
                    let _ = ready_tx.send(Err(format!("starting the async runtime: {e}")));
                    workers.stop(&jobs);
                    return;
                }
            };
            rt.block_on(async move {
                let listener = match bind(config.addr).await {
                    Ok(l) => l,
                    Err(e) => {
                        let _ = ready_tx.send(Err(e));
                        return;
                    }
                };
                let _ = ready_tx.send(listener.local_addr().map_err(|e| e.to_string()));
                spawn_daily_expiry(&state.jobs, config.keep);
                let stop = async {
                    let _ = stop_rx.await;
                };
                if let Err(e) = serve_until(listener, api::router(state), stop).await {
                    tracing::error!("{e}");
                }
            });
            workers.stop(&jobs);
        })
        .map_err(|e| format!("starting the server thread: {e}"))?;
    let addr = ready_rx
        .recv()
        .map_err(|_| "the server thread ended before listening".to_string())??;
    Ok(RunningServer {
        addr,
        stop: Some(stop_tx),
        thread: Some(thread),
    })
}
