//! The viewer in a real browser: headless Chromium (Debian's, driven by `puppeteer-core` from
//! npm through `tests/browser/viewer_check.mjs`) opens a finished job's page from a server on
//! 127.0.0.1, seeks the song to 1, 2 and 5 s, and the joint world positions read from the
//! three.js scene must equal the job's `.npy` frames within 1e-5 m — for a solo and for both
//! dancers of a duet. Playing 1 s must advance the song and the pose, every request must stay
//! on the host, and the page must log no error.
//!
//! Needs `/usr/bin/chromium` and `npm ci` run in `tests/browser` (`tools/test.sh` does both);
//! the screenshots are kept under the target folder (`viewer-shots/`) for a person to look at.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

use crate::common::{TestServer, demo_song, shared, start};
use dancegen_io::npy::{NpyArray, parse_npy};
use dancegen_server::Limits;
use serde_json::Value;

/// The issue's tolerance between the scene's joints and the `.npy` (metres).
const TOLERANCE_M: f32 = 1e-5;
const SEEK_TIMES: [u32; 3] = [1, 2, 5];
const FPS: u32 = 30;
const JOB_TIMEOUT: Duration = Duration::from_secs(900);

fn browser_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/browser")
}

fn check_prerequisites() {
    assert!(
        Path::new("/usr/bin/chromium").exists(),
        "this test needs Chromium at /usr/bin/chromium (Debian: apt-get install chromium; \
         tools/test.sh installs it)"
    );
    assert!(
        browser_dir().join("node_modules/puppeteer-core").is_dir(),
        "this test needs puppeteer-core in {}: run `npm ci --prefix {}` (tools/test.sh does)",
        browser_dir().display(),
        browser_dir().display()
    );
}

/// The first `seconds` of a BVH (its header and that many frames), as a shorter real take.
fn trimmed_bvh(path: &Path, seconds: f64) -> Vec<u8> {
    let text = std::fs::read_to_string(path).unwrap();
    let (header, motion) = text.split_once("MOTION").unwrap();
    let mut lines = motion.lines().filter(|l| !l.trim().is_empty());
    let _frames = lines.next().unwrap();
    let frame_time_line = lines.next().unwrap();
    let dt: f64 = frame_time_line
        .split(':')
        .nth(1)
        .unwrap()
        .trim()
        .parse()
        .unwrap();
    let keep = (seconds / dt).round() as usize;
    let rows: Vec<&str> = lines.take(keep).collect();
    let mut out = format!(
        "{header}MOTION\nFrames: {}\n{frame_time_line}\n",
        rows.len()
    );
    for r in rows {
        out.push_str(r);
        out.push('\n');
    }
    out.into_bytes()
}

/// `node`, with the owner secret of the jobs the test's client made in
/// `DANCEGEN_OWNER_SECRET`: the page then acts as the browser that made them
/// (`chromium.mjs`'s `ownedPage`).
fn node_as_owner(s: &TestServer) -> Command {
    let mut node = Command::new("node");
    if let Some(secret) = s.client.token() {
        node.env("DANCEGEN_OWNER_SECRET", secret);
    }
    node
}

/// Runs the browser driver on job `id`; its JSON report.
fn view(s: &TestServer, id: &str, name: &str) -> Value {
    let shots = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("viewer-shots")
        .join(name);
    let out = node_as_owner(s)
        .arg(browser_dir().join("viewer_check.mjs"))
        .arg(s.server.url())
        .arg(id)
        .arg(&shots)
        .output()
        .expect("this test needs node (Node.js) on the PATH");
    assert!(
        out.status.success(),
        "viewer_check failed for the {name} job:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let report: Value = serde_json::from_slice(&out.stdout).unwrap_or_else(|e| {
        panic!(
            "viewer_check printed no JSON ({e}):\n{}",
            String::from_utf8_lossy(&out.stdout)
        )
    });
    let a = std::fs::read(shots.join("shot_1.png")).expect("screenshot at 1 s");
    let b = std::fs::read(shots.join("shot_5.png")).expect("screenshot at 5 s");
    assert_ne!(a, b, "{name}: the screenshots at 1 s and 5 s are the same");
    println!("{name}: screenshots in {}", shots.display());
    report
}

fn npy(bytes: &[u8]) -> NpyArray {
    parse_npy(bytes).unwrap_or_else(|e| panic!("the job's .npy: {e}"))
}

/// Largest distance between the scene's joints of one dancer at `t` and frame `t·30` of a
/// `(T, 24, 3)` `.npy`.
fn max_error(scene: &Value, npy: &NpyArray, t: u32) -> f32 {
    assert_eq!(npy.dtype, "<f4", "the job's .npy is float32");
    let (shape, data) = (&npy.shape, &npy.data);
    assert_eq!(&shape[1..], &[24, 3], "npy shape {shape:?}");
    let frame = (t * FPS) as usize;
    assert!(
        frame < shape[0],
        "frame {frame} beyond the npy's {}",
        shape[0]
    );
    let joints = scene.as_array().expect("joints of a dancer");
    assert_eq!(joints.len(), 24);
    let mut worst = 0f32;
    for (j, p) in joints.iter().enumerate() {
        for k in 0..3 {
            let x = p[k].as_f64().unwrap() as f32;
            worst = worst.max((x - data[(frame * 24 + j) * 3 + k] as f32).abs());
        }
    }
    worst
}

/// What every page must satisfy: no error, and every request to the server's own host.
fn check_requests(report: &Value, base: &str, name: &str) {
    let errors = report["errors"].as_array().unwrap();
    assert!(errors.is_empty(), "{name}: page errors {errors:?}");
    for url in report["requests"].as_array().unwrap() {
        let url = url.as_str().unwrap();
        assert!(
            url.starts_with(&format!("{base}/")) || url.starts_with("data:"),
            "{name}: a request left the host: {url}"
        );
    }
}

/// [`check_requests`], and playing moves the song and the dancers.
fn check_page(report: &Value, base: &str, name: &str) {
    check_requests(report, base, name);
    let play = &report["play"];
    let (t0, t1) = (play["t0"].as_f64().unwrap(), play["t1"].as_f64().unwrap());
    assert!(
        t1 > t0 + 0.3,
        "{name}: 1 s of play moved the song from {t0} to {t1}"
    );
    assert!(
        play["moved"].as_f64().unwrap() > 1e-3,
        "{name}: the dancers did not move while playing: {play}"
    );
}

/// The playback controls (issue 45): speeds 0.25× to 2× set the song's rate, Loop starts the
/// dance again when it ends (played from 0.4 s before its end for 1.2 s, the song is back
/// near its start and still playing), and Full screen gives the variations the screen.
fn check_controls(report: &Value, name: &str) {
    let c = &report["controls"];
    let speeds: Vec<f64> = c["speeds"]
        .as_array()
        .unwrap_or_else(|| panic!("{name}: no speeds: {c}"))
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    assert_eq!(speeds, [0.25, 0.5, 1.0, 1.5, 2.0], "{name}: {c}");
    assert_eq!(c["rate"].as_f64(), Some(2.0), "{name}: {c}");
    let lp = &c["loop"];
    assert_eq!(lp["paused"], false, "{name}: the loop stopped: {lp}");
    assert!(
        lp["time"].as_f64().unwrap() < 1.5,
        "{name}: no loop back to the start: {lp}"
    );
    if c["fullscreenEnabled"] == true {
        assert_eq!(c["fullscreen"], "variations-box", "{name}: {c}");
    }
}

/// What the viewer draws besides the skinned bodies (issue 45), at 1 s of the first variation:
/// a head over every dancer's head joint, a contact shadow on the floor under every dancer's
/// supporting feet (the mean floor position of the scene's joints within 5 cm of its lowest one,
/// read at the same moment; paler the higher that joint), and the legend: in a duet naming the
/// given leader and the generated partner, in a group each dancer by number.
fn check_figures(report: &Value, name: &str, dancers: usize) {
    let f = &report["figures"][0];
    let arr = |k: &str| {
        f[k].as_array()
            .unwrap_or_else(|| panic!("{name}: no {k}: {f}"))
            .clone()
    };
    let (heads, shadows, pelvis, lowest) =
        (arr("heads"), arr("shadows"), arr("pelvis"), arr("lowest"));
    // The scene's joints at the same moment (the figures are read at the first seek time).
    let scene = report["joints"][SEEK_TIMES[0].to_string()][0]
        .as_array()
        .unwrap_or_else(|| panic!("{name}: no joints at {} s", SEEK_TIMES[0]))
        .clone();
    assert_eq!(heads.len(), dancers, "{name}: heads {f}");
    assert_eq!(shadows.len(), dancers, "{name}: shadows {f}");
    let v = |x: &Value, i: usize| x[i].as_f64().unwrap();
    for d in 0..dancers {
        // The head is the highest thing of its dancer, above the pelvis.
        assert!(
            v(&heads[d], 1) > v(&pelvis[d], 1) + 0.3,
            "{name} dancer {d}: head {f}"
        );
        check_shadow(
            f,
            &shadows[d],
            &scene[d],
            lowest[d].as_f64().unwrap(),
            name,
            d,
        );
    }
    let legend: Vec<&str> = f["legend"]
        .as_array()
        .unwrap()
        .iter()
        .map(|l| l.as_str().unwrap())
        .collect();
    if name == "duet" {
        assert_eq!(
            legend,
            ["Leader (given)", "Partner (generated)"],
            "{name}: {f}"
        );
    } else if name == "group" {
        let want: Vec<String> = (1..=dancers).map(|d| format!("Dancer {d}")).collect();
        assert_eq!(legend, want, "{name}: {f}");
    } else {
        assert!(
            legend.is_empty(),
            "{name}: a solo dance needs no legend: {f}"
        );
    }
}

/// Dancer `d`'s contact shadow `s` (figures `f`): exactly (1e-4 m) at the mean floor position
/// of its joints `joints` within 5 cm of the lowest, on the floor, and paler the higher the
/// lowest joint (`lowest` m) is.
fn check_shadow(f: &Value, s: &Value, joints: &Value, lowest: f64, name: &str, d: usize) {
    let v = |x: &Value, i: usize| x[i].as_f64().unwrap();
    let at = &s["at"];
    let joints = joints.as_array().unwrap();
    let low = joints.iter().map(|j| v(j, 1)).fold(f64::MAX, f64::min);
    let feet: Vec<&Value> = joints.iter().filter(|j| v(j, 1) <= low + 0.05).collect();
    let mean = |k: usize| feet.iter().map(|j| v(j, k)).sum::<f64>() / feet.len() as f64;
    let off = (v(at, 0) - mean(0)).hypot(v(at, 2) - mean(2));
    assert!(
        off < 1e-4,
        "{name} dancer {d}: the shadow is {off} m from under the supporting feet: {f}"
    );
    assert!(
        v(at, 1).abs() < 0.01,
        "{name} dancer {d}: the shadow is off the floor: {f}"
    );
    let height = lowest.max(0.0);
    let opacity = s["opacity"].as_f64().unwrap();
    let want = 0.5 * (1.0 - 0.75 * (height / 0.5).min(1.0));
    assert!(
        (opacity - want).abs() < 1e-6,
        "{name} dancer {d}: opacity {opacity} at {height} m: {f}"
    );
}

/// The camera as the page opens (issue 45): following the dancers, with every joint of every
/// dancer in the picture at 1 s and at 5 s, and the target keeping its place over their root
/// centroid on the floor (1e-4 m) in between.
fn check_follow(report: &Value, name: &str) {
    let f = &report["follow"];
    let v = |x: &Value, i: usize| x[i].as_f64().unwrap();
    let offset = |c: &Value| {
        assert_eq!(
            c["following"], true,
            "{name}: not following as the page opens: {f}"
        );
        assert_eq!(
            c["headInView"], true,
            "{name}: the head is out of the picture: {f}"
        );
        assert_eq!(
            c["jointsInView"], c["joints"],
            "{name}: joints out of the picture: {f}"
        );
        [
            v(&c["target"], 0) - v(&c["centroid"], 0),
            v(&c["target"], 2) - v(&c["centroid"], 2),
        ]
    };
    let (a, b) = (offset(&f["1"]), offset(&f["5"]));
    let drift = (a[0] - b[0]).hypot(a[1] - b[1]);
    assert!(
        drift < 1e-4,
        "{name}: the camera left the dancers by {drift} m: {f}"
    );
    let front = &report["views"]["front"];
    assert_eq!(
        front["following"], false,
        "{name}: Front is a fixed view: {front}"
    );
    println!(
        "{name}: camera {:.2} m from the head when following, {:.2} m in Front",
        f["1"]["distance"].as_f64().unwrap(),
        front["distance"].as_f64().unwrap(),
    );
}

/// A phone-sized page (issue 45): the variations stack, one under the other, and scrolled past
/// them to the end of the page, Play and the scrub bar are still on the screen, uncovered.
fn check_phone(report: &Value, name: &str) {
    let p = &report["phone"];
    let canvases = p["canvases"]
        .as_array()
        .unwrap_or_else(|| panic!("{name}: {p}"));
    let at = |c: &Value, i: usize| c[i].as_f64().unwrap();
    for pair in canvases.windows(2) {
        assert!(
            at(&pair[1], 0) >= at(&pair[0], 1),
            "{name}: the variations are not stacked on a phone: {p}"
        );
    }
    assert!(
        p["scrolled"].as_f64().unwrap() > 0.0,
        "{name}: nothing to scroll: {p}"
    );
    let height = p["height"].as_f64().unwrap();
    for id in ["play", "scrub"] {
        let c = &p[id];
        assert!(
            c["top"].as_f64().unwrap() >= 0.0 && c["bottom"].as_f64().unwrap() <= height,
            "{name}: {id} is off the phone's screen: {p}"
        );
        assert_eq!(c["onTop"], true, "{name}: {id} is covered: {p}");
    }
}

/// The timeline under the scrub bar (issue 45): shown, with the job's waveform (800 slices)
/// and beats (the demo song has a steady beat: more than one a second, inside the dance),
/// and painted.
fn check_timeline(report: &Value, job: &Value, name: &str) {
    let t = &report["timeline"];
    assert!(
        job["timeline"].is_string(),
        "{name}: the job has no timeline: {job}"
    );
    assert_eq!(t["shown"], true, "{name}: {t}");
    assert_eq!(t["peaks"], 800, "{name}: {t}");
    let duration = t["duration"].as_f64().unwrap();
    let beats = t["beats"].as_u64().unwrap() as f64;
    assert!(
        beats > duration,
        "{name}: {beats} beats in {duration} s: {t}"
    );
    let (first, last) = (
        t["firstBeat"].as_f64().unwrap(),
        t["lastBeat"].as_f64().unwrap(),
    );
    assert!(0.0 <= first && last <= duration, "{name}: {t}");
    assert!(
        t["inked"].as_u64().unwrap() > 1000,
        "{name}: nothing drawn: {t}"
    );
}

/// Every download link of the page saves under the job's name for it
/// (`<song>-<system>-seed<k>.<ext>`), the face file says it is the face, and "Download all"
/// points at the job's zip.
fn check_downloads(report: &Value, job: &Value, name: &str) {
    let shown = report["downloads"]["variations"].as_array().unwrap();
    let variations = job["variations"].as_array().unwrap();
    assert_eq!(shown.len(), variations.len(), "{name}: {report}");
    for (links, v) in shown.iter().zip(variations) {
        let links = links.as_array().unwrap();
        assert_eq!(
            links.len(),
            v["files"].as_object().unwrap().len(),
            "{name}: {links:?}"
        );
        for (kind, url) in v["files"].as_object().unwrap() {
            let link = links
                .iter()
                .find(|l| l["href"] == *url)
                .unwrap_or_else(|| panic!("{name}: no link to {url}: {links:?}"));
            assert_eq!(link["download"], v["names"][kind], "{name} {kind}: {link}");
            assert!(
                link["download"]
                    .as_str()
                    .unwrap()
                    .contains(&format!("-{name}-seed")),
                "{name} {kind}: {link}"
            );
        }
    }
    let all = &report["downloads"]["all"];
    assert_eq!(all["hidden"], false, "{name}: {all}");
    let id = job["id"].as_str().unwrap();
    assert_eq!(all["href"], format!("api/jobs/{id}/zip"), "{name}: {all}");
}

#[test]
fn the_viewer_shows_the_jobs_joints_in_time_with_the_song() {
    check_prerequisites();
    let s = start(Limits::default());
    let base = s.server.url();

    // Two variations of the solo: side by side on a desktop, stacked on a phone.
    let solo = s.submit_song(&demo_song(), r#"{"seed": 2, "end": 8, "variations": 2}"#);
    assert_eq!(solo.status, 202, "{}", solo.json);
    let song = std::fs::read(demo_song()).unwrap();
    let leader = trimmed_bvh(&shared().join("data/cmu-salsa/61_13_scaled.bvh"), 7.0);
    let duet = s.submit(&[
        ("song", Some("demo.ogg"), &song),
        ("leader", Some("61_13_first_7s.bvh"), &leader),
        ("params", None, br#"{"system": "duet", "seed": 1}"#),
    ]);
    assert_eq!(duet.status, 202, "{}", duet.json);

    for (reply, name) in [(&solo, "solo"), (&duet, "duet")] {
        let id = reply.json["id"].as_str().unwrap();
        let job = s.wait(id, JOB_TIMEOUT);
        assert_eq!(job["state"], "done", "{name}: {job}");
        let files = &job["variations"][0]["files"];
        let report = view(&s, id, name);
        check_page(&report, &base, name);
        check_downloads(&report, &job, name);
        check_controls(&report, name);
        check_follow(&report, name);
        check_phone(&report, name);
        check_figures(&report, name, if name == "duet" { 2 } else { 1 });
        check_timeline(&report, &job, name);
        assert_eq!(
            report["views"]["closeupShown"], false,
            "{name}: the close-up is for holistic dances"
        );
        // The glb's dancers in order: a duet's leader (dancer 0), then the follower.
        let mut expected = Vec::new();
        if name == "duet" {
            expected.push(npy(&s.download(files["leader_npy"].as_str().unwrap())));
        }
        expected.push(npy(&s.download(files["npy"].as_str().unwrap())));
        for t in SEEK_TIMES {
            let dancers = report["joints"][t.to_string()][0].as_array().unwrap();
            assert_eq!(
                dancers.len(),
                expected.len(),
                "{name}: dancers in the scene"
            );
            for (d, npy) in expected.iter().enumerate() {
                let err = max_error(&dancers[d], npy, t);
                println!("{name} dancer {d} at {t} s: max joint error {err:.2e} m");
                assert!(
                    err <= TOLERANCE_M,
                    "{name} dancer {d} at {t} s: the scene is {err} m from the npy"
                );
            }
        }
    }
}

/// The editing flow in the page (issue 44): mark a part on the timeline, regenerate it as a
/// new version, see the versions listed, compare two side by side with their own downloads.
#[test]
fn a_part_marked_on_the_timeline_is_regenerated_as_a_new_version_and_compared() {
    check_prerequisites();
    let s = start(Limits::default());
    let r = s.submit_song(&demo_song(), r#"{"seed": 3, "end": 10}"#);
    assert_eq!(r.status, 202, "{}", r.json);
    let id = r.json["id"].as_str().unwrap().to_string();
    let job = s.wait(&id, JOB_TIMEOUT);
    assert_eq!(job["state"], "done", "{job}");

    let shots = Path::new(env!("CARGO_TARGET_TMPDIR")).join("edit-shots");
    let out = node_as_owner(&s)
        .arg(browser_dir().join("edit_check.mjs"))
        .arg(s.server.url())
        .arg(&id)
        .arg(&shots)
        .output()
        .expect("this test needs node (Node.js) on the PATH");
    assert!(
        out.status.success(),
        "edit_check failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let report: Value = serde_json::from_slice(&out.stdout).unwrap_or_else(|e| {
        panic!(
            "edit_check printed no JSON ({e}):\n{}",
            String::from_utf8_lossy(&out.stdout)
        )
    });
    println!("edit flow: {report}\nscreenshots in {}", shots.display());
    check_requests(&report, &s.server.url(), "edit");

    // The playhead marks, and a drag along the strip chooses, 2-4 s of the 10 s dance, shown
    // as a band.
    assert_eq!(report["marked"], "1", "{report}");
    let dragged: Vec<f64> = report["dragged"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|v| v.as_str()?.parse().ok())
        .collect();
    assert!(
        dragged.len() == 2 && (dragged[0] - 2.0).abs() <= 0.2 && (dragged[1] - 4.0).abs() <= 0.2,
        "dragged {dragged:?}"
    );
    let sel = &report["selection"];
    assert_eq!(sel["hidden"], false, "{sel}");
    let pct = |v: &Value| {
        v.as_str()
            .unwrap_or("")
            .trim_end_matches('%')
            .parse::<f64>()
            .ok()
    };
    assert!(
        pct(&sel["left"]).is_some_and(|l| (l - 20.0).abs() < 1.5),
        "selection starts at {sel}"
    );

    assert_eq!(
        report["continueShown"], true,
        "a solo dance can be continued"
    );

    // The new version is a job that edits this one, made from the marks.
    let eid = report["edited"].as_str().expect("a new version opened");
    assert_ne!(eid, id);
    let edited = s.wait(eid, JOB_TIMEOUT);
    assert_eq!(edited["state"], "done", "{edited}");
    let edit = &edited["params"]["edit"];
    assert_eq!(edit["of"], id.as_str(), "{edited}");
    assert_eq!(edit["keep"], "arms", "{edited}");
    let part = edit["regenerate"][0].as_array().unwrap();
    let (a, b) = (part[0].as_f64().unwrap(), part[1].as_f64().unwrap());
    assert!((a - 2.0).abs() < 0.15 && (b - 4.0).abs() < 0.15, "{edit}");
    let old = npy(&s.download(job["variations"][0]["files"]["npy"].as_str().unwrap()));
    let new = npy(&s.download(edited["variations"][0]["files"]["npy"].as_str().unwrap()));
    let frame = 72;
    let (fa, fb) = ((a * 30.0).round() as usize, (b * 30.0).round() as usize);
    for f in (0..old.data.len() / frame).filter(|f| !(fa..fb).contains(f)) {
        for i in f * frame..(f + 1) * frame {
            assert!(
                (old.data[i] - new.data[i]).abs() <= 1e-4,
                "frame {f} changed"
            );
        }
    }

    // Both versions listed; the comparison shows both, each with its downloads.
    let versions = report["versions"].as_array().unwrap();
    assert_eq!(versions.len(), 2, "{report}");
    assert_eq!(report["versionsShown"], true);
    assert!(
        versions[1].as_str().unwrap().contains("made new"),
        "{report}"
    );
    let cmp = &report["compare"];
    assert_eq!(cmp["figures"], 2, "{cmp}");
    let titles: Vec<&str> = cmp["titles"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(Value::as_str)
        .collect();
    assert!(
        titles[0].starts_with("Version 2") && titles[1].starts_with("Version 1"),
        "{titles:?}"
    );
    assert!(
        cmp["downloads"]
            .as_array()
            .unwrap()
            .iter()
            .all(|n| n.as_u64() >= Some(5)),
        "{cmp}"
    );
    assert_eq!(cmp["editBoxShown"], false, "{cmp}");
}

/// The song form with the keyboard and on a phone (issue 45): the drop zone is a tab stop
/// that Enter and Space open the file picker from; an empty file shows as "0 B" and is refused
/// before upload, naming the field; on a touch screen the zone says "Choose a song", and every
/// dance system's name fits its drop-down. The character field is offered for solo and
/// holistic dances, refuses a file that is not a character, and sends the one chosen. "Try
/// again" on a cancelled job fills the form in with its settings, song and character.
#[test]
fn the_song_form_works_from_the_keyboard_and_on_a_phone() {
    check_prerequisites();
    let s = start(Limits::default());
    let dir = tempfile::tempdir().unwrap();
    let empty = dir.path().join("empty.wav");
    std::fs::write(&empty, b"").unwrap();
    // Copies in the test's own folder: Chromium refused to upload the robot from the shared
    // data's read-only folder (net::ERR_ACCESS_DENIED); the song is copied alike.
    let song = dir.path().join("demo.ogg");
    std::fs::copy(demo_song(), &song).unwrap();
    let robot = dir.path().join("RobotExpressive.glb");
    std::fs::copy(
        shared().join("data/holistic/three-js-robot-expressive/RobotExpressive.glb"),
        &robot,
    )
    .unwrap();
    // A cancelled job with the robot, for "Try again".
    let song_bytes = std::fs::read(&song).unwrap();
    let robot_bytes = std::fs::read(&robot).unwrap();
    let r = s.submit(&[
        (
            "params",
            None,
            br#"{"seed": 5, "end": 6, "rig": "mixamo", "variations": 2}"#,
        ),
        ("song", Some("demo.ogg"), &song_bytes),
        ("character", Some("robot.glb"), &robot_bytes),
    ]);
    assert_eq!(r.status, 202, "{}", r.json);
    let cancelled = r.json["id"].as_str().unwrap().to_string();
    assert!(s.delete(&format!("/api/jobs/{cancelled}")).status < 300);
    let job = s.wait(&cancelled, JOB_TIMEOUT);
    assert_eq!(job["state"], "cancelled", "{job}");
    let shots = Path::new(env!("CARGO_TARGET_TMPDIR")).join("form-shots");
    let out = node_as_owner(&s)
        .arg(browser_dir().join("form_check.mjs"))
        .arg(s.server.url())
        .arg(&shots)
        .arg(&empty)
        .arg(&song)
        .arg(&robot)
        .arg(&cancelled)
        .output()
        .expect("this test needs node (Node.js) on the PATH");
    assert!(
        out.status.success(),
        "form_check failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let r: Value = serde_json::from_slice(&out.stdout).unwrap();
    println!("form: {r}; the phone's page in {}", shots.display());
    assert_eq!(r["errors"], serde_json::json!([]), "{r}");
    let desk = &r["desktop"];
    assert_eq!(desk["focused"], "drop-zone", "{desk}");
    assert_eq!(desk["enter"], true, "Enter on the drop zone: {desk}");
    assert_eq!(desk["space"], true, "Space on the drop zone: {desk}");
    assert_eq!(desk["name"], "empty.wav · 0 B", "{desk}");
    assert!(
        desk["notice"]
            .as_str()
            .unwrap_or("")
            .contains("is empty (0 B)"),
        "{desk}"
    );
    assert_eq!(desk["invalid"], "song", "{desk}");
    let phone = &r["phone"];
    assert!(
        phone["words"]
            .as_str()
            .unwrap()
            .starts_with("Choose a song"),
        "{phone}"
    );
    let room = phone["room"].as_f64().unwrap();
    for o in phone["options"].as_array().unwrap() {
        let width = o[1].as_f64().unwrap();
        assert!(width <= room, "{o} is cut: {width:.0} px in {room:.0} px");
    }
    // The character field (issue 45): offered for one dancer, a file that is not a .glb or
    // .vrm refused in the page naming the field, the robot sent with the song.
    let c = &r["character"];
    assert_eq!(
        c["shownFor"],
        serde_json::json!({"solo": true, "duet": false, "group": false, "holistic": true}),
        "{c}"
    );
    assert_eq!(c["refused"]["invalid"], "character", "{c}");
    assert!(
        c["refused"]["notice"]
            .as_str()
            .unwrap_or("")
            .contains("is not a .glb or .vrm"),
        "{c}"
    );
    assert_eq!(c["params"]["character"], "character.glb", "{c}");
    assert_eq!(c["params"]["end"], 4.0, "{c}");

    // "Try again" (issue 45): the cancelled job's page links to the form filled in from it.
    let a = &r["again"];
    assert_eq!(a["link"]["href"], format!("?again={cancelled}"), "{a}");
    assert_eq!(a["url"], format!("?again={cancelled}"), "{a}");
    assert!(
        a["notice"].as_str().unwrap_or("").contains("filled in"),
        "{a}"
    );
    assert_eq!(
        (
            &a["system"],
            &a["seed"],
            &a["end"],
            &a["rig"],
            &a["variations"]
        ),
        (
            &Value::from("solo"),
            &Value::from("5"),
            &Value::from("6"),
            &Value::from("mixamo"),
            &Value::from("2")
        ),
        "{a}"
    );
    assert_eq!(a["song"][1], song_bytes.len(), "the song, whole: {a}");
    assert_eq!(
        a["character"][1],
        robot_bytes.len(),
        "the character, whole: {a}"
    );
    assert!(
        a["songName"].as_str().unwrap_or("").starts_with("demo.ogg"),
        "{a}"
    );
}

/// "My dances" in the page (issue 45): two finished dances are listed newest first with their
/// pictures, song, system, seed and state, and the buttons for each; renaming through the
/// page's prompt shows the new name; deleting asks first and removes the dance; the deleted
/// dance's URL then says so in words and links to the library.
#[test]
fn my_dances_lists_renames_and_deletes_dances() {
    check_prerequisites();
    let s = start(Limits::default());
    let mut ids = Vec::new();
    for seed in [4, 5] {
        let r = s.submit_song(&demo_song(), &format!(r#"{{"seed": {seed}, "end": 4}}"#));
        assert_eq!(r.status, 202, "{}", r.json);
        let id = r.json["id"].as_str().unwrap().to_string();
        assert_eq!(s.wait(&id, JOB_TIMEOUT)["state"], "done");
        ids.push(id);
    }
    let shots = Path::new(env!("CARGO_TARGET_TMPDIR")).join("library-shots");
    // A browser without the jobs' owner secret lists none of them.
    let stranger = Command::new("node") // no secret
        .arg(browser_dir().join("library_check.mjs"))
        .arg(s.server.url())
        .arg(shots.join("stranger"))
        .arg("stranger")
        .output()
        .expect("this test needs node (Node.js) on the PATH");
    assert!(
        stranger.status.success(),
        "library_check (stranger) failed:\n{}",
        String::from_utf8_lossy(&stranger.stderr)
    );
    let seen: Value = serde_json::from_slice(&stranger.stdout).unwrap();
    assert_eq!(seen["items"], serde_json::json!([]), "{seen}");
    assert_eq!(seen["errors"], serde_json::json!([]), "{seen}");
    // The browser that made them (the client's secret in its storage) lists them.
    let out = node_as_owner(&s)
        .arg(browser_dir().join("library_check.mjs"))
        .arg(s.server.url())
        .arg(&shots)
        .output()
        .expect("this test needs node (Node.js) on the PATH");
    assert!(
        out.status.success(),
        "library_check failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let r: Value = serde_json::from_slice(&out.stdout).unwrap();
    println!("library: {r}; screenshots in {}", shots.display());
    assert_eq!(r["errors"], serde_json::json!([]), "{r}");
    let items = r["items"].as_array().unwrap();
    let listed: Vec<&str> = items.iter().map(|i| i["id"].as_str().unwrap()).collect();
    assert_eq!(
        listed,
        [ids[1].as_str(), ids[0].as_str()],
        "newest first: {r}"
    );
    for (item, seed) in items.iter().zip([5, 4]) {
        assert_eq!(item["picture"], true, "{item}");
        assert_eq!(item["title"], "demo_metal_madness_45s", "{item}");
        let meta = item["meta"].as_str().unwrap();
        assert!(
            meta.starts_with(&format!("Solo · seed {seed} · done")),
            "{item}"
        );
        assert_eq!(
            item["buttons"],
            serde_json::json!(["Open", "Rename", "Delete", "Again with another seed"]),
            "{item}"
        );
    }
    assert_eq!(r["renamed"], "Salsa night", "{r}");
    let dialogs: Vec<&str> = r["dialogs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|d| d["type"].as_str().unwrap())
        .collect();
    assert_eq!(dialogs, ["prompt", "confirm"], "{r}");
    assert_eq!(r["left"], serde_json::json!([ids[1]]), "{r}");
    assert_eq!(s.get(&format!("/api/jobs/{}", ids[0])).status, 404);
    assert_eq!(
        s.get(&format!("/api/jobs/{}", ids[1])).json["name"],
        "Salsa night"
    );
    let unknown = &r["unknown"];
    assert!(
        unknown["notice"]
            .as_str()
            .unwrap()
            .contains("not on this server"),
        "{unknown}"
    );
    assert_eq!(unknown["link"], "./#library", "{unknown}");
}

/// A holistic dance in the viewer (issue 45): its own face (the head mesh with the 52 ARKit
/// morph targets) instead of a head sphere, and a Close-up view, offered only to it, that
/// brings the camera to under half the front view's distance from the head, which stays in
/// the picture.
#[test]
fn a_holistic_dance_has_a_close_up_on_the_face_and_hands() {
    check_prerequisites();
    let s = start(Limits::default());
    let r = s.submit_song(
        &demo_song(),
        r#"{"system": "holistic", "seed": 1, "end": 6}"#,
    );
    assert_eq!(r.status, 202, "{}", r.json);
    let id = r.json["id"].as_str().unwrap();
    let job = s.wait(id, JOB_TIMEOUT);
    assert_eq!(job["state"], "done", "{job}");
    let report = view(&s, id, "holistic");
    assert_eq!(report["errors"], serde_json::json!([]), "{report}");
    check_follow(&report, "holistic");
    let v = &report["views"];
    assert_eq!(v["closeupShown"], true, "{v}");
    let (front, close) = (&v["front"], &v["closeup"]);
    assert_eq!(front["face"], true, "the file's face: {v}");
    assert_eq!(front["headSpheres"], 0, "no sphere over the face: {v}");
    assert_eq!(close["view"], "closeup", "{v}");
    assert_eq!(close["headInView"], true, "{v}");
    let (df, dc) = (
        front["distance"].as_f64().unwrap(),
        close["distance"].as_f64().unwrap(),
    );
    println!(
        "holistic: camera {df:.2} m from the head in the front view, {dc:.2} m in the close-up"
    );
    assert!(
        dc < df / 2.0,
        "close-up at {dc:.2} m, front at {df:.2} m: {v}"
    );
}

/// The user's character in the viewer (issue 45): a solo job made with the three.js robot
/// shows the robot dancing. Its one dancer's joints are the robot's bones that the file names
/// for SMPL's joints: the head above the pelvis, moving between 1 s and 5 s, the camera on
/// the head, the contact shadow under its supporting feet, no head sphere (the robot has its
/// own head) and no page error. The screenshot at 1 s is `docs/images/serve-character.png`.
#[test]
fn a_job_made_with_my_character_shows_it_dancing() {
    check_prerequisites();
    let s = start(Limits::default());
    let base = s.server.url();
    let song = std::fs::read(demo_song()).unwrap();
    let robot =
        std::fs::read(shared().join("data/holistic/three-js-robot-expressive/RobotExpressive.glb"))
            .unwrap();
    let r = s.submit(&[
        ("params", None, br#"{"seed": 2, "end": 8}"#),
        ("song", Some("demo.ogg"), &song),
        ("character", Some("RobotExpressive.glb"), &robot),
    ]);
    assert_eq!(r.status, 202, "{}", r.json);
    let id = r.json["id"].as_str().unwrap();
    let job = s.wait(id, JOB_TIMEOUT);
    assert_eq!(job["state"], "done", "{job}");
    let report = view(&s, id, "character");
    check_page(&report, &base, "character");
    check_controls(&report, "character");
    check_follow(&report, "character");
    let at = |t: u32| report["joints"][t.to_string()][0].clone();
    let (one, five) = (at(1), at(5));
    let dancers = one.as_array().unwrap();
    assert_eq!(dancers.len(), 1, "one dancer: {one}");
    let joints = dancers[0].as_array().unwrap();
    assert_eq!(joints.len(), 24, "the SMPL joints' bones: {one}");
    let v = |x: &Value, i: usize| x[i].as_f64().unwrap();
    let (pelvis, head) = (&joints[0], &joints[15]);
    assert!(
        v(head, 1) > v(pelvis, 1) + 0.3,
        "head {head}, pelvis {pelvis}"
    );
    let moved = (0..24)
        .map(|j| {
            let (a, b) = (&one[0][j], &five[0][j]);
            (0..3)
                .map(|k| (v(a, k) - v(b, k)).powi(2))
                .sum::<f64>()
                .sqrt()
        })
        .fold(0.0, f64::max);
    assert!(moved > 0.1, "the robot moved {moved} m from 1 s to 5 s");
    let f = &report["figures"][0];
    assert_eq!(f["heads"], serde_json::json!([]), "no head sphere: {f}");
    check_shadow(
        f,
        &f["shadows"][0],
        &dancers[0],
        f["lowest"][0].as_f64().unwrap(),
        "character",
        0,
    );
    assert_eq!(report["views"]["front"]["headInView"], true, "{report}");
    assert_eq!(report["views"]["front"]["headSpheres"], 0, "{report}");
}

/// A group in the viewer (issue 45): three figures, each with a head and a contact shadow under
/// its own supporting feet, the legend "Dancer 1" to "Dancer 3", the camera following the
/// group with every joint in the picture, and no page error.
#[test]
fn a_group_is_shown_dancer_by_dancer() {
    check_prerequisites();
    let s = start(Limits::default());
    let base = s.server.url();
    let r = s.submit_song(
        &demo_song(),
        r#"{"system": "group", "dancers": 3, "seed": 1, "end": 6}"#,
    );
    assert_eq!(r.status, 202, "{}", r.json);
    let id = r.json["id"].as_str().unwrap();
    let job = s.wait(id, JOB_TIMEOUT);
    assert_eq!(job["state"], "done", "{job}");
    let report = view(&s, id, "group");
    check_page(&report, &base, "group");
    check_follow(&report, "group");
    check_figures(&report, "group", 3);
}
