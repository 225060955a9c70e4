//! `dancegen serve` as users run it, as a separate process:
//! - a job survives `kill -9` of the server in the middle of its generation (the restarted
//!   server runs it again and finishes it), and its files are the very bytes
//!   `dancegen generate` writes for the same song, options and seed;
//! - load over loopback, bounded in count and time: 50 songs submitted at once, then 1000
//!   status and SSE requests while the jobs run. Every job must end done, run exactly once and
//!   leave its files; none may be lost or duplicated; the server's peak memory must stay under
//!   1.5 GB. Status latency (p50/p99) and the peak are printed
//!   (`cargo test -p dancegen-cli --test cli_serve -- --nocapture fifty`).
//!
//! The two tests take turns ([`ONE_SERVER_AT_A_TIME`]), so the load figures are not the
//! other test's.

mod common;
#[path = "common/serve.rs"]
mod serve;

use std::collections::HashSet;
use std::path::Path;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use common::{dancegen, ok};
use serve::ServeProcess;

/// Held by each test for its whole run.
static ONE_SERVER_AT_A_TIME: Mutex<()> = Mutex::new(());

const SEED: &str = "9";
const END_S: &str = "10";
const JOB_TIMEOUT: Duration = Duration::from_secs(900);

fn demo_song() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/demo_metal_madness_45s.ogg")
}

#[test]
fn a_job_killed_mid_generation_finishes_after_a_restart_with_the_clis_bytes() {
    let _turn = ONE_SERVER_AT_A_TIME
        .lock()
        .unwrap_or_else(|e| e.into_inner());
    let data = tempfile::tempdir().unwrap();
    let server = ServeProcess::start(data.path(), &[]);
    let params = format!(r#"{{"seed": {SEED}, "end": {END_S}}}"#);
    let r = server.client.submit_song(&demo_song(), &params).unwrap();
    assert_eq!(r.status, 202, "{}", r.json);
    let id = r.json["id"].as_str().unwrap().to_string();

    // Wait until the job is really generating (model loaded, song analysed), then kill -9.
    let t = Instant::now();
    loop {
        let job = server.client.get(&format!("/api/jobs/{id}")).unwrap().json;
        let denoising = job["state"] == "running"
            && job["stage"] != "load_model"
            && job["stage"] != "analyse_song"
            && !job["stage"].is_null();
        if denoising {
            break;
        }
        assert_ne!(
            job["state"], "done",
            "the job ended before it could be killed: {job}"
        );
        assert!(t.elapsed() < JOB_TIMEOUT, "the job never started: {job}");
        std::thread::sleep(Duration::from_millis(50));
    }
    server.kill9();

    let server = ServeProcess::start(data.path(), &[]);
    let job = server.client.wait(&id, JOB_TIMEOUT).unwrap();
    assert_eq!(job["state"], "done", "{job}");
    assert_eq!(job["attempts"], 2, "the job should have run twice: {job}");
    // No staging leftovers in the job folder.
    let folder = data.path().join("jobs").join(&id);
    let hidden: Vec<_> = std::fs::read_dir(&folder)
        .unwrap()
        .flatten()
        .filter(|e| e.file_name().to_string_lossy().starts_with('.'))
        .map(|e| e.file_name())
        .collect();
    assert!(hidden.is_empty(), "left in the job folder: {hidden:?}");

    // The CLI on the uploaded song (the same bytes) with the same options.
    let song = folder.join(
        job["files"]
            .as_object()
            .unwrap()
            .keys()
            .find(|k| k.starts_with("song"))
            .unwrap(),
    );
    let cli = tempfile::tempdir().unwrap();
    let outputs: Vec<String> = ["glb", "fbx", "npy", "bvh", "npz"]
        .iter()
        .map(|ext| {
            cli.path()
                .join(format!("dance.{ext}"))
                .display()
                .to_string()
        })
        .collect();
    let mut args = vec![
        "generate",
        song.to_str().unwrap(),
        "--seed",
        SEED,
        "--end",
        END_S,
        "--progress",
        "none",
        "-q",
    ];
    for o in &outputs {
        args.extend(["-o", o.as_str()]);
    }
    ok(&dancegen(&args));
    for ext in ["glb", "fbx", "npy", "bvh", "npz"] {
        let served = server
            .client
            .download(job["variations"][0]["files"][ext].as_str().unwrap())
            .unwrap();
        let written = std::fs::read(cli.path().join(format!("dance.{ext}"))).unwrap();
        assert!(
            served == written,
            "dance.{ext}: the server's {} bytes differ from the CLI's {}",
            served.len(),
            written.len()
        );
    }
}

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
    let _turn = ONE_SERVER_AT_A_TIME
        .lock()
        .unwrap_or_else(|e| e.into_inner());
    let data = tempfile::tempdir().unwrap();
    // Fifty people's submissions, from one address on loopback: the per-address job limit
    // (10 a minute by default) would refuse them, so it is raised here.
    let server = ServeProcess::start(data.path(), &["--max-jobs-per-minute", "100"]);
    let song = Arc::new(std::fs::read(demo_song()).unwrap());

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

/// A holistic job over loopback: the served files are the CLI's bytes for the same song and
/// options, and they include the face as Live Link CSV and the (T, 52, 3) joints.
#[test]
fn a_holistic_job_serves_fingers_and_face_as_the_cli_writes_them() {
    let _turn = ONE_SERVER_AT_A_TIME
        .lock()
        .unwrap_or_else(|e| e.into_inner());
    let data = tempfile::tempdir().unwrap();
    let server = ServeProcess::start(data.path(), &[]);
    let r = server
        .client
        .submit_song(
            &demo_song(),
            r#"{"system": "holistic", "seed": 4, "end": 5}"#,
        )
        .unwrap();
    assert_eq!(r.status, 202, "{}", r.json);
    let id = r.json["id"].as_str().unwrap().to_string();
    let job = server.client.wait(&id, JOB_TIMEOUT).unwrap();
    assert_eq!(job["state"], "done", "{job}");
    let files = &job["variations"][0]["files"];
    let cli = tempfile::tempdir().unwrap();
    let out = |ext: &str| cli.path().join(format!("d.{ext}")).display().to_string();
    let song = demo_song();
    let mut args = vec![
        "generate",
        song.to_str().unwrap(),
        "--system",
        "holistic",
        "--seed",
        "4",
        "--end",
        "5",
        "-q",
    ];
    let outs: Vec<String> = ["npy", "json", "csv"].iter().map(|e| out(e)).collect();
    for o in &outs {
        args.extend(["-o", o.as_str()]);
    }
    ok(&dancegen(&args));
    for ext in ["npy", "json", "csv"] {
        let url = files[ext]
            .as_str()
            .unwrap_or_else(|| panic!("no .{ext} among the job's files: {job}"));
        let served = server.client.download(url).unwrap();
        let written = std::fs::read(out(ext)).unwrap();
        assert!(
            served == written,
            "d.{ext}: the server's bytes differ from the CLI's"
        );
    }
    let a = dancegen_io::read_npy(Path::new(&out("npy"))).unwrap();
    assert_eq!(a.shape, vec![150, 52, 3]);
}
