//! The one library API, as every front end uses it: solo and duet jobs through
//! `Generator::run` with the shipped models, progress that only grows and ends at 1.0, and
//! cancellation that leaves no file behind (not even a staging folder), nor harms a file that
//! was there before.

use std::path::{Path, PathBuf};
use std::sync::Mutex;

use dancegen_generate::models::{Origin, SearchDir};
use dancegen_generate::request::{CommonOptions, DancerSelection, OutputRequest};
use dancegen_generate::systems::duet::{DuetOptions, load_leader};
use dancegen_generate::{
    CancelToken, GenerateError, Generator, ModelLocator, Progress, Request, Role, Song,
    SystemRequest,
};

fn shared() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared")
}

/// The shipped models, and nothing else on the search path.
fn generator() -> Generator {
    Generator::new(ModelLocator::new(vec![SearchDir {
        dir: Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models"),
        origin: Origin::Explicit,
    }]))
}

fn song() -> Song {
    Song::File(shared().join("data/music/sectoid/feelings.ogg"))
}

fn solo(outputs: &[PathBuf], start: f64, end: f64) -> Request {
    Request {
        song: song(),
        system: SystemRequest::Solo(Default::default()),
        common: CommonOptions {
            seed: 7,
            steps: Some(4),
            start: Some(start),
            end: Some(end),
            ..Default::default()
        },
        model: None,
        outputs: outputs.iter().map(OutputRequest::new).collect(),
    }
}

/// Runs `req`, recording every progress report.
fn run_recorded(
    g: &Generator,
    req: &Request,
    cancel: &CancelToken,
    cancel_when: impl Fn(&Progress) -> bool + Sync,
) -> (
    Result<dancegen_generate::Generated, GenerateError>,
    Vec<Progress>,
) {
    let seen = Mutex::new(Vec::new());
    let cb = |p: &Progress| {
        seen.lock().unwrap().push(p.clone());
        if cancel_when(p) {
            cancel.cancel();
        }
    };
    let r = g.run(req, &cb, cancel);
    (r, seen.into_inner().unwrap())
}

fn assert_grows_to_one(reports: &[Progress]) {
    assert!(reports.len() > 5, "{reports:?}");
    for w in reports.windows(2) {
        assert!(w[1].fraction >= w[0].fraction, "went back: {w:?}");
    }
    let last = reports.last().unwrap();
    assert_eq!((last.stage, last.fraction), ("done", 1.0));
    assert!(
        reports[..reports.len() - 1]
            .iter()
            .all(|p| p.fraction < 1.0 + 1e-12)
    );
    for stage in ["load_model", "analyse_song", "denoising", "write_outputs"] {
        assert!(
            reports.iter().any(|p| p.stage == stage),
            "no {stage} report"
        );
    }
}

fn entries(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn solo_and_duet_run_through_one_api() {
    let g = generator();
    let dir = tempfile::tempdir().unwrap();
    let p = |n: &str| dir.path().join(n);

    let (r, reports) = run_recorded(
        &g,
        &solo(&[p("solo.npy"), p("solo.glb")], 20.0, 26.0),
        &CancelToken::new(),
        |_| false,
    );
    let solo = r.unwrap();
    assert_grows_to_one(&reports);
    assert!(reports.iter().any(|p| p.stage == "choreography"));
    assert_eq!(solo.system, "solo");
    assert_eq!(solo.dancers.len(), 1);
    assert_eq!(solo.dancers[0].role, Role::Solo);
    assert_eq!(solo.dancers[0].motion.frames(), 180, "6 s at 30 fps");
    assert_eq!(solo.written, vec![p("solo.npy"), p("solo.glb")]);
    assert!(!solo.beat_times_s.is_empty() && solo.beat_times_s.iter().all(|&t| t < 6.0));
    let npy = dancegen_io::read_npy(&p("solo.npy")).unwrap();
    assert_eq!(npy.shape, vec![180, 24, 3]);

    // The duet through the same generator: the follower of a real leader (8 s of a CMU salsa
    // take), the couple in the .glb, the follower alone in the .npy.
    let mut leader = load_leader(&shared().join("data/cmu-salsa/61_13_scaled.bvh")).unwrap();
    leader.poses.truncate(240 * 72);
    leader.trans.truncate(240 * 3);
    let duet = Request {
        song: song(),
        system: SystemRequest::Duet(DuetOptions::new(leader.clone(), "61_13")),
        common: CommonOptions {
            seed: 1,
            steps: Some(3),
            start: Some(10.0),
            ..Default::default()
        },
        model: None,
        outputs: vec![
            OutputRequest::new(p("couple.glb")),
            OutputRequest::new(p("f.npy")),
        ],
    };
    let (r, reports) = run_recorded(&g, &duet, &CancelToken::new(), |_| false);
    let duet = r.unwrap();
    assert_grows_to_one(&reports);
    let roles: Vec<Role> = duet.dancers.iter().map(|d| d.role).collect();
    assert_eq!(roles, vec![Role::Leader, Role::Follower]);
    assert_eq!(
        duet.dancers[0].motion.poses, leader.poses,
        "the leader is kept as given"
    );
    assert_eq!(duet.dancers[1].motion.frames(), 240);
    assert_eq!((duet.start_s, duet.end_s), (10.0, 18.0));
    let f = dancegen_io::read_npy(&p("f.npy")).unwrap();
    assert_eq!(
        f.shape,
        vec![240, 24, 3],
        "single-dancer formats hold the follower"
    );
    assert_eq!(
        entries(dir.path()),
        vec!["couple.glb", "f.npy", "solo.glb", "solo.npy"],
        "no staging folder left"
    );
}

#[test]
fn a_cancel_after_the_first_step_leaves_no_file() {
    let g = generator();
    let dir = tempfile::tempdir().unwrap();
    // A file from before: a cancelled job must not replace or remove it.
    let old = dir.path().join("dance.npy");
    std::fs::write(&old, b"the user's earlier dance").unwrap();
    let outs = [old.clone(), dir.path().join("dance.glb")];
    let cancel = CancelToken::new();
    let (r, reports) = run_recorded(&g, &solo(&outs, 30.0, 34.0), &cancel, |p| {
        p.stage == "denoising" && p.fraction > 0.0
    });
    assert!(
        matches!(r, Err(GenerateError::Cancelled)),
        "{:?}",
        r.map(|d| d.written)
    );
    assert!(reports.iter().any(|p| p.stage == "denoising"));
    assert!(reports.iter().all(|p| p.stage != "write_outputs"));
    assert_eq!(entries(dir.path()), vec!["dance.npy"]);
    assert_eq!(std::fs::read(&old).unwrap(), b"the user's earlier dance");
}

#[test]
fn a_cancel_while_drawing_the_preview_leaves_no_file() {
    let g = generator();
    let dir = tempfile::tempdir().unwrap();
    let outs = [dir.path().join("a.npy"), dir.path().join("a.gif")];
    let cancel = CancelToken::new();
    // The .npy is written first; a cancel late in the writing (while the GIF's frames are
    // drawn, or at the latest at the check before the files are committed) must take it back
    // too: a job's files appear together or not at all.
    let (r, reports) = run_recorded(&g, &solo(&outs, 40.0, 46.0), &cancel, |p| {
        p.stage == "write_outputs" && p.fraction > 0.97
    });
    assert!(
        matches!(r, Err(GenerateError::Cancelled)),
        "{:?}",
        r.map(|d| d.written)
    );
    assert!(reports.iter().any(|p| p.stage == "write_outputs"));
    assert!(entries(dir.path()).is_empty(), "{:?}", entries(dir.path()));
}

#[test]
fn follower_only_and_many_dancer_rules() {
    let g = generator();
    let dir = tempfile::tempdir().unwrap();
    let mut leader = load_leader(&shared().join("data/cmu-salsa/60_13_scaled.bvh")).unwrap();
    leader.poses.truncate(96 * 72);
    leader.trans.truncate(96 * 3);
    let req = Request {
        song: song(),
        system: SystemRequest::Duet(DuetOptions::new(leader, "60_13")),
        common: CommonOptions {
            steps: Some(2),
            ..Default::default()
        },
        model: None,
        outputs: vec![OutputRequest {
            path: dir.path().join("only.json"),
            dancers: DancerSelection::Generated,
            rig: Default::default(),
            character: None,
            video: Default::default(),
        }],
    };
    let done = g.run(&req, &|_| {}, &CancelToken::new()).unwrap();
    assert_eq!(done.dancers.len(), 2);
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("only.json")).unwrap()).unwrap();
    assert_eq!(
        json["shape"],
        serde_json::json!([96, 24, 3]),
        "the follower alone"
    );
}

#[test]
fn a_missing_model_names_every_place_looked_in_and_writes_nothing() {
    let empty = tempfile::tempdir().unwrap();
    let g = Generator::new(ModelLocator::new(vec![SearchDir {
        dir: empty.path().to_path_buf(),
        origin: Origin::EnvVar,
    }]));
    let out = empty.path().join("x.glb");
    let e = g
        .run(
            &solo(std::slice::from_ref(&out), 0.0, 3.0),
            &|_| {},
            &CancelToken::new(),
        )
        .unwrap_err();
    let msg = e.to_string();
    assert!(matches!(e, GenerateError::ModelNotFound(_)), "{msg}");
    assert!(
        msg.contains(&empty.path().join("lodgepp-small").display().to_string()),
        "{msg}"
    );
    assert!(
        msg.contains("DANCEGEN_MODEL_DIR") && msg.contains("models install"),
        "{msg}"
    );
    assert!(!out.exists());
}

/// Asking the solo system to run the shipped duet model names the `--system` that runs it.
#[test]
fn a_model_of_another_system_names_the_system_that_runs_it() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.npy");
    let mut req = solo(std::slice::from_ref(&out), 0.0, 3.0);
    let duet = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models/reactdance-small");
    req.model = Some(duet.clone());
    let e = generator()
        .run(&req, &|_| {}, &CancelToken::new())
        .unwrap_err();
    let msg = e.to_string();
    assert!(matches!(e, GenerateError::Invalid(_)), "{msg}");
    assert!(msg.contains(&duet.display().to_string()), "{msg}");
    assert!(
        msg.contains("a duet model") && msg.contains("--system duet"),
        "{msg}"
    );
    assert!(!out.exists());
}

/// A leader given as joint positions (what `generate -o x.npy` writes) is refused with the
/// formats that would do, naming the file once.
#[test]
fn a_leader_without_rotations_is_refused_with_the_formats_that_have_them() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("leader.npy");
    let frames = 30;
    dancegen_io::write_npy_f32(&p, &[frames, 24, 3], &vec![0.1; frames * 24 * 3]).unwrap();
    let Err(e) = load_leader(&p) else {
        panic!("joint positions were taken as a leader");
    };
    let msg = e.to_string();
    assert_eq!(msg.matches(&p.display().to_string()).count(), 1, "{msg}");
    assert!(
        msg.contains("no rotations") && msg.contains(".npz"),
        "{msg}"
    );
}

#[test]
fn bad_outputs_fail_before_any_work() {
    let g = generator();
    let dir = tempfile::tempdir().unwrap();
    for (path, needle) in [
        (dir.path().join("a.fbz"), "unknown output format"),
        (dir.path().join("no/such/dir/a.glb"), "does not exist"),
        // Only a holistic dance has a face for Live Link Face CSV.
        (dir.path().join("face.csv"), "--system holistic"),
    ] {
        let e = g
            .run(
                &solo(std::slice::from_ref(&path), 0.0, 3.0),
                &|_| {},
                &CancelToken::new(),
            )
            .unwrap_err()
            .to_string();
        assert!(
            e.contains(needle) && e.contains(&path.display().to_string()),
            "{e}"
        );
    }
    let twice = [dir.path().join("a.npy"), dir.path().join("a.npy")];
    let e = g
        .run(&solo(&twice, 0.0, 3.0), &|_| {}, &CancelToken::new())
        .unwrap_err()
        .to_string();
    assert!(e.contains("named twice"), "{e}");
    assert!(entries(dir.path()).is_empty());
}
