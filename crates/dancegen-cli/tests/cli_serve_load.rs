//! Load on `dancegen serve` over loopback, bounded in count and time: 50 songs submitted at
//! once, then 1000 status and SSE requests while the jobs run. Every job must end done, run
//! exactly once and leave its files; none may be lost or duplicated; the server's peak
//! memory must stay under 1.5 GB. Status latency (p50/p99) and the peak are printed
//! (`cargo test -p dancegen-cli --test cli_serve_load -- --nocapture`).

mod common;
#[path = "common/serve.rs"]
mod serve;

use std::collections::HashSet;
use std::path::Path;
use std::sync::Arc;
use std::time::{Duration, Instant};

use serve::ServeProcess;

const SUBMISSIONS: usize = 50;
const STATUS_REQUESTS: usize = 950;
const SSE_REQUESTS: usize = 50;
/// Threads sending the status and SSE requests.
const CLIENTS: usize = 8;
/// The issue's memory ceiling for the server process.
const MAX_PEAK_BYTES: u64 = 1536 << 20;
/// Seconds of the song each job dances: short, so 50 jobs take a couple of minutes on 2 cores.
const JOB_SECONDS: &str = "2.5";
const ALL_JOBS_TIMEOUT: Duration = Duration::from_secs(1500);

fn percentile(sorted: &[f64], p: f64) -> f64 {
    let i = ((sorted.len() as f64 - 1.0) * p).round() as usize;
    sorted[i.min(sorted.len() - 1)]
}

#[test]
fn fifty_jobs_and_a_thousand_status_requests_lose_nothing() {
    let data = tempfile::tempdir().unwrap();
    let server = ServeProcess::start(data.path(), &[]);
    let song = Arc::new(
        std::fs::read(
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/demo_metal_madness_45s.ogg"),
        )
        .unwrap(),
    );

    // 50 submissions at once, each with its own seed.
    let started = Instant::now();
    let submitters: Vec<_> = (0..SUBMISSIONS)
        .map(|k| {
            let (client, song) = (server.client.clone(), song.clone());
            std::thread::spawn(move || {
                let params = format!(r#"{{"seed": {k}, "end": {JOB_SECONDS}}}"#);
                client.submit(&[
                    ("params", None, params.as_bytes()),
                    ("song", Some("demo.ogg"), &song),
                ])
            })
        })
        .collect();
    let mut ids = Vec::new();
    for t in submitters {
        let r = t.join().unwrap().expect("submission");
        assert_eq!(r.status, 202, "{}", r.json);
        ids.push(r.json["id"].as_str().unwrap().to_string());
    }
    let submit_s = started.elapsed().as_secs_f64();
    assert_eq!(
        ids.iter().collect::<HashSet<_>>().len(),
        SUBMISSIONS,
        "duplicate ids"
    );

    // 1000 status / SSE requests spread over the jobs while they run.
    let ids = Arc::new(ids);
    let clients: Vec<_> = (0..CLIENTS)
        .map(|c| {
            let (client, ids) = (server.client.clone(), ids.clone());
            std::thread::spawn(move || {
                let mut latencies = Vec::new();
                let mut k = c;
                while k < STATUS_REQUESTS + SSE_REQUESTS {
                    let id = &ids[k % ids.len()];
                    if k < STATUS_REQUESTS {
                        let t = Instant::now();
                        let r = client.get(&format!("/api/jobs/{id}")).expect("status");
                        latencies.push(t.elapsed().as_secs_f64());
                        assert_eq!(r.status, 200, "{}", r.json);
                        assert_eq!(r.json["id"].as_str(), Some(id.as_str()));
                    } else {
                        // The stream's first event is the job's current object.
                        let ev = client
                            .events(&format!("/api/jobs/{id}/events"), 1, |_| true)
                            .expect("SSE");
                        assert_eq!(ev.len(), 1);
                        assert_eq!(ev[0]["id"].as_str(), Some(id.as_str()));
                    }
                    k += CLIENTS;
                }
                latencies
            })
        })
        .collect();
    let mut latencies: Vec<f64> = clients
        .into_iter()
        .flat_map(|t| t.join().unwrap())
        .collect();
    latencies.sort_by(f64::total_cmp);
    let running_when_done = ids
        .iter()
        .filter(|id| {
            let s = server.client.get(&format!("/api/jobs/{id}")).unwrap().json;
            s["state"] != "done"
        })
        .count();

    // Every job ends done, having run once, with its files.
    for id in ids.iter() {
        let job = server.client.wait(id, ALL_JOBS_TIMEOUT).unwrap();
        assert_eq!(job["state"], "done", "{job}");
        assert_eq!(job["attempts"], 1, "{job}");
        assert!(job["files"]["dance.glb"].is_string(), "{job}");
    }
    let total_s = started.elapsed().as_secs_f64();
    let folders = std::fs::read_dir(data.path().join("jobs"))
        .unwrap()
        .flatten()
        .count();
    assert_eq!(folders, SUBMISSIONS, "job folders on disk");
    let peak = server.peak_rss().expect("the server's /proc status");
    println!(
        "{SUBMISSIONS} submissions in {submit_s:.1} s; {STATUS_REQUESTS} status requests while \
         {running_when_done} jobs were still queued or running: p50 {:.1} ms, p99 {:.1} ms, \
         max {:.1} ms; {SSE_REQUESTS} SSE streams; all {SUBMISSIONS} jobs done in {total_s:.0} s; \
         server peak RSS {:.0} MB",
        percentile(&latencies, 0.5) * 1e3,
        percentile(&latencies, 0.99) * 1e3,
        latencies.last().unwrap() * 1e3,
        peak as f64 / (1 << 20) as f64
    );
    assert!(
        peak < MAX_PEAK_BYTES,
        "server peak memory {} MB over {} MB",
        peak >> 20,
        MAX_PEAK_BYTES >> 20
    );
}
