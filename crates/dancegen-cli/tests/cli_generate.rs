//! The `generate` contract with the bundled Lodge++ model: output files and their layout
//! (`.npy` = world joints (T, 24, 3), metres, Y-up, 30 fps), the length rules, and clear errors.

mod common;

use common::*;

fn song() -> String {
    shared()
        .join("data/music/sectoid/feelings.ogg")
        .to_str()
        .unwrap()
        .to_string()
}

/// `(T, 24, 3)` joints of a generated `.npy`.
fn joints(path: &std::path::Path) -> (usize, Vec<f64>) {
    let a = dancegen_io::read_npy(path).unwrap();
    assert_eq!(a.shape.len(), 3, "{:?}", a.shape);
    assert_eq!(&a.shape[1..], &[24, 3]);
    (a.shape[0], a.data)
}

#[test]
fn generates_every_format_for_a_song_segment() {
    let dir = tempfile::tempdir().unwrap();
    let out = |n: &str| dir.path().join(n).to_str().unwrap().to_string();
    let o = dancegen(&[
        "-q",
        "generate",
        &song(),
        "--start",
        "20",
        "--end",
        "30",
        "--seed",
        "3",
        "--steps",
        "20",
        "-o",
        &out("d.npy"),
        "-o",
        &out("d.glb"),
        "-o",
        &out("d.bvh"),
        "-o",
        &out("d.npz"),
        "-o",
        &out("d.json"),
    ]);
    ok(&o);
    let (t, j) = joints(&dir.path().join("d.npy"));
    assert_eq!(t, 300, "10 s at 30 fps");
    assert!(j.iter().all(|v| v.is_finite()));
    for f in 0..t {
        let y = |k: usize| j[(f * 24 + k) * 3 + 1];
        // Feet never below the floor; the pelvis above it.
        let low = [7, 8, 10, 11]
            .map(y)
            .into_iter()
            .fold(f64::INFINITY, f64::min);
        assert!(low > -1e-4, "frame {f}: foot at {low}");
        assert!(y(0) > 0.3, "frame {f}: pelvis at {}", y(0));
        // Right way up: the neck above the pelvis (the v2/v3 retrains stood on their heads,
        // docs/solo-data-v2.md).
        assert!(
            y(12) > y(0),
            "frame {f}: upside down (neck {} below pelvis {})",
            y(12),
            y(0)
        );
        // Stays on stage: within a 6 m square around the origin.
        assert!(j[f * 72].abs() < 3.0 && j[f * 72 + 2].abs() < 3.0);
    }
    // Standing on the floor, not hovering: the lowest foot is near 0 in most frames (the
    // grounded training clips have a median lowest-foot height of ~0.01 m; 0.08 m would be a
    // visible hover).
    let mut lows: Vec<f64> = (0..t)
        .map(|f| {
            [7, 8, 10, 11]
                .map(|k| j[(f * 24 + k) * 3 + 1])
                .into_iter()
                .fold(f64::INFINITY, f64::min)
        })
        .collect();
    lows.sort_by(f64::total_cmp);
    assert!(lows[t / 2] < 0.08, "median lowest foot {}", lows[t / 2]);
    for f in ["d.glb", "d.bvh", "d.npz", "d.json"] {
        let m = std::fs::metadata(dir.path().join(f)).unwrap();
        assert!(m.len() > 1000, "{f}");
    }
    // The npz and the npy describe the same dance (up to FK of float32-stored poses: < 1 mm).
    let back = dir.path().join("back.npy");
    ok(&dancegen(&[
        "-q",
        "convert",
        &out("d.npz"),
        "-o",
        back.to_str().unwrap(),
    ]));
    let (t2, j2) = joints(&back);
    assert_eq!(t2, t);
    let err = j
        .iter()
        .zip(&j2)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(err < 1e-3, "npz vs npy joints differ by {err}");
}

#[test]
fn same_seed_same_dance_other_seed_other_dance() {
    let dir = tempfile::tempdir().unwrap();
    let run = |seed: &str, name: &str| {
        let p = dir.path().join(name);
        ok(&dancegen(&[
            "-q",
            "generate",
            &song(),
            "--start",
            "60",
            "--end",
            "64.5",
            "--steps",
            "10",
            "--seed",
            seed,
            "-o",
            p.to_str().unwrap(),
        ]));
        joints(&p).1
    };
    let a = run("1", "a.npy");
    let b = run("1", "b.npy");
    let c = run("2", "c.npy");
    assert_eq!(a, b);
    assert_ne!(a, c);
    assert_eq!(a.len(), 135 * 72);
}

#[test]
fn unknown_genre_lists_the_choices() {
    let o = dancegen(&["-q", "generate", &song(), "--end", "3", "--genre", "polka"]);
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(e.contains("polka") && e.contains("salsa"), "{e}");
}

#[test]
fn short_songs_and_bad_files_are_clear_errors() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.npy");
    let o = dancegen(&[
        "-q",
        "generate",
        &song(),
        "--start",
        "10",
        "--end",
        "11.5",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("at least 2"), "{}", stderr(&o));
    let bad = dir.path().join("not_audio.mp3");
    std::fs::write(&bad, b"this is not audio").unwrap();
    let o = dancegen(&[
        "-q",
        "generate",
        bad.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("not_audio.mp3"), "{}", stderr(&o));
    assert!(!out.exists(), "no output on failure");
}

/// A song without a beat (here 12 s of silence) is danced, with a warning on stderr that says
/// so; a song with a beat gets none.
#[test]
fn a_song_without_a_beat_is_danced_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let silent = dir.path().join("silence.wav");
    let spec = hound::WavSpec {
        channels: 1,
        sample_rate: 22_050,
        bits_per_sample: 16,
        sample_format: hound::SampleFormat::Int,
    };
    let mut w = hound::WavWriter::create(&silent, spec).unwrap();
    for _ in 0..12 * 22_050 {
        w.write_sample(0i16).unwrap();
    }
    w.finalize().unwrap();
    let out = dir.path().join("x.npy");
    let o = dancegen(&[
        "-q",
        "generate",
        silent.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    ok(&o);
    assert!(out.exists());
    let err = stderr(&o);
    assert!(
        err.contains("warning: no beat was found in the music from 0.0 to 12.0 s"),
        "{err}"
    );
    let o = dancegen(&[
        "-q",
        "generate",
        &song(),
        "--start",
        "10",
        "--end",
        "16",
        "-o",
        out.to_str().unwrap(),
    ]);
    ok(&o);
    assert!(!stderr(&o).contains("warning"), "{}", stderr(&o));
}

/// The MP4 of a dance keeps the song's stereo, cut to the danced span: the sound is the
/// song's own file decoded by ffmpeg from `--start` for the dance's length (it used to be a
/// mono WAV of the analysis decode).
#[test]
fn the_video_keeps_the_songs_stereo_for_the_danced_span() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("v.mp4");
    let o = dancegen(&[
        "-q",
        "generate",
        &song(),
        "--start",
        "10",
        "--end",
        "14",
        "-o",
        out.to_str().unwrap(),
    ]);
    ok(&o);
    let probe = std::process::Command::new("ffprobe")
        .args(["-v", "error", "-select_streams", "a:0"])
        .args([
            "-show_entries",
            "stream=channels,duration",
            "-of",
            "csv=p=0",
        ])
        .arg(&out)
        .output()
        .expect("ffprobe comes with ffmpeg (tools/test.sh installs it)");
    let text = String::from_utf8_lossy(&probe.stdout);
    let fields: Vec<&str> = text.trim().split(',').collect();
    assert_eq!(fields.first(), Some(&"2"), "audio stream: {text}");
    let seconds: f64 = fields[1].parse().unwrap();
    assert!(
        (seconds - 4.0).abs() < 0.1,
        "the sound lasts {seconds} s: {text}"
    );
    // 640 × 480 unless 1280 × 720 is asked for; another size is refused, naming the choices.
    let size = |path: &std::path::Path| {
        let o = std::process::Command::new("ffprobe")
            .args(["-v", "error", "-select_streams", "v:0"])
            .args(["-show_entries", "stream=width,height", "-of", "csv=p=0"])
            .arg(path)
            .output()
            .unwrap();
        String::from_utf8_lossy(&o.stdout).trim().to_string()
    };
    assert_eq!(size(&out), "640,480");
    let hd = dir.path().join("hd.mp4");
    ok(&dancegen(&[
        "-q",
        "generate",
        &song(),
        "--start",
        "10",
        "--end",
        "12",
        "--video-size",
        "1280x720",
        "-o",
        hd.to_str().unwrap(),
    ]));
    assert_eq!(size(&hd), "1280,720");
    let o = dancegen(&[
        "-q",
        "generate",
        &song(),
        "--video-size",
        "4k",
        "-o",
        "x.mp4",
    ]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("choose 640x480 or 1280x720"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn missing_model_files_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let o = dancegen(&[
        "-q",
        "generate",
        &song(),
        "--end",
        "3",
        "--model",
        dir.path().to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(e.contains("model.toml") && e.contains("missing"), "{e}");
}

/// A 5-minute song (feelings + the start of escape_from_chaosland, 22.05 kHz mono WAV) danced
/// to its full length: no NaNs, on stage, feet on the floor. Few denoising steps keep it quick;
/// the long-form placement and stage keeping are what is tested.
#[test]
fn five_minute_song_full_length_on_stage() {
    let dir = tempfile::tempdir().unwrap();
    let wav = dir.path().join("five_minutes.wav");
    let sr = 22050;
    let mut samples = Vec::new();
    for name in ["feelings.ogg", "escape_from_chaosland.ogg"] {
        let src = dancegen_music::decode::AudioSource::File(
            shared().join("data/music/sectoid").join(name),
        );
        let a = dancegen_music::load::load_many(&src, &[sr], |_| {}).unwrap();
        samples.extend_from_slice(&a[0].samples);
    }
    samples.truncate(300 * sr as usize);
    let spec = hound::WavSpec {
        channels: 1,
        sample_rate: sr,
        bits_per_sample: 16,
        sample_format: hound::SampleFormat::Int,
    };
    let mut w = hound::WavWriter::create(&wav, spec).unwrap();
    for s in &samples {
        w.write_sample((s.clamp(-1.0, 1.0) * 32767.0) as i16)
            .unwrap();
    }
    w.finalize().unwrap();
    let out = dir.path().join("long.npy");
    ok(&dancegen(&[
        "-q",
        "generate",
        wav.to_str().unwrap(),
        "--steps",
        "4",
        "-o",
        out.to_str().unwrap(),
    ]));
    let (t, j) = joints(&out);
    assert_eq!(t, 9000);
    assert!(j.iter().all(|v| v.is_finite()));
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for f in 0..t {
        for (k, c) in [0usize, 2].into_iter().enumerate() {
            lo[k] = lo[k].min(j[f * 72 + c]);
            hi[k] = hi[k].max(j[f * 72 + c]);
        }
        let low = [7, 8, 10, 11]
            .map(|k| j[(f * 24 + k) * 3 + 1])
            .into_iter()
            .fold(f64::INFINITY, f64::min);
        assert!(low > -1e-4, "frame {f}: foot at {low}");
    }
    println!(
        "root x {:.2}..{:.2} m, z {:.2}..{:.2} m",
        lo[0], hi[0], lo[1], hi[1]
    );
    assert!(
        lo.iter().chain(&hi).all(|v| v.abs() < 3.0),
        "left the 6 m stage"
    );
}

#[test]
fn json_progress_grows_to_one_on_stderr() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("p.npy");
    let o = dancegen(&[
        "generate",
        &song(),
        "--start",
        "5",
        "--end",
        "9",
        "--steps",
        "3",
        "--progress",
        "json",
        "-o",
        out.to_str().unwrap(),
    ]);
    ok(&o);
    let reports: Vec<serde_json::Value> = stderr(&o)
        .lines()
        .filter(|l| l.starts_with('{'))
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("{l}: {e}")))
        .collect();
    assert!(reports.len() > 5, "{reports:?}");
    let fractions: Vec<f64> = reports
        .iter()
        .map(|r| r["fraction"].as_f64().unwrap())
        .collect();
    assert!(fractions.windows(2).all(|w| w[1] >= w[0]), "{fractions:?}");
    let last = reports.last().unwrap();
    assert_eq!(last["fraction"].as_f64(), Some(1.0));
    assert_eq!(last["stage"], "done");
    for r in &reports {
        assert!(r["stage"].is_string() && r.get("eta_s").is_some(), "{r}");
    }
    assert!(reports.iter().any(|r| r["stage"] == "denoising"));
    // The stdout summary is unchanged by the progress mode.
    let said = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(
        said.contains("generated in") && said.contains("p.npy"),
        "{said}"
    );
}

#[test]
fn systems_are_chosen_by_name_with_clear_errors() {
    // The holistic model dances to the music alone: a genre is refused, by name.
    let o = dancegen(&[
        "-q",
        "generate",
        &song(),
        "--end",
        "3",
        "--system",
        "holistic",
        "--genre",
        "salsa",
    ]);
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(
        e.contains("--genre salsa") && e.contains("no genres"),
        "{e}"
    );
    // A face mapping needs a face.
    let o = dancegen(&[
        "-q",
        "generate",
        &song(),
        "--end",
        "3",
        "--flame-mapping",
        "m.npy",
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("--system holistic"), "{}", stderr(&o));
    // Shipped, but a group needs its size.
    let o = dancegen(&["-q", "generate", &song(), "--end", "3", "--system", "group"]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("--dancers"), "{}", stderr(&o));
    let o = dancegen(&["-q", "generate", &song(), "--end", "3", "--system", "polka"]);
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(e.contains("solo") && e.contains("holistic"), "{e}");
    let o = dancegen(&["-q", "generate", &song(), "--end", "3", "--system", "duet"]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("--leader"), "{}", stderr(&o));
}
