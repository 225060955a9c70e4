//! Limits per client address, so that one user (or one broken script) cannot take a shared
//! server from the others: jobs accepted per minute (`--max-jobs-per-minute`) and progress
//! streams open at once (`--max-streams-per-client`). The address is the TCP peer's: behind a
//! reverse proxy every client is the proxy, so set these there instead (README, "Security").

use std::collections::{HashMap, VecDeque};
use std::net::IpAddr;
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::{Duration, Instant};

use axum::http::StatusCode;

use crate::error::ApiError;

/// Jobs one address may have accepted in any minute, by default: a person makes a dance every
/// few minutes at most; a script submitting a folder should use `dancegen batch` or raise it.
pub const DEFAULT_JOBS_PER_MINUTE: usize = 10;
/// Progress streams (`/events`) one address may hold open at once, by default: a page opens
/// one per job it shows; a browser with a dozen tabs of dances stays under it.
pub const DEFAULT_STREAMS_PER_CLIENT: usize = 16;
/// Addresses remembered before the quiet ones are forgotten (bounds the memory a stream of
/// new addresses can take).
const MAX_TRACKED_ADDRESSES: usize = 10_000;
const MINUTE: Duration = Duration::from_secs(60);

fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

/// The per-address counters.
pub struct ClientLimits {
    jobs_per_minute: usize,
    streams_per_client: usize,
    accepted: Mutex<HashMap<IpAddr, VecDeque<Instant>>>,
    streams: Mutex<HashMap<IpAddr, usize>>,
}

impl ClientLimits {
    pub fn new(jobs_per_minute: usize, streams_per_client: usize) -> Arc<Self> {
        Arc::new(ClientLimits {
            jobs_per_minute,
            streams_per_client,
            accepted: Mutex::new(HashMap::new()),
            streams: Mutex::new(HashMap::new()),
        })
    }

    /// `Err` (429 naming `max-jobs-per-minute`) when `ip` already had its jobs this minute.
    pub fn check_job(&self, ip: IpAddr) -> Result<(), ApiError> {
        let now = Instant::now();
        let mut accepted = lock(&self.accepted);
        let Some(times) = accepted.get_mut(&ip) else {
            return Ok(());
        };
        while times
            .front()
            .is_some_and(|t| now.duration_since(*t) >= MINUTE)
        {
            times.pop_front();
        }
        if times.len() < self.jobs_per_minute {
            return Ok(());
        }
        let wait = times
            .front()
            .map_or(0.0, |t| (MINUTE - now.duration_since(*t)).as_secs_f64());
        Err(ApiError::limit(
            StatusCode::TOO_MANY_REQUESTS,
            "max-jobs-per-minute",
            format!(
                "this address made {} dances in the last minute, the limit \
                 (--max-jobs-per-minute); try again in {:.0} s",
                times.len(),
                wait.ceil()
            ),
        ))
    }

    /// Counts a job accepted from `ip`.
    pub fn count_job(&self, ip: IpAddr) {
        let now = Instant::now();
        let mut accepted = lock(&self.accepted);
        if accepted.len() >= MAX_TRACKED_ADDRESSES {
            accepted.retain(|_, times| {
                times
                    .back()
                    .is_some_and(|t| now.duration_since(*t) < MINUTE)
            });
        }
        let times = accepted.entry(ip).or_default();
        times.push_back(now);
        while times.len() > self.jobs_per_minute {
            times.pop_front();
        }
    }

    /// A stream slot for `ip`, released when the guard is dropped (the stream ends or the client
    /// goes); `Err` (429 naming `max-streams-per-client`) when `ip` holds all of its slots.
    pub fn open_stream(self: &Arc<Self>, ip: IpAddr) -> Result<StreamSlot, ApiError> {
        let mut streams = lock(&self.streams);
        let open = streams.entry(ip).or_insert(0);
        if *open >= self.streams_per_client {
            return Err(ApiError::limit(
                StatusCode::TOO_MANY_REQUESTS,
                "max-streams-per-client",
                format!(
                    "this address has {open} progress streams open, the limit \
                     (--max-streams-per-client); close a page showing a dance, or poll \
                     GET /api/jobs/ID instead"
                ),
            ));
        }
        *open += 1;
        Ok(StreamSlot {
            limits: self.clone(),
            ip,
        })
    }

    /// Streams `ip` holds open now.
    pub fn open_streams(&self, ip: IpAddr) -> usize {
        lock(&self.streams).get(&ip).copied().unwrap_or(0)
    }
}

/// One open progress stream of an address ([`ClientLimits::open_stream`]).
pub struct StreamSlot {
    limits: Arc<ClientLimits>,
    ip: IpAddr,
}

impl Drop for StreamSlot {
    fn drop(&mut self) {
        let mut streams = lock(&self.limits.streams);
        if let Some(open) = streams.get_mut(&self.ip) {
            *open = open.saturating_sub(1);
            if *open == 0 {
                streams.remove(&self.ip);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const A: IpAddr = IpAddr::V4(std::net::Ipv4Addr::new(10, 0, 0, 1));
    const B: IpAddr = IpAddr::V4(std::net::Ipv4Addr::new(10, 0, 0, 2));

    #[test]
    fn jobs_per_minute_are_counted_per_address() {
        let l = ClientLimits::new(2, 1);
        for _ in 0..2 {
            l.check_job(A).unwrap();
            l.count_job(A);
        }
        let e = l.check_job(A).unwrap_err();
        assert_eq!(e.status, StatusCode::TOO_MANY_REQUESTS);
        assert_eq!(e.limit.as_deref(), Some("max-jobs-per-minute"));
        assert!(e.message.contains("try again in"), "{}", e.message);
        l.check_job(B).unwrap();
    }

    #[test]
    fn stream_slots_come_back_when_dropped() {
        let l = ClientLimits::new(1, 2);
        let s1 = l.open_stream(A).unwrap();
        let _s2 = l.open_stream(A).unwrap();
        let e = l.open_stream(A).err().unwrap();
        assert_eq!(e.limit.as_deref(), Some("max-streams-per-client"));
        let _b = l.open_stream(B).unwrap();
        drop(s1);
        assert_eq!(l.open_streams(A), 1);
        let _s3 = l.open_stream(A).unwrap();
    }
}
