//! The HTTP API over loopback: a server on a free port of 127.0.0.1 with a temporary data
//! dir, spoken to as a client would. Jobs run the shipped models on the bundled demo song.

use std::time::Duration;

use crate::common::{TestServer, demo_song, shared, start};
use dancegen_server::client::{Part, Reply};
use dancegen_server::{Limits, ServeConfig};
use serde_json::Value;

const JOB_TIMEOUT: Duration = Duration::from_secs(600);

fn error_of(r: &Reply) -> String {
    r.json["error"].as_str().unwrap_or("").to_string()
}

#[test]
fn a_solo_job_runs_streams_progress_and_serves_its_files_with_range() {
    let s = start(Limits::default());
    let r = s.submit_song(&demo_song(), r#"{"seed": 4, "end": 8, "variations": 2}"#);
    assert_eq!(r.status, 202, "{}", r.json);
    let id = r.json["id"].as_str().unwrap().to_string();

    // The stream starts with the current object and follows the job to its end.
    let events = s.events(&format!("/api/jobs/{id}/events"), |v| {
        v["state"] == "done" || v["state"] == "failed"
    });
    let last = events.last().unwrap();
    assert_eq!(last["state"], "done", "{last}");
    assert!(events.len() >= 3, "only {} events", events.len());
    let progress: Vec<f64> = events
        .iter()
        .filter(|e| e["state"] == "running")
        .map(|e| e["progress"].as_f64().unwrap())
        .collect();
    assert!(
        progress.windows(2).all(|w| w[1] >= w[0]),
        "progress went back: {progress:?}"
    );
    assert!(
        events.iter().any(|e| e["stage"] == "denoising"),
        "no denoising stage seen"
    );

    let job = s.wait(&id, JOB_TIMEOUT);
    assert_eq!(job["attempts"], 1);
    let files = job["files"].as_object().unwrap();
    for name in [
        "song.ogg",
        "dance.glb",
        "dance.bvh",
        "dance.npz",
        "dance.npy",
        "dance.json",
        "dance-2.glb",
        "dance-2.npy",
    ] {
        assert!(files.contains_key(name), "{name} missing from {files:?}");
    }
    let vars = job["variations"].as_array().unwrap();
    assert_eq!(vars.len(), 2);
    assert_eq!(
        (vars[0]["seed"].as_u64(), vars[1]["seed"].as_u64()),
        (Some(4), Some(5))
    );
    assert_ne!(
        s.download(vars[0]["files"]["npy"].as_str().unwrap()),
        s.download(vars[1]["files"]["npy"].as_str().unwrap()),
        "two seeds made the same dance"
    );

    // The viewer seeks in the song: Range gets 206 with exactly the bytes asked for.
    let song = std::fs::read(demo_song()).unwrap();
    let r = s.get_range(job["song"].as_str().unwrap(), "bytes=100-1099");
    assert_eq!(r.status, 206);
    assert_eq!(r.bytes, &song[100..1100]);
    assert_eq!(
        r.header("content-range"),
        Some(format!("bytes 100-1099/{}", song.len()).as_str())
    );
    assert!(r.header("content-type").unwrap_or("").starts_with("audio/"));

    // Removing a finished job removes it and its files.
    let folder = s.data.path().join("jobs").join(&id);
    assert!(folder.join("dance.glb").is_file());
    assert_eq!(s.delete(&format!("/api/jobs/{id}")).status, 204);
    assert_eq!(s.get(&format!("/api/jobs/{id}")).status, 404);
    assert!(!folder.exists());
}

/// Downloads are named for people: each variation's `names`, the files' `Content-Disposition`
/// and the entries of the "download all" zip are `<song>-<system>-seed<k>.<ext>`, from the
/// uploaded song's name, and the zip holds exactly the bytes of the files.
#[test]
fn downloads_are_named_after_the_song_and_come_as_one_zip() {
    let s = start(Limits::default());
    let dir = tempfile::tempdir().unwrap();
    let song = dir.path().join("My Song (live).ogg");
    std::fs::copy(demo_song(), &song).unwrap();
    let r = s.submit_song(&song, r#"{"seed": 4, "end": 6, "variations": 2}"#);
    assert_eq!(r.status, 202, "{}", r.json);
    let id = r.json["id"].as_str().unwrap().to_string();
    // Before the dance is finished there is nothing to zip.
    let early = s.get(&format!("/api/jobs/{id}/zip"));
    if early.status != 200 {
        assert_eq!(early.status, 409, "{}", early.json);
        assert!(error_of(&early).contains("not finished"), "{}", early.json);
    }
    let job = s.wait(&id, JOB_TIMEOUT);
    assert_eq!(job["state"], "done", "{job}");
    let mut expected = std::collections::BTreeMap::new();
    for (k, v) in job["variations"].as_array().unwrap().iter().enumerate() {
        let seed = 4 + k;
        let (files, names) = (
            v["files"].as_object().unwrap(),
            v["names"].as_object().unwrap(),
        );
        assert_eq!(
            files.keys().collect::<Vec<_>>(),
            names.keys().collect::<Vec<_>>()
        );
        for kind in ["glb", "fbx", "bvh", "npz", "npy", "json"] {
            assert_eq!(
                names[kind],
                format!("My-Song-(live)-solo-seed{seed}.{kind}"),
                "{v}"
            );
        }
        for (kind, url) in files {
            let r = s.get(url.as_str().unwrap());
            assert_eq!(r.status, 200);
            let name = names[kind].as_str().unwrap();
            let disposition = r.header("content-disposition").unwrap_or("");
            assert!(
                disposition.contains(&format!("filename=\"{name}\"")),
                "{kind}: {disposition}"
            );
            expected.insert(name.to_string(), r.bytes);
        }
    }
    let z = s.get(&format!("/api/jobs/{id}/zip"));
    assert_eq!(z.status, 200, "{}", z.json);
    assert_eq!(z.header("content-type"), Some("application/zip"));
    assert!(
        z.header("content-disposition")
            .unwrap_or("")
            .contains("filename=\"My-Song-(live)-solo-seeds4-5.zip\""),
        "{:?}",
        z.header("content-disposition")
    );
    let mut archive = zip::ZipArchive::new(std::io::Cursor::new(z.bytes)).unwrap();
    let mut got = std::collections::BTreeMap::new();
    for i in 0..archive.len() {
        let mut f = archive.by_index(i).unwrap();
        let mut bytes = Vec::new();
        std::io::Read::read_to_end(&mut f, &mut bytes).unwrap();
        got.insert(f.name().to_string(), bytes);
    }
    assert_eq!(
        got.keys().collect::<Vec<_>>(),
        expected.keys().collect::<Vec<_>>()
    );
    assert!(got == expected, "the zip's files differ from the downloads");
    // The song itself is not a dance file: it is not zipped, and downloads under its own
    // name (every job file is an attachment).
    let song = job["song"].as_str().unwrap();
    let r = s.get(song);
    let stored = song.rsplit('/').next().unwrap();
    assert_eq!(
        r.header("content-disposition"),
        Some(format!("attachment; filename=\"{stored}\"; filename*=UTF-8''{stored}").as_str())
    );
    assert_eq!(s.get("/api/jobs/nosuchjob/zip").status, 404);
}

/// A mono 16-bit WAV of `seconds` of a 220 Hz tone at 22,050 Hz.
fn tone_wav(seconds: f64) -> Vec<u8> {
    wav(seconds, 8000.0)
}

/// A mono 16-bit WAV of `seconds` of a 220 Hz tone of peak `amplitude` (0: silence).
fn wav(seconds: f64, amplitude: f64) -> Vec<u8> {
    let spec = hound::WavSpec {
        channels: 1,
        sample_rate: 22_050,
        bits_per_sample: 16,
        sample_format: hound::SampleFormat::Int,
    };
    let mut bytes = std::io::Cursor::new(Vec::new());
    let mut w = hound::WavWriter::new(&mut bytes, spec).unwrap();
    for i in 0..(seconds * 22_050.0) as u32 {
        let x = (std::f64::consts::TAU * 220.0 * f64::from(i) / 22_050.0).sin();
        w.write_sample((x * amplitude) as i16).unwrap();
    }
    w.finalize().unwrap();
    bytes.into_inner()
}

/// A song without a beat (silence) is danced, and the job says so in `warnings`; a song with
/// a beat has none.
#[test]
fn a_song_without_a_beat_is_danced_with_a_warning() {
    let s = start(Limits::default());
    let silent = s.submit(&[
        ("params", None, br#"{"seed": 1}"#),
        ("song", Some("quiet.wav"), &wav(8.0, 0.0)),
    ]);
    assert_eq!(silent.status, 202, "{}", silent.json);
    let beat = s.submit_song(&demo_song(), r#"{"seed": 1, "start": 10, "end": 16}"#);
    assert_eq!(beat.status, 202, "{}", beat.json);
    let job = s.wait(silent.json["id"].as_str().unwrap(), JOB_TIMEOUT);
    assert_eq!(job["state"], "done", "{job}");
    let warnings = job["warnings"].as_array().unwrap();
    assert_eq!(warnings.len(), 1, "{job}");
    assert!(
        warnings[0]
            .as_str()
            .unwrap()
            .starts_with("no beat was found in the music from 0.0 to 8.0 s"),
        "{warnings:?}"
    );
    let job = s.wait(beat.json["id"].as_str().unwrap(), JOB_TIMEOUT);
    assert_eq!(job["state"], "done", "{job}");
    assert_eq!(job["warnings"], serde_json::json!([]), "{job}");
}

/// What used to be accepted and then failed in the job (or failed in the decoder's or the
/// command line's words) is refused at upload, naming the field and saying what to do, with
/// no server path or flag in the message.
#[test]
fn songs_spans_and_leaders_are_checked_at_upload_in_words() {
    let s = start(Limits::default());
    let song = std::fs::read(demo_song()).unwrap();
    let submit = |params: &str, name: &str, bytes: &[u8]| {
        s.submit(&[
            ("params", None, params.as_bytes()),
            ("song", Some(name), bytes),
        ])
    };
    let refused = |r: &Reply, field: &str, words: &str| {
        assert_eq!(r.status, 400, "{}", r.json);
        assert_eq!(r.json["field"], field, "{}", r.json);
        let e = error_of(r);
        assert!(e.contains(words), "{e}");
        assert!(
            !e.contains('/') && !e.contains("--"),
            "a path or a flag: {e}"
        );
    };
    // The demo song is 45 s; the solo system needs 2 s of music.
    refused(
        &submit(r#"{"seed": 1}"#, "clip.wav", &tone_wav(0.5)),
        "song",
        "the song is 0.5 s long; a solo dance needs at least 2.0 s of music",
    );
    refused(
        &submit(r#"{"start": 500}"#, "demo.ogg", &song),
        "start",
        "start at 43.0 s or earlier",
    );
    refused(
        &submit(r#"{"start": 44}"#, "demo.ogg", &song),
        "start",
        "leaves 1.0 s of the 45.0 s song",
    );
    refused(
        &submit(r#"{"end": 60}"#, "demo.ogg", &song),
        "end",
        "after the song's end (45.0 s)",
    );
    refused(
        &submit(r#"{"start": 10, "end": 11}"#, "demo.ogg", &song),
        "end",
        "end at 12.0 s or later",
    );
    refused(
        &submit(
            r#"{"system": "group", "dancers": 3}"#,
            "clip.wav",
            &tone_wav(2.2),
        ),
        "song",
        "a group dance needs at least 2.5 s",
    );
    refused(
        &submit(r#"{}"#, "notes.mp3", b"these are my notes, not a song\n"),
        "song",
        "this file is not audio, or not in a format this server reads",
    );
    let r = s.submit(&[
        ("params", None, br#"{"system": "duet"}"#),
        ("song", Some("demo.ogg"), &song),
        ("leader", Some("partner.ogg"), &song),
    ]);
    refused(&r, "leader", "the leader must be a dance motion file");
    assert!(!error_of(&r).contains("leader: leader"), "{}", r.json);
    // Right at the bounds is accepted.
    let ok = submit(r#"{"start": 43, "end": 45}"#, "demo.ogg", &song);
    assert_eq!(ok.status, 202, "{}", ok.json);
}

#[test]
fn file_names_that_leave_the_job_folder_are_not_found() {
    let s = start(Limits::default());
    let r = s.submit_song(&demo_song(), r#"{"end": 3}"#);
    assert_eq!(r.status, 202, "{}", r.json);
    let id = r.json["id"].as_str().unwrap();
    // Something worth stealing one folder up.
    std::fs::write(s.data.path().join("jobs").join("secret.txt"), b"secret").unwrap();
    assert_eq!(s.get(&format!("/api/jobs/{id}/files/song.ogg")).status, 200);
    for name in [
        "..%2Fsecret.txt",
        "%2e%2e%2fsecret.txt",
        "..%5Csecret.txt",
        "..",
        "%2E%2E",
        ".incoming",
        "%2Fetc%2Fpasswd",
        "no-such-file.glb",
    ] {
        let r = s.get(&format!("/api/jobs/{id}/files/{name}"));
        assert_eq!(
            r.status,
            404,
            "{name}: {}",
            String::from_utf8_lossy(&r.bytes)
        );
        assert!(r.json["error"].is_string(), "{name}: not a JSON error");
    }
    assert_eq!(
        s.get(&format!("/api/jobs/{id}/files/../../jobs.sqlite3"))
            .status,
        404
    );
    assert_eq!(s.get("/api/jobs/..%2F..%2Fetc/files/passwd").status, 404);
    assert_eq!(s.get("/api/jobs/nosuchjob").status, 404);
    let _ = s.delete(&format!("/api/jobs/{id}"));
}

#[test]
fn limits_and_bad_input_get_clear_json_errors() {
    let s = start(Limits {
        upload_bytes: 1 << 20,
        song_seconds: 30.0,
        ..Limits::default()
    });
    let song = std::fs::read(demo_song()).unwrap(); // 45 s, under 1 MB
    assert!(song.len() < 1 << 20);

    // 413 on the declared length, before the body is read: the client sends only the headers
    // (a client that keeps writing a refused body may see the connection close under it).
    let reply = raw_exchange(
        s.server.addr,
        "POST /api/jobs HTTP/1.1\r\nHost: x\r\nContent-Type: multipart/form-data; \
         boundary=b\r\nContent-Length: 3145728\r\n\r\n",
    );
    assert!(reply.starts_with("HTTP/1.1 413"), "{reply}");
    assert!(
        reply.contains("\"error\"") && reply.contains("limit"),
        "{reply}"
    );
    // 413 on a song over the limit inside a body the server reads whole.
    let big = vec![0u8; (1 << 20) + 1];
    let r = s.submit(&[("song", Some("big.wav"), &big)]);
    assert_eq!(r.status, 413, "{}", r.json);
    assert!(error_of(&r).contains("limit"), "{}", r.json);

    // 400 naming the field.
    let cases: [(&str, &[Part], &str); 6] = [
        (
            "params",
            &[("song", Some("a.ogg"), &song), ("params", None, b"{nope")],
            "params",
        ),
        (
            "steps",
            &[
                ("song", Some("a.ogg"), &song),
                ("params", None, br#"{"steps": -3}"#),
            ],
            "steps",
        ),
        (
            "system",
            &[
                ("song", Some("a.ogg"), &song),
                ("params", None, br#"{"system": "ballet"}"#),
            ],
            "system",
        ),
        (
            "genre",
            &[
                ("song", Some("a.ogg"), &song),
                ("params", None, br#"{"genre": "polka"}"#),
            ],
            "genre",
        ),
        ("no song", &[("params", None, b"{}")], "song"),
        (
            "duet without a leader",
            &[
                ("song", Some("a.ogg"), &song),
                ("params", None, br#"{"system": "duet"}"#),
            ],
            "leader",
        ),
    ];
    for (what, parts, field) in cases {
        let r = s.submit(parts);
        assert_eq!(r.status, 400, "{what}: {}", r.json);
        assert_eq!(r.json["field"], field, "{what}: {}", r.json);
        assert!(error_of(&r).starts_with(field), "{what}: {}", r.json);
    }

    // Audio the decoder cannot read: 400 saying what the file is, not the decoder's internals.
    let noise: Vec<u8> = (0..50_000u32)
        .map(|i| (i.wrapping_mul(2654435761) >> 13) as u8)
        .collect();
    let r = s.submit(&[("song", Some("song.mp3"), &noise)]);
    assert_eq!(r.status, 400, "{}", r.json);
    assert_eq!(r.json["field"], "song");
    let e = error_of(&r);
    assert!(
        e.contains("is not audio") || e.contains("damaged or cut short"),
        "{}",
        r.json
    );
    assert!(
        !e.contains("probe") && !e.contains("song.mp3"),
        "{}",
        r.json
    );

    // A song over the duration limit: 400 naming the limit.
    let r = s.submit_song(&demo_song(), "");
    assert_eq!(r.status, 400, "{}", r.json);
    assert!(error_of(&r).contains("30 s"), "{}", r.json);
    assert!(error_of(&r).contains("duration limit"), "{}", r.json);

    drop(s);

    // 429: a queue that holds one job.
    let q = start(Limits {
        queue_length: 1,
        ..Limits::default()
    });
    let first = q.submit_song(&demo_song(), "");
    assert_eq!(first.status, 202, "{}", first.json);
    let second = q.submit_song(&demo_song(), "");
    assert_eq!(second.status, 429, "{}", second.json);
    assert!(
        error_of(&second).contains("queue is full"),
        "{}",
        second.json
    );
    // Cancelling the first frees the queue.
    let id = first.json["id"].as_str().unwrap();
    let r = q.delete(&format!("/api/jobs/{id}"));
    assert_eq!(r.status, 202, "{}", r.json);
    let job = q.wait(id, JOB_TIMEOUT);
    assert_eq!(job["state"], "cancelled", "{job}");
    let third = q.submit_song(&demo_song(), r#"{"end": 3, "mp4": true}"#);
    assert_eq!(third.status, 202, "{}", third.json);
    let id3 = third.json["id"].as_str().unwrap();
    let job = q.wait(id3, JOB_TIMEOUT);
    assert_eq!(job["state"], "done", "{job}");
    assert!(
        job["variations"][0]["files"]["mp4"].is_string(),
        "asked for an MP4: {job}"
    );
}

/// Sends `request` as is on a new connection and returns everything the server answers.
fn raw_exchange(addr: std::net::SocketAddr, request: &str) -> String {
    use std::io::{Read, Write};
    let mut tcp = std::net::TcpStream::connect(addr).unwrap();
    tcp.set_read_timeout(Some(Duration::from_secs(30))).unwrap();
    tcp.write_all(request.as_bytes()).unwrap();
    let mut reply = Vec::new();
    let _ = tcp.read_to_end(&mut reply);
    String::from_utf8_lossy(&reply).into_owned()
}

/// An upload over the limit from a plain client that sends its whole body before it reads
/// (no `Expect: 100-continue`) gets the 413 and its JSON, not a reset connection.
#[test]
fn an_oversized_upload_from_a_plain_client_gets_its_413() {
    use std::io::{Read, Write};
    let s = start(Limits {
        upload_bytes: 1 << 20,
        ..Limits::default()
    });
    let boundary = "----plainclient";
    let head = format!(
        "--{boundary}\r\nContent-Disposition: form-data; name=\"song\"; \
         filename=\"big.wav\"\r\nContent-Type: audio/wav\r\n\r\n"
    );
    let tail = format!("\r\n--{boundary}--\r\n");
    let song = vec![0u8; 6 << 20];
    let length = head.len() + song.len() + tail.len();
    let request = format!(
        "POST /api/jobs HTTP/1.1\r\nHost: test\r\nContent-Type: multipart/form-data; \
         boundary={boundary}\r\nContent-Length: {length}\r\nConnection: close\r\n\r\n"
    );
    let mut tcp = std::net::TcpStream::connect(s.server.addr).unwrap();
    tcp.set_read_timeout(Some(Duration::from_secs(30))).unwrap();
    // Everything first, as such a client does; a reset shows here as a write error.
    for part in [request.as_bytes(), head.as_bytes(), &song, tail.as_bytes()] {
        tcp.write_all(part)
            .expect("the server closed the connection under the upload");
    }
    let mut reply = Vec::new();
    tcp.read_to_end(&mut reply)
        .expect("the server reset the connection");
    let reply = String::from_utf8_lossy(&reply);
    assert!(reply.starts_with("HTTP/1.1 413"), "{reply}");
    assert!(reply.contains("larger than the limit of 1 MB"), "{reply}");
}

#[test]
fn a_slow_upload_is_cut_off_at_the_body_deadline() {
    use std::io::{Read, Write};
    let s = start(Limits {
        body_deadline: Duration::from_secs(1),
        ..Limits::default()
    });
    let mut tcp = std::net::TcpStream::connect(s.server.addr).unwrap();
    tcp.set_read_timeout(Some(Duration::from_secs(30))).unwrap();
    // A client that promises 100 kB and sends a few bytes, then stalls.
    write!(
        tcp,
        "POST /api/jobs HTTP/1.1\r\nHost: x\r\nContent-Type: multipart/form-data; \
         boundary=b\r\nContent-Length: 100000\r\n\r\n--b\r\nContent-Disposition: form-data; \
         name=\"song\"; filename=\"a.ogg\"\r\n\r\nOggS"
    )
    .unwrap();
    let t = std::time::Instant::now();
    let mut reply = Vec::new();
    let _ = tcp.read_to_end(&mut reply);
    let reply = String::from_utf8_lossy(&reply);
    assert!(
        t.elapsed() < Duration::from_secs(20),
        "not cut off: {reply}"
    );
    assert!(reply.starts_with("HTTP/1.1 408"), "{reply}");
    assert!(reply.contains("\"error\""), "not a JSON error: {reply}");
}

#[test]
fn systems_page_and_viewer_are_served() {
    let s: TestServer = start(Limits::default());
    let r = s.get("/api/systems");
    assert_eq!(r.status, 200);
    let systems = r.json["systems"].as_array().unwrap();
    let solo = systems.iter().find(|x| x["name"] == "solo").unwrap();
    assert_eq!(solo["available"], true, "{solo}");
    assert!(
        solo["genres"]
            .as_array()
            .unwrap()
            .iter()
            .any(|g| g == "salsa")
    );
    let duet = systems.iter().find(|x| x["name"] == "duet").unwrap();
    assert_eq!(duet["needs_leader"], true);
    let group = systems.iter().find(|x| x["name"] == "group").unwrap();
    assert_eq!(
        (
            group["dancers"]["min"].as_u64(),
            group["dancers"]["max"].as_u64()
        ),
        (Some(2), Some(5))
    );
    assert_eq!(r.json["limits"]["upload_bytes"], Value::from(64u64 << 20));

    let page = s.get("/");
    assert_eq!(page.status, 200);
    assert!(
        page.header("content-type")
            .unwrap()
            .starts_with("text/html")
    );
    let html = String::from_utf8(page.bytes).unwrap();
    assert!(html.contains("importmap"), "the page has no import map");
    let three = s.get("/vendor/three/three.module.js");
    assert_eq!(three.status, 200);
    assert!(
        three
            .header("content-type")
            .unwrap()
            .starts_with("text/javascript")
    );
    assert_eq!(s.get("/vendor/three/LICENSE").status, 200);
    assert_eq!(s.get("/no-such-page.js").status, 404);
    assert_eq!(s.get("/api/nothing-here").status, 404);
}

/// `edit` in a job's params (issue 44): a new job, the same song and system, the frames
/// outside the regenerated range the edited dance's, the range new; bad edits get a 400 that
/// names the field.
/// Dances `params` on the demo song, then submits an edit of that job (seed 7, 3-6 s
/// regenerated, `keep` kept); returns both jobs once done.
fn dance_then_edit(s: &TestServer, params: &str, keep: &str) -> (Value, Value) {
    let r = s.submit_song(&demo_song(), params);
    assert_eq!(r.status, 202, "{}", r.json);
    let id = r.json["id"].as_str().unwrap().to_string();
    let job = s.wait(&id, JOB_TIMEOUT);
    assert_eq!(job["state"], "done", "{job}");
    let edit = format!(
        r#"{{"seed": 7, "edit": {{"of": "{id}", "regenerate": [[3, 6]], "keep": "{keep}"}}}}"#
    );
    let r = s.submit(&[("params", None, edit.as_bytes())]);
    assert_eq!(r.status, 202, "{}", r.json);
    let eid = r.json["id"].as_str().unwrap().to_string();
    let edited = s.wait(&eid, JOB_TIMEOUT);
    assert_eq!(edited["state"], "done", "{edited}");
    (job, edited)
}

#[test]
fn an_edit_is_a_new_version_that_keeps_the_dance_outside_its_range() {
    let s = start(Limits::default());
    let (job, edited) = dance_then_edit(&s, r#"{"seed": 1, "end": 10}"#, "legs");
    let id = job["id"].as_str().unwrap().to_string();
    let eid = edited["id"].as_str().unwrap().to_string();
    assert_eq!(edited["params"]["system"], "solo");
    assert_eq!(edited["params"]["end"], 10.0);
    assert_eq!(edited["params"]["edit"]["of"], id.as_str());
    let npy = |job: &Value| {
        let bytes = s.download(job["variations"][0]["files"]["npy"].as_str().unwrap());
        dancegen_io::npy::parse_npy(&bytes).unwrap().data
    };
    let (old, new) = (npy(&job), npy(&edited));
    assert_eq!(old.len(), new.len());
    let frame = 72;
    for f in (0..old.len() / frame).filter(|f| !(90..180).contains(f)) {
        for i in f * frame..(f + 1) * frame {
            assert!((old[i] - new[i]).abs() <= 1e-4, "frame {f} changed");
        }
    }
    let moved = (90 * frame..180 * frame)
        .map(|i| (old[i] - new[i]).abs())
        .fold(0.0, f64::max);
    assert!(moved > 0.05, "the range is the old one ({moved} m)");

    // Both jobs list the same two versions, the first one first.
    for of in [&id, &eid] {
        let r = s.get(&format!("/api/jobs/{of}/versions"));
        assert_eq!(r.status, 200, "{}", r.json);
        let v = r.json["versions"].as_array().unwrap();
        assert_eq!(v.len(), 2, "{}", r.json);
        assert_eq!(
            (v[0]["id"].as_str(), v[0]["number"].as_u64()),
            (Some(id.as_str()), Some(1))
        );
        assert_eq!(v[1]["id"].as_str(), Some(eid.as_str()));
        assert_eq!(v[1]["edit"]["regenerate"][0][1], 6.0);
        assert!(v[0].get("edit").is_none());
    }
    assert_eq!(s.get("/api/jobs/nosuchjob/versions").status, 404);

    // "Continue": the whole dance, then more of it to the new end.
    let params = format!(r#"{{"end": 14, "edit": {{"of": "{id}", "continue": true}}}}"#);
    let r = s.submit(&[("params", None, params.as_bytes())]);
    assert_eq!(r.status, 202, "{}", r.json);
    let cid = r.json["id"].as_str().unwrap().to_string();
    let continued = s.wait(&cid, JOB_TIMEOUT);
    assert_eq!(continued["state"], "done", "{continued}");
    assert_eq!(continued["params"]["end"], 14.0);
    let longer = npy(&continued);
    assert_eq!(longer.len(), 420 * frame, "14 s of dance");
    assert!(
        old.iter().zip(&longer).all(|(a, b)| (a - b).abs() <= 1e-4),
        "the first 10 s changed"
    );
    let r = s.submit(&[(
        "params",
        None,
        format!(r#"{{"end": 10.2, "edit": {{"of": "{id}", "continue": true}}}}"#).as_bytes(),
    )]);
    assert_eq!(r.status, 400, "{}", r.json);
    assert_eq!(r.json["field"], "end", "{}", r.json);

    for (params, field) in [
        (
            r#"{"edit": {"of": "nosuchjob", "regenerate": [[1, 2]]}}"#.to_string(),
            "edit.of",
        ),
        (
            format!(r#"{{"edit": {{"of": "{id}", "regenerate": [[8, 12]]}}}}"#),
            "edit.regenerate",
        ),
        (
            format!(r#"{{"edit": {{"of": "{id}", "regenerate": [[1, 2]], "variation": 3}}}}"#),
            "edit.variation",
        ),
        (
            format!(r#"{{"system": "group", "edit": {{"of": "{id}", "regenerate": [[1, 2]]}}}}"#),
            "system",
        ),
    ] {
        let r = s.submit(&[("params", None, params.as_bytes())]);
        assert_eq!(r.status, 400, "{params}: {}", r.json);
        assert_eq!(r.json["field"], field, "{params}: {}", r.json);
    }
    let song = std::fs::read(demo_song()).unwrap();
    let params = format!(r#"{{"edit": {{"of": "{id}", "regenerate": [[1, 2]]}}}}"#);
    let r = s.submit(&[
        ("song", Some("song.ogg"), &song),
        ("params", None, params.as_bytes()),
    ]);
    assert_eq!(r.status, 400, "{}", r.json);
    assert_eq!(r.json["field"], "song");
}

#[test]
fn a_group_edit_keeps_every_dancer_outside_its_range() {
    let s = start(Limits::default());
    let r = s.submit_song(
        &demo_song(),
        r#"{"system": "group", "dancers": 3, "seed": 1, "end": 10}"#,
    );
    assert_eq!(r.status, 202, "{}", r.json);
    let id = r.json["id"].as_str().unwrap().to_string();
    let job = s.wait(&id, JOB_TIMEOUT);
    assert_eq!(job["state"], "done", "{job}");

    let params = format!(r#"{{"seed": 7, "edit": {{"of": "{id}", "regenerate": [[3, 6]]}}}}"#);
    let r = s.submit(&[("params", None, params.as_bytes())]);
    assert_eq!(r.status, 202, "{}", r.json);
    let eid = r.json["id"].as_str().unwrap().to_string();
    let edited = s.wait(&eid, JOB_TIMEOUT);
    assert_eq!(edited["state"], "done", "{edited}");
    assert_eq!(edited["params"]["system"], "group");
    assert_eq!(edited["dancers"], 3);
    // The group's .npy is (N, T, 24, 3): every dancer's kept frames unchanged.
    let npy = |job: &Value| {
        let bytes = s.download(job["variations"][0]["files"]["npy"].as_str().unwrap());
        dancegen_io::npy::parse_npy(&bytes).unwrap().data
    };
    let (old, new) = (npy(&job), npy(&edited));
    assert_eq!(old.len(), new.len());
    let (frame, frames) = (72, 300);
    assert_eq!(old.len(), 3 * frames * frame);
    for d in 0..3 {
        let at = |f: usize| (d * frames + f) * frame;
        for f in (0..frames).filter(|f| !(90..180).contains(f)) {
            for i in at(f)..at(f + 1) {
                assert!(
                    (old[i] - new[i]).abs() <= 1e-4,
                    "dancer {d}, frame {f} changed"
                );
            }
        }
        let moved = (at(90)..at(180))
            .map(|i| (old[i] - new[i]).abs())
            .fold(0.0, f64::max);
        assert!(
            moved > 0.02,
            "dancer {d}: the range is the old one ({moved} m)"
        );
    }
}

#[test]
fn a_holistic_edit_keeps_the_arms_it_is_asked_to_keep() {
    let s = start(Limits::default());
    let (job, edited) = dance_then_edit(
        &s,
        r#"{"system": "holistic", "seed": 1, "end": 10}"#,
        "arms",
    );
    assert_eq!(edited["params"]["system"], "holistic");
    // The SMPL-H rotations (T, 156) of the .npz each job serves.
    let poses = |job: &Value| {
        let bytes = s.download(job["variations"][0]["files"]["npz"].as_str().unwrap());
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("dance.npz");
        std::fs::write(&path, bytes).unwrap();
        let m = dancegen_io::npz::read_npz_members(&path, &["poses"]).unwrap();
        m[0].1.data.clone()
    };
    let (old, new) = (poses(&job), poses(&edited));
    assert_eq!(old.len(), new.len());
    let frames = old.len() / 156;
    assert_eq!(frames, 300);
    let arms = [13, 14, 16, 17, 18, 19, 20, 21];
    for f in 0..frames {
        let kept = !(90..180).contains(&f);
        for j in 0..52 {
            if kept || arms.contains(&j) {
                for i in f * 156 + 3 * j..f * 156 + 3 * j + 3 {
                    assert!(
                        (old[i] - new[i]).abs() <= 1e-4,
                        "frame {f}, joint {j} changed"
                    );
                }
            }
        }
    }
    let legs = (90..180)
        .flat_map(|f| [1, 2, 4, 5].map(|j| f * 156 + 3 * j))
        .flat_map(|at| at..at + 3)
        .map(|i| (old[i] - new[i]).abs())
        .fold(0.0, f64::max);
    assert!(
        legs > 0.02,
        "the legs of the range are the old ones (they moved {legs} rad at most)"
    );
}

/// `serve --keep-days`: a finished job (done, failed or cancelled) that ended longer ago than
/// the keep time is gone when the server starts, with its files; a recent one stays, and
/// without a keep time nothing is removed (queued jobs never expire: the store's unit test).
#[test]
fn finished_jobs_older_than_the_keep_time_are_removed_at_start() {
    use dancegen_server::job::{JobParams, JobState};
    use dancegen_server::store::{Store, now};
    let data = tempfile::tempdir().unwrap();
    let db = data.path().join("jobs.sqlite3");
    let day = 86_400.0;
    // id, the state it ended in, days since it ended.
    let jobs: [(&str, JobState, f64); 4] = [
        ("olddone", JobState::Done, 40.0),
        ("oldfailed", JobState::Failed, 31.0),
        ("oldcancelled", JobState::Cancelled, 60.0),
        ("recentdone", JobState::Done, 29.0),
    ];
    {
        let (store, _) = Store::open(&db).unwrap();
        let params = JobParams::parse(r#"{"system": "solo"}"#, 4).unwrap();
        for (id, state, _) in &jobs {
            store.insert(id, &params, "song.ogg", None, None).unwrap();
            store.claim().unwrap().unwrap();
            store.finish(id, *state, None, &[]).unwrap();
            let dir = data.path().join("jobs").join(id);
            std::fs::create_dir_all(&dir).unwrap();
            std::fs::write(dir.join("song.ogg"), b"x").unwrap();
        }
    }
    {
        // Back-date them (the store stamps "now").
        let conn = rusqlite::Connection::open(&db).unwrap();
        for (id, _, days) in &jobs {
            let t = now() - days * day;
            conn.execute(
                "UPDATE jobs SET created = ?2, finished = ?2 WHERE id = ?1",
                rusqlite::params![id, t],
            )
            .unwrap();
        }
    }
    let start = |keep: Option<f64>| {
        let mut config = ServeConfig::new(data.path());
        config.addr = "127.0.0.1:0".parse().unwrap();
        config.keep = keep.map(|d| Duration::from_secs_f64(d * day));
        let server = dancegen_server::spawn(config).expect("server starts");
        let client = dancegen_server::client::Client::new(server.url());
        let present: Vec<bool> = jobs
            .iter()
            .map(|(id, ..)| client.get(&format!("/api/jobs/{id}")).unwrap().status == 200)
            .collect();
        server.stop();
        present
    };
    assert_eq!(start(None), [true; 4], "no keep time: every job stays");
    let present = start(Some(30.0));
    for ((id, state, _), here) in jobs.iter().zip(&present) {
        let dir = data.path().join("jobs").join(id);
        let expired = matches!(id, &"olddone" | &"oldfailed" | &"oldcancelled");
        assert_eq!(*here, !expired, "{id} ({state:?})");
        assert_eq!(dir.exists(), !expired, "{id}'s folder");
    }
}

/// "My dances" (issue 45): the library lists the jobs newest first, each finished dance with
/// its picture; a dance can be named (and the name cleared), checked in words; "again" makes a
/// new job from a finished one with its song and settings and another seed; an edited version
/// or an unknown job cannot be made again.
#[test]
fn the_library_lists_names_and_makes_a_dance_again() {
    let s = start(Limits::default());
    let first = s.submit_song(&demo_song(), r#"{"seed": 3, "end": 4}"#);
    assert_eq!(first.status, 202, "{}", first.json);
    let id = first.json["id"].as_str().unwrap().to_string();
    let done = s.wait(&id, Duration::from_secs(600));
    assert_eq!(done["state"], "done", "{done}");
    let thumb = done["thumbnail"]
        .as_str()
        .expect("a finished dance has a picture");
    let png = s.download(thumb);
    assert!(png.starts_with(b"\x89PNG"), "the picture is a PNG");

    let named = s.send_json(
        "PATCH",
        &format!("/api/jobs/{id}"),
        r#"{"name": "  Warm-up  "}"#,
    );
    assert_eq!(named.status, 200, "{}", named.json);
    assert_eq!(named.json["name"], "Warm-up");
    let bad = s.send_json(
        "PATCH",
        &format!("/api/jobs/{id}"),
        &format!(r#"{{"name": "{}"}}"#, "x".repeat(81)),
    );
    assert_eq!(
        (bad.status, bad.json["field"].as_str()),
        (400, Some("name")),
        "{}",
        bad.json
    );
    assert_eq!(
        s.send_json("PATCH", "/api/jobs/nosuchjob", r#"{"name": "x"}"#)
            .status,
        404
    );

    let again = s.send_json("POST", &format!("/api/jobs/{id}/again"), r#"{"seed": 9}"#);
    assert_eq!(again.status, 202, "{}", again.json);
    let id2 = again.json["id"].as_str().unwrap().to_string();
    let done2 = s.wait(&id2, Duration::from_secs(600));
    assert_eq!(done2["state"], "done", "{done2}");
    assert_eq!(done2["params"]["seed"], 9);
    assert_eq!(done2["params"]["end"], done["params"]["end"]);
    assert_eq!(done2["params"]["song_title"], done["params"]["song_title"]);
    assert_eq!(
        s.download(done2["song"].as_str().unwrap()),
        std::fs::read(demo_song()).unwrap(),
        "the same song"
    );
    assert_eq!(done2["name"], Value::Null, "a new dance has no name yet");

    let list = s.get("/api/jobs");
    assert_eq!(list.status, 200, "{}", list.json);
    let ids: Vec<&str> = list.json["jobs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|j| j["id"].as_str().unwrap())
        .collect();
    assert_eq!(ids, [id2.as_str(), id.as_str()], "newest first");
    assert_eq!(list.json["jobs"][1]["name"], "Warm-up");
    // Cleared, the song's name shows again.
    let cleared = s.send_json("PATCH", &format!("/api/jobs/{id}"), r#"{"name": ""}"#);
    assert_eq!(cleared.json["name"], Value::Null);
    assert_eq!(
        s.send_json("POST", "/api/jobs/nosuchjob/again", "{}")
            .status,
        404
    );
    let bad_seed = s.send_json("POST", &format!("/api/jobs/{id}/again"), r#"{"seed": -1}"#);
    assert_eq!(
        (bad_seed.status, bad_seed.json["field"].as_str()),
        (400, Some("seed")),
        "{}",
        bad_seed.json
    );
    // Deleted, it leaves the library.
    assert_eq!(s.delete(&format!("/api/jobs/{id}")).status, 204);
    let after = s.get("/api/jobs");
    assert_eq!(after.json["jobs"].as_array().unwrap().len(), 1);
}

/// The rig choice (issue 45): a job asked with `"rig": "mixamo"` names the bones of its
/// `.bvh`, `.fbx` and `.glb` as Mixamo does, and an unknown rig is refused naming the choices.
#[test]
fn a_job_names_its_bones_for_the_chosen_rig() {
    let s = start(Limits::default());
    let bad = s.submit_song(&demo_song(), r#"{"rig": "maya"}"#);
    assert_eq!(
        (bad.status, bad.json["field"].as_str()),
        (400, Some("rig")),
        "{}",
        bad.json
    );
    assert!(
        bad.json["error"].as_str().unwrap().contains("mixamo"),
        "{}",
        bad.json
    );
    let r = s.submit_song(&demo_song(), r#"{"seed": 1, "end": 4, "rig": "mixamo"}"#);
    assert_eq!(r.status, 202, "{}", r.json);
    let id = r.json["id"].as_str().unwrap();
    let job = s.wait(id, Duration::from_secs(600));
    assert_eq!(job["state"], "done", "{job}");
    assert_eq!(job["params"]["rig"], "mixamo");
    let files = &job["variations"][0]["files"];
    let has_hips = |kind: &str| {
        let bytes = s.download(files[kind].as_str().unwrap());
        bytes.windows(14).any(|w| w == b"mixamorig:Hips")
    };
    for kind in ["bvh", "fbx", "glb"] {
        assert!(has_hips(kind), "the .{kind} has no bone mixamorig:Hips");
    }
}

/// The three.js robot (CC0), a character with its own bone names, two skins and rigid parts.
fn robot() -> Vec<u8> {
    std::fs::read(shared().join("data/holistic/three-js-robot-expressive/RobotExpressive.glb"))
        .unwrap()
}

/// A GLB's JSON chunk and its binary chunk.
fn glb_parts(bytes: &[u8]) -> (Value, Vec<u8>) {
    let len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let json = serde_json::from_slice(&bytes[20..20 + len]).unwrap();
    (json, bytes[20 + len..].to_vec())
}

/// A GLB of `json` and the binary chunk (with its header) `bin`.
fn glb_of(json: &Value, bin: &[u8]) -> Vec<u8> {
    let mut text = serde_json::to_vec(json).unwrap();
    while !text.len().is_multiple_of(4) {
        text.push(b' ');
    }
    let mut glb = b"glTF".to_vec();
    glb.extend_from_slice(&2u32.to_le_bytes());
    glb.extend_from_slice(&((20 + text.len() + bin.len()) as u32).to_le_bytes());
    glb.extend_from_slice(&(text.len() as u32).to_le_bytes());
    glb.extend_from_slice(b"JSON");
    glb.extend_from_slice(&text);
    glb.extend_from_slice(bin);
    glb
}

/// The character upload (issue 45): a solo job with the robot makes a `.glb` that is the robot
/// (its nodes, meshes and skins) dancing the job's dance, with the SMPL joints' nodes named
/// for the viewer, while the other files are the dance itself; an edit and "again" keep the
/// character. A character that cannot dance is refused at upload in `generate --character`'s
/// words, naming the field: not glTF, no humanoid bones, a file reached outside the upload,
/// several dancers, the wrong format.
#[test]
fn a_job_dances_on_the_uploaded_character() {
    let s = start(Limits::default());
    let song = std::fs::read(demo_song()).unwrap();
    let with = |params: &str, name: &str, character: &[u8]| {
        s.submit(&[
            ("params", None, params.as_bytes()),
            ("song", Some("demo.wav"), &song),
            ("character", Some(name), character),
        ])
    };
    let refused = |r: &Reply, words: &str| {
        assert_eq!(
            (r.status, r.json["field"].as_str()),
            (400, Some("character")),
            "{}",
            r.json
        );
        let e = error_of(r);
        assert!(e.contains(words), "{e}");
        assert!(!e.contains("/jobs/"), "the server's path: {e}");
    };
    refused(&with("{}", "hero.glb", b"not a model"), "not a glTF");
    refused(&with("{}", "hero.fbx", &robot()), ".glb or .vrm");
    refused(&with("{}", "hero.glb", b""), "empty");
    refused(
        &with(
            r#"{"system": "group", "dancers": 3}"#,
            "robot.glb",
            &robot(),
        ),
        "solo or holistic",
    );
    // Bones that are not a humanoid's: the robot's renamed bone0, bone1, …
    let (json, bin) = glb_parts(&robot());
    let mut anonymous = json.clone();
    for (i, node) in anonymous["nodes"]
        .as_array_mut()
        .unwrap()
        .iter_mut()
        .enumerate()
    {
        node["name"] = format!("bone{i}").into();
    }
    refused(&with("{}", "anon.glb", &glb_of(&anonymous, &bin)), "bone3");
    // An image naming a file: on a server it could be any file there, so it is not read.
    let mut reaching = json.clone();
    reaching["images"] = serde_json::json!([{"uri": "../../song.wav"}]);
    refused(
        &with("{}", "reach.glb", &glb_of(&reaching, &bin)),
        "external file",
    );

    let r = with(r#"{"seed": 2, "end": 5}"#, "RobotExpressive.glb", &robot());
    assert_eq!(r.status, 202, "{}", r.json);
    let id = r.json["id"].as_str().unwrap().to_string();
    let job = s.wait(&id, JOB_TIMEOUT);
    assert_eq!(job["state"], "done", "{job}");
    assert_eq!(job["params"]["character"], "character.glb");
    let is_robot = |job: &Value| {
        let files = &job["variations"][0]["files"];
        let (out, _) = glb_parts(&s.download(files["glb"].as_str().unwrap()));
        for key in ["nodes", "meshes", "skins"] {
            assert_eq!(
                out[key].as_array().map(Vec::len),
                json[key].as_array().map(Vec::len)
            );
        }
        let anim = &out["animations"][0];
        assert_eq!(anim["name"], "dance");
        let nodes = anim["extras"]["dancegen_smpl_nodes"].as_array().unwrap();
        assert_eq!(
            out["nodes"][nodes[15].as_u64().unwrap() as usize]["name"],
            "Head"
        );
        // The joints file is the dance, not the character.
        let npy = dancegen_io::npy::parse_npy(&s.download(files["npy"].as_str().unwrap())).unwrap();
        assert_eq!(&npy.shape[1..], &[24, 3]);
    };
    is_robot(&job);

    // An edit of it is the robot again; so is the dance made again with another seed.
    let edit = format!(r#"{{"seed": 7, "edit": {{"of": "{id}", "regenerate": [[1, 3]]}}}}"#);
    let r = s.submit(&[("params", None, edit.as_bytes())]);
    assert_eq!(r.status, 202, "{}", r.json);
    let edited = s.wait(r.json["id"].as_str().unwrap(), JOB_TIMEOUT);
    assert_eq!(edited["state"], "done", "{edited}");
    is_robot(&edited);
    let r = s.send_json("POST", &format!("/api/jobs/{id}/again"), r#"{"seed": 3}"#);
    assert_eq!(r.status, 202, "{}", r.json);
    let again = s.wait(r.json["id"].as_str().unwrap(), JOB_TIMEOUT);
    assert_eq!(again["state"], "done", "{again}");
    is_robot(&again);
    // An edit brings no character of its own.
    let r = s.submit(&[
        ("params", None, edit.as_bytes()),
        ("character", Some("robot.glb"), &robot()),
    ]);
    assert_eq!(
        (r.status, r.json["field"].as_str()),
        (400, Some("character"))
    );
}
