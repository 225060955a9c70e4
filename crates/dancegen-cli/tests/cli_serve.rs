//! `dancegen serve` as users run it: a job survives `kill -9` of the server in the middle of
//! its generation (the restarted server runs it again and finishes it), and its files are
//! the very bytes `dancegen generate` writes for the same song, options and seed.

mod common;
#[path = "common/serve.rs"]
mod serve;

use std::path::Path;
use std::time::{Duration, Instant};

use common::{dancegen, ok};
use serve::ServeProcess;

const SEED: &str = "9";
const END_S: &str = "10";
const JOB_TIMEOUT: Duration = Duration::from_secs(900);

fn demo_song() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/demo_metal_madness_45s.ogg")
}

#[test]
fn a_job_killed_mid_generation_finishes_after_a_restart_with_the_clis_bytes() {
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
    let outputs: Vec<String> = ["glb", "npy", "bvh", "npz"]
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
    for ext in ["glb", "npy", "bvh", "npz"] {
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
