//! Editing a duet's follower through the library (issue 44): a range made new and a follower
//! continued from a motion, with the shipped ReactDance model, a real salsa leader and a
//! held-out song; held to the bounds where the model can reach them.

mod edit_common;

use std::sync::OnceLock;

use edit_common::{REAL_POSE_SPREAD_M, generator, joints, shared};

use dancegen_generate::edit::{Edit, GivenMotion};
use dancegen_generate::request::CommonOptions;
use dancegen_generate::systems::duet::DuetOptions;
use dancegen_generate::{CancelToken, Request, Song, SystemRequest};
use dancegen_metrics::edit::edit_quality;
use dancegen_motion::repr::SmplMotion;

/// The CMU salsa leader of couple 13 at its true 60 fps, its first 24 s.
fn leader() -> &'static GivenMotion {
    static L: OnceLock<GivenMotion> = OnceLock::new();
    L.get_or_init(|| {
        let path = shared().join("data/cmu-salsa/60_13_scaled.bvh");
        let mut g = GivenMotion::load(&path, "the leader", Some(60.0), "--leader-fps").unwrap();
        let t = 24 * 30;
        g.motion = SmplMotion::new(
            30.0,
            g.motion.poses[..t * 72].to_vec(),
            g.motion.trans[..t * 3].to_vec(),
        )
        .unwrap();
        g
    })
}

fn duet(seed: u64, edit: Edit) -> SmplMotion {
    let l = leader();
    let req = Request {
        song: Song::File(shared().join("data/music/sectoid/feelings.ogg")),
        system: SystemRequest::Duet(DuetOptions::new(l.motion.clone(), l.label.clone())),
        common: CommonOptions {
            seed,
            start: Some(30.0),
            edit,
            ..Default::default()
        },
        model: None,
        outputs: vec![],
    };
    let done = generator()
        .run(&req, &|_| {}, &CancelToken::new())
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(done.dancers.len(), 2, "leader and follower");
    done.dancers[1].motion.clone()
}

fn base() -> &'static SmplMotion {
    static B: OnceLock<SmplMotion> = OnceLock::new();
    B.get_or_init(|| duet(0, Edit::default()))
}

/// Mean distance of the pelvis-relative joints of two motions over `frames`.
fn pose_difference(a: &[f64], b: &[f64], frames: std::ops::Range<usize>) -> f64 {
    let n = frames.len() * 24;
    let mut d = 0.0;
    for f in frames {
        for j in 0..24 {
            let (i, r) = ((f * 24 + j) * 3, f * 72);
            d += (0..3)
                .map(|c| ((a[i + c] - a[r + c]) - (b[i + c] - b[r + c])).powi(2))
                .sum::<f64>()
                .sqrt();
        }
    }
    d / n as f64
}

#[test]
fn a_regenerated_range_of_the_follower_is_new_and_joins_the_kept_frames() {
    let original = base();
    let edit = Edit {
        base: Some(GivenMotion::one("follower".into(), original.clone())),
        regenerate: vec![[8.0, 14.0]],
        ..Edit::default()
    };
    let edited = duet(3, edit);
    let made = 240..420;
    assert_eq!(edited.frames(), original.frames());
    for f in (0..edited.frames()).filter(|f| !made.contains(f)) {
        assert_eq!(
            edited.poses[f * 72..(f + 1) * 72],
            original.poses[f * 72..(f + 1) * 72],
            "frame {f}"
        );
        assert_eq!(
            edited.trans[f * 3..(f + 1) * 3],
            original.trans[f * 3..(f + 1) * 3]
        );
    }
    let (jo, je) = (joints(original), joints(&edited));
    let q = edit_quality(&jo, &je, std::slice::from_ref(&made), 30.0).unwrap();
    // How much another seed changes the same frames of the whole follower (the model's own
    // variety, for the message).
    let other = joints(&duet(3, Edit::default()));
    let seeds = pose_difference(&jo, &other, made.clone());
    eprintln!("duet regenerate: {q:?}; another seed differs by {seeds:.3} m there");
    assert!(q.kept_max_m <= 1e-4, "{q:?}");
    let ratio = q.join_jerk_ratio.expect("joins inside the dance");
    assert!(ratio < 1.5, "boundary jerk ratio {ratio:.2} at the joins");
    assert!(
        q.join_root_step_m <= q.other_root_step_m + 0.05,
        "root step {:.3} m at a join against {:.3} m elsewhere",
        q.join_root_step_m,
        q.other_root_step_m
    );
    assert!(
        q.join_foot_slide_m <= q.other_foot_slide_m,
        "a planted foot slides {:.3} m in a frame at a join, {:.3} m elsewhere",
        q.join_foot_slide_m,
        q.other_foot_slide_m
    );
    assert!(
        q.new_difference_m >= REAL_POSE_SPREAD_M / 2.0,
        "the new part differs by {:.3} m; another seed by {seeds:.3} m",
        q.new_difference_m
    );
}

#[test]
fn a_follower_continued_from_a_motion_starts_with_its_last_second() {
    let original = base();
    // The base follower's last 5 s continued: the new follower's first second is their last.
    let from = SmplMotion::new(
        30.0,
        original.poses[..150 * 72].to_vec(),
        original.trans[..150 * 3].to_vec(),
    )
    .unwrap();
    let edit = Edit {
        continue_from: Some(GivenMotion::one("motion".into(), from.clone())),
        ..Edit::default()
    };
    let made = duet(4, edit);
    for f in 0..30 {
        assert_eq!(
            made.poses[f * 72..(f + 1) * 72],
            from.poses[(120 + f) * 72..(121 + f) * 72],
            "frame {f}"
        );
    }
    let j = joints(&made);
    let after = std::ops::Range {
        start: 30,
        end: made.frames(),
    };
    let q = edit_quality(&j, &j, std::slice::from_ref(&after), 30.0).unwrap();
    eprintln!("duet continue: {q:?}");
    assert!(
        q.join_root_step_m <= q.other_root_step_m + 0.05,
        "root step {:.3} m at the join against {:.3} m elsewhere",
        q.join_root_step_m,
        q.other_root_step_m
    );
}

#[test]
fn edits_the_duet_system_does_not_apply_are_refused_naming_them() {
    let l = leader();
    let req = Request {
        song: Song::File(shared().join("data/music/sectoid/feelings.ogg")),
        system: SystemRequest::Duet(DuetOptions::new(l.motion.clone(), l.label.clone())),
        common: CommonOptions {
            edit: Edit {
                keyframe_root: true,
                ..Edit::default()
            },
            ..Default::default()
        },
        model: None,
        outputs: vec![],
    };
    let e = generator()
        .run(&req, &|_| {}, &CancelToken::new())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("--keyframe is not supported by --system duet"),
        "{e}"
    );
}
