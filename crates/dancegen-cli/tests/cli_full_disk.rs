//! A full disk (issue 47): `dancegen generate -o`, `dancegen batch` and `dancegen serve` each
//! write onto a small tmpfs that the test fills. Each must fail with a clear error, leave no
//! partial file, and (the server) keep answering; once space is freed, the next run succeeds.
//!
//! Mounting a tmpfs needs root. Without it these tests say so and pass, unless
//! `DANCEGEN_REQUIRE_TMPFS=1` (`tools/test.sh` sets it when it runs as root), where they fail.

mod common;
#[path = "common/serve.rs"]
mod serve;

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

use common::{dancegen, ok, stderr};
use serve::ServeProcess;

fn demo_song() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/demo_metal_madness_45s.ogg")
}

/// A tmpfs of a few MB mounted on a temporary folder, unmounted when dropped.
struct Tmpfs {
    dir: tempfile::TempDir,
}

impl Tmpfs {
    /// Mounts `mb` MB, or says why it cannot (then the test passes unless required).
    fn mount(mb: usize) -> Option<Tmpfs> {
        let dir = tempfile::tempdir().unwrap();
        let mounted = Command::new("mount")
            .args(["-t", "tmpfs", "-o", &format!("size={mb}m"), "tmpfs"])
            .arg(dir.path())
            .status()
            .is_ok_and(|s| s.success());
        if mounted {
            return Some(Tmpfs { dir });
        }
        let why = "cannot mount a tmpfs (this test needs root)";
        assert!(
            std::env::var_os("DANCEGEN_REQUIRE_TMPFS").is_none(),
            "{why}, and DANCEGEN_REQUIRE_TMPFS is set"
        );
        eprintln!("skipped: {why}");
        None
    }

    fn path(&self) -> &Path {
        self.dir.path()
    }

    /// Fills the file system, then gives back `leave` bytes: writes zeros to a filler file
    /// until the disk refuses, then shortens it.
    fn fill_leaving(&self, leave: u64) {
        let filler = self.path().join("filler");
        let mut f = std::fs::File::create(&filler).unwrap();
        let block = vec![0u8; 64 << 10];
        let mut written = 0u64;
        loop {
            match f.write(&block) {
                Ok(0) | Err(_) => break,
                Ok(n) => written += n as u64,
            }
        }
        f.set_len(written.saturating_sub(leave)).unwrap();
    }

    fn free(&self) {
        std::fs::remove_file(self.path().join("filler")).unwrap();
    }

    /// Files under the mount (relative paths), the filler excepted.
    fn files(&self) -> Vec<String> {
        fn walk(dir: &Path, root: &Path, out: &mut Vec<String>) {
            for e in std::fs::read_dir(dir).unwrap().flatten() {
                let p = e.path();
                if p.is_dir() {
                    walk(&p, root, out);
                } else {
                    out.push(p.strip_prefix(root).unwrap().display().to_string());
                }
            }
        }
        let mut out = Vec::new();
        walk(self.path(), self.path(), &mut out);
        out.retain(|f| f != "filler");
        out.sort();
        out
    }
}

impl Drop for Tmpfs {
    fn drop(&mut self) {
        let _ = Command::new("umount")
            .arg("-l")
            .arg(self.dir.path())
            .status();
    }
}

#[test]
fn generate_on_a_full_disk_fails_cleanly_and_works_once_there_is_room() {
    let Some(disk) = Tmpfs::mount(4) else { return };
    let out = |n: &str| disk.path().join(n).to_str().unwrap().to_string();
    let song = demo_song();
    let args = |glb: &str, npy: &str| {
        vec![
            "-q".to_string(),
            "generate".into(),
            song.to_str().unwrap().into(),
            "--end".into(),
            "8".into(),
            "-o".into(),
            glb.to_string(),
            "-o".into(),
            npy.to_string(),
        ]
    };
    disk.fill_leaving(16 << 10);
    let a = args(&out("dance.glb"), &out("dance.npy"));
    let o = dancegen(&a.iter().map(String::as_str).collect::<Vec<_>>());
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(e.contains("No space left on device"), "{e}");
    assert!(e.contains("dance."), "the error names the file: {e}");
    assert_eq!(disk.files(), Vec::<String>::new(), "no partial file");

    disk.free();
    ok(&dancegen(&a.iter().map(String::as_str).collect::<Vec<_>>()));
    assert_eq!(disk.files(), ["dance.glb", "dance.npy"]);
}

#[test]
fn batch_on_a_full_disk_fails_the_song_cleanly_and_a_rerun_makes_it() {
    let Some(disk) = Tmpfs::mount(4) else { return };
    let manifest_dir = tempfile::tempdir().unwrap();
    let manifest = manifest_dir.path().join("songs.jsonl");
    std::fs::write(
        &manifest,
        format!(
            "{{\"id\": \"demo\", \"song\": \"{}\", \"end\": 6, \"outputs\": [\"dance.glb\", \"dance.npy\"]}}\n",
            demo_song().display()
        ),
    )
    .unwrap();
    let out = disk.path().join("out");
    std::fs::create_dir(&out).unwrap();
    let run = || {
        dancegen(&[
            "-q",
            "batch",
            manifest.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ])
    };
    disk.fill_leaving(16 << 10);
    let o = run();
    assert!(
        !o.status.success(),
        "a song that could not be written fails the run"
    );
    // The song's error is in results.jsonl (written: a line fits in the room left).
    let results = std::fs::read_to_string(out.join("results.jsonl")).unwrap_or_default();
    assert!(
        results.contains("\"id\":\"demo\"") && results.contains("No space left on device"),
        "{}\nresults: {results}",
        stderr(&o)
    );
    let left = disk.files();
    assert!(
        left.iter()
            .all(|f| !f.starts_with("out/demo/dance") && !f.ends_with("done.json")),
        "no dance file or done.json from the failed song: {left:?}"
    );

    disk.free();
    let again = run();
    assert!(
        again.status.success(),
        "{}\nresults: {}",
        stderr(&again),
        std::fs::read_to_string(out.join("results.jsonl")).unwrap_or_default()
    );
    let made = disk.files();
    for f in [
        "out/demo/dance.glb",
        "out/demo/dance.npy",
        "out/demo/done.json",
    ] {
        assert!(made.iter().any(|m| m == f), "{f} missing: {made:?}");
    }
}

#[test]
fn the_server_survives_a_full_disk_and_the_next_job_succeeds() {
    let Some(disk) = Tmpfs::mount(16) else { return };
    let data = disk.path().join("serve");
    let server = ServeProcess::start(&data, &[]);
    let params = r#"{"end": 6}"#;
    let first = server.client.submit_song(&demo_song(), params).unwrap();
    assert_eq!(first.status, 202, "{}", first.json);
    let id = first.json["id"].as_str().unwrap().to_string();
    // The disk fills while the job works.
    disk.fill_leaving(64 << 10);
    let job = server.client.wait(&id, Duration::from_secs(600)).unwrap();
    assert_eq!(job["state"], "failed", "{job}");
    let error = job["error"].as_str().unwrap_or("");
    assert!(
        error.contains("space") || error.contains("full"),
        "the job says the disk is full: {error}"
    );
    let left: Vec<String> = disk
        .files()
        .into_iter()
        .filter(|f| f.starts_with(&format!("serve/jobs/{id}/")))
        .collect();
    assert!(
        left.iter().all(|f| f.ends_with("/song.ogg")),
        "only the song stays in the failed job's folder: {left:?}"
    );
    // The server keeps answering, and says no in words while the disk is full.
    assert_eq!(server.client.get("/api/systems").unwrap().status, 200);
    assert_eq!(
        server
            .client
            .get(&format!("/api/jobs/{id}"))
            .unwrap()
            .status,
        200
    );

    disk.free();
    let next = server.client.submit_song(&demo_song(), params).unwrap();
    assert_eq!(next.status, 202, "{}", next.json);
    let next_id = next.json["id"].as_str().unwrap().to_string();
    let done = server
        .client
        .wait(&next_id, Duration::from_secs(600))
        .unwrap();
    assert_eq!(done["state"], "done", "{done}");
}
