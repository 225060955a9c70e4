//! `dancegen batch`: shards as separate processes, a process killed mid-way and run again,
//! every song generated exactly once with the bytes of a single `generate` call; bad lines
//! fail alone.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use common::{dancegen, ok, shared, stderr};
use serde_json::Value;

const OUTPUTS: [&str; 3] = ["dance.glb", "dance.npy", "dance.bvh"];

fn song(name: &str) -> PathBuf {
    shared().join("data/music/sectoid").join(name)
}

/// The three songs: (id, song, start, end, seed given in the manifest).
fn songs() -> Vec<(&'static str, PathBuf, f64, f64, Option<u64>)> {
    vec![
        ("feelings", song("feelings.ogg"), 10.0, 18.0, Some(7)),
        (
            "chaosland",
            song("escape_from_chaosland.ogg"),
            0.0,
            8.0,
            None,
        ),
        ("metal", song("metal_madness.ogg"), 20.0, 28.0, Some(3)),
    ]
}

/// FNV-1a 64 of the id folded to 32 bits: the documented default seed, computed here
/// independently of the binary.
fn default_seed(id: &str) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in id.bytes() {
        h = (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3);
    }
    (h ^ (h >> 32)) & 0xffff_ffff
}

fn batch(args: &[&str]) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_dancegen"));
    c.arg("batch")
        .args(args)
        .env_remove("DANCEGEN_MODEL_DIR")
        .env(
            "XDG_DATA_HOME",
            Path::new(env!("CARGO_TARGET_TMPDIR")).join("no-installed-models"),
        )
        .stdout(Stdio::null())
        .stderr(Stdio::piped());
    c
}

fn wait(mut child: Child) -> std::process::Output {
    let mut err = String::new();
    if let Some(mut e) = child.stderr.take() {
        use std::io::Read;
        e.read_to_string(&mut err).unwrap();
    }
    let status = child.wait().unwrap();
    assert!(status.success(), "batch failed: {err}");
    std::process::Output {
        status,
        stdout: Vec::new(),
        stderr: err.into_bytes(),
    }
}

fn results(out: &Path) -> Vec<Value> {
    std::fs::read_to_string(out.join("results.jsonl"))
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

#[test]
fn two_shards_a_kill_and_a_rerun_generate_each_song_once_as_generate_would() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = dir.path().join("songs.jsonl");
    let mut text = String::new();
    for (id, song, start, end, seed) in songs() {
        let mut line = serde_json::json!({
            "id": id, "song": song, "start": start, "end": end, "outputs": OUTPUTS,
        });
        if let Some(s) = seed {
            line["seed"] = s.into();
        }
        text.push_str(&format!("{line}\n"));
    }
    std::fs::write(&manifest, text).unwrap();
    let out = dir.path().join("out");
    let (m, o) = (manifest.to_str().unwrap(), out.to_str().unwrap());

    // Shard 0 (feelings, metal) is killed once feelings is done; shard 1 (chaosland) runs
    // beside it in its own process.
    let shard0 = batch(&[m, "--out", o, "--shard", "0/2"]).spawn().unwrap();
    let shard1 = batch(&[m, "--out", o, "--shard", "1/2"]).spawn().unwrap();
    let first_done = out.join("feelings/done.json");
    let deadline = Instant::now() + Duration::from_secs(600);
    let mut shard0 = shard0;
    while !first_done.exists() {
        assert!(
            Instant::now() < deadline,
            "shard 0 never finished its first song"
        );
        assert!(shard0.try_wait().unwrap().is_none(), "shard 0 ended early");
        std::thread::sleep(Duration::from_millis(20));
    }
    shard0.kill().unwrap();
    shard0.wait().unwrap();
    assert!(
        !out.join("metal/done.json").exists(),
        "the kill came too late to interrupt the second song"
    );
    assert!(
        !out.join("metal/dance.glb").exists(),
        "a killed song left an output"
    );
    wait(shard1);

    // Run shard 0 again, then the whole manifest: nothing is generated twice.
    let again = wait(batch(&[m, "--out", o, "--shard", "0/2"]).spawn().unwrap());
    assert!(
        stderr(&again).contains("feelings: already done"),
        "{}",
        stderr(&again)
    );
    wait(batch(&[m, "--out", o, "--jobs", "2"]).spawn().unwrap());

    let lines = results(&out);
    for (id, ..) in songs() {
        let of_id: Vec<&Value> = lines.iter().filter(|l| l["id"] == id).collect();
        let generated = of_id
            .iter()
            .filter(|l| l["skipped"] == false && l["error"].is_null())
            .count();
        assert_eq!(generated, 1, "{id} generated {generated} times: {of_id:?}");
        assert!(of_id.iter().all(|l| l["error"].is_null()), "{of_id:?}");
        assert!(of_id.iter().all(|l| l["seconds"].is_number()));
    }
    // feelings: generated, skipped by the rerun of shard 0, skipped by the full run.
    assert_eq!(lines.iter().filter(|l| l["id"] == "feelings").count(), 3);

    // Each song equals a single `generate` call with the same options.
    let single = dir.path().join("single");
    for (id, song, start, end, seed) in songs() {
        let seed = seed.unwrap_or_else(|| default_seed(id));
        let done: Value =
            serde_json::from_slice(&std::fs::read(out.join(id).join("done.json")).unwrap())
                .unwrap();
        assert_eq!(done["seed"], seed, "{id}");
        assert_eq!(done["outputs"], serde_json::json!(OUTPUTS));
        let to = single.join(id);
        std::fs::create_dir_all(&to).unwrap();
        let mut args = vec![
            "generate".to_string(),
            song.display().to_string(),
            format!("--start={start}"),
            format!("--end={end}"),
            format!("--seed={seed}"),
            "-q".into(),
        ];
        for name in OUTPUTS {
            args.push("-o".into());
            args.push(to.join(name).display().to_string());
        }
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        ok(&dancegen(&args));
        for name in OUTPUTS {
            let a = std::fs::read(out.join(id).join(name)).unwrap();
            let b = std::fs::read(to.join(name)).unwrap();
            assert!(a == b, "{id}/{name} differs from the single generate call");
        }
        // Nothing half-written is left beside the outputs.
        for entry in std::fs::read_dir(out.join(id)).unwrap() {
            let name = entry.unwrap().file_name().into_string().unwrap();
            assert!(
                OUTPUTS.contains(&name.as_str()) || name == "done.json" || name == ".batch.lock",
                "{id}: unexpected {name}"
            );
        }
    }
}

#[test]
fn bad_lines_fail_alone_with_their_line_and_the_rest_goes_on() {
    let dir = tempfile::tempdir().unwrap();
    let good = song("feelings.ogg");
    std::fs::copy(&good, dir.path().join("here.ogg")).unwrap();
    let manifest = dir.path().join("m.jsonl");
    std::fs::write(
        &manifest,
        [
            "{\"id\": \"broken\", \"song\": ".to_string(),
            r#"{"id": "gone", "song": "missing.ogg"}"#.to_string(),
            r#"{"id": "typo", "song": "here.ogg", "colour": "red"}"#.to_string(),
            // The song path is relative to the manifest's folder.
            r#"{"id": "fine", "song": "here.ogg", "end": 6, "outputs": ["d.npy"]}"#.to_string(),
            r#"{"id": "fine", "song": "here.ogg"}"#.to_string(),
            r#"{"id": "unreadable", "song": "m.jsonl", "outputs": ["d.npy"]}"#.to_string(),
        ]
        .join("\n"),
    )
    .unwrap();
    let out = dir.path().join("out");
    let o = dancegen(&[
        "batch",
        manifest.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(!o.status.success(), "a failed song must fail the run");
    let err = stderr(&o);
    assert!(err.contains("5 of 6 songs failed"), "{err}");

    let lines = results(&out);
    assert_eq!(lines.len(), 6, "{lines:?}");
    let by_line = |n: u64| lines.iter().find(|l| l["line"] == n).unwrap();
    let error = |n: u64| by_line(n)["error"].as_str().unwrap_or_default().to_string();
    assert!(error(1).contains("line 1: not JSON"), "{}", error(1));
    assert!(by_line(1)["id"].is_null());
    assert!(
        error(2).contains("missing.ogg: no such file"),
        "{}",
        error(2)
    );
    assert_eq!(by_line(2)["id"], "gone");
    assert!(error(3).contains("no --colour"), "{}", error(3));
    assert!(by_line(4)["error"].is_null(), "{:?}", by_line(4));
    assert_eq!(by_line(4)["skipped"], false);
    assert!(error(5).contains("first on line 4"), "{}", error(5));
    assert!(error(6).contains("m.jsonl"), "{}", error(6));
    let npy = std::fs::read(out.join("fine/d.npy")).unwrap();
    assert!(npy.starts_with(b"\x93NUMPY"));
    assert!(out.join("fine/done.json").exists());
    assert!(!out.join("unreadable/done.json").exists());

    // A missing manifest is an error naming it.
    let o = dancegen(&["batch", "nowhere.jsonl", "--out", out.to_str().unwrap()]);
    assert!(stderr(&o).contains("nowhere.jsonl: cannot read the manifest"));
    let o = dancegen(&[
        "batch",
        manifest.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--shard",
        "2/2",
    ]);
    assert!(stderr(&o).contains("need 0 ≤ I < N"), "{}", stderr(&o));
}

/// Edits through a manifest (issue 44): an `--edit` with its ranges and a keyframe, their
/// files taken from the manifest's folder like the song.
#[test]
fn a_manifest_line_edits_a_dance_and_reaches_a_keyframe() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy(song("feelings.ogg"), dir.path().join("here.ogg")).unwrap();
    let base = dir.path().join("base.npz");
    ok(&dancegen(&[
        "-q",
        "generate",
        dir.path().join("here.ogg").to_str().unwrap(),
        "--end",
        "8",
        "-o",
        base.to_str().unwrap(),
        "-o",
        dir.path().join("base.npy").to_str().unwrap(),
    ]));
    let manifest = dir.path().join("m.jsonl");
    std::fs::write(
        &manifest,
        [
            r#"{"id": "edited", "song": "here.ogg", "edit": "base.npz", "regenerate": ["2-4"], "seed": 5, "outputs": ["d.npy"]}"#,
            r#"{"id": "posed", "song": "here.ogg", "end": 8, "keyframe": ["base.npz:30@5"], "keyframe_root": true, "outputs": ["d.npy"]}"#,
        ]
        .join("\n"),
    )
    .unwrap();
    let out = dir.path().join("out");
    ok(&dancegen(&[
        "batch",
        manifest.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]));
    let read = |p: &Path| dancegen_io::read_npy(p).unwrap().data;
    let (old, edited) = (
        read(&dir.path().join("base.npy")),
        read(&out.join("edited/d.npy")),
    );
    assert_eq!(old.len(), edited.len());
    let frame = 72;
    for f in (0..old.len() / frame).filter(|f| !(60..120).contains(f)) {
        for i in f * frame..(f + 1) * frame {
            assert!((old[i] - edited[i]).abs() <= 1e-4, "frame {f} changed");
        }
    }
    let posed = read(&out.join("posed/d.npy"));
    let worst = (0..frame)
        .map(|i| (posed[150 * frame + i] - old[30 * frame + i]).abs())
        .fold(0.0, f64::max);
    assert!(worst <= 0.03, "the keyframe is missed by {worst} m");
}
