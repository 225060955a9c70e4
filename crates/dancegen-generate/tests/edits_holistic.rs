//! Editing a holistic dance through the library (issue 44): a range made new and a dance
//! continued, fingers and face included, with the shipped SoulNet model and a held-out song.

mod edit_common;

use std::sync::OnceLock;

use edit_common::{REAL_POSE_SPREAD_M, assert_joins, generator, joints, shared};

use dancegen_generate::edit::{Edit, GivenMotion, HolisticGiven};
use dancegen_generate::request::{CommonOptions, OutputRequest};
use dancegen_generate::systems::holistic::HolisticOptions;
use dancegen_generate::{CancelToken, Request, Song, SystemRequest};
use dancegen_metrics::edit::edit_quality;
use dancegen_motion::repr::SmplMotion;

/// A holistic dance: the body, the SMPL-H rotations (156 per frame) and the face (52).
#[derive(Clone)]
struct Holistic {
    body: SmplMotion,
    poses: Vec<f32>,
    face: Vec<f32>,
}

/// The dance as a user gets it: written to an `.npz` and read back as an edit reads it.
fn holistic(seed: u64, edit: Edit) -> Holistic {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("dance.npz");
    let req = Request {
        song: Song::File(shared().join("data/music/sectoid/feelings.ogg")),
        system: SystemRequest::Holistic(HolisticOptions::default()),
        common: CommonOptions {
            seed,
            start: Some(30.0),
            end: Some(54.0),
            edit,
            ..Default::default()
        },
        model: None,
        outputs: vec![OutputRequest::new(out.clone())],
    };
    generator()
        .run(&req, &|_| {}, &CancelToken::new())
        .unwrap_or_else(|e| panic!("{e}"));
    let g = GivenMotion::load_dance(&out, "the dance", None, "").unwrap();
    let h = g
        .holistic
        .expect("a holistic .npz holds the fingers and face");
    Holistic {
        body: g.motion,
        poses: h.poses,
        face: h.face,
    }
}

fn base() -> &'static Holistic {
    static B: OnceLock<Holistic> = OnceLock::new();
    B.get_or_init(|| holistic(0, Edit::default()))
}

fn given(h: &Holistic) -> GivenMotion {
    let mut g = GivenMotion::one("base.npz".into(), h.body.clone());
    g.holistic = Some(HolisticGiven {
        poses: h.poses.clone(),
        face: h.face.clone(),
    });
    g
}

#[test]
fn a_regenerated_range_keeps_body_fingers_and_face_outside_it() {
    let original = base();
    let edit = Edit {
        base: Some(given(original)),
        regenerate: vec![[8.0, 14.0]],
        ..Edit::default()
    };
    let edited = holistic(3, edit);
    let made = 240..420;
    let t = original.body.frames();
    assert_eq!(edited.body.frames(), t);
    for f in (0..t).filter(|f| !made.contains(f)) {
        assert_eq!(
            edited.poses[f * 156..(f + 1) * 156],
            original.poses[f * 156..(f + 1) * 156],
            "frame {f}"
        );
        assert_eq!(
            edited.face[f * 52..(f + 1) * 52],
            original.face[f * 52..(f + 1) * 52],
            "frame {f}"
        );
        assert_eq!(
            edited.body.trans[f * 3..(f + 1) * 3],
            original.body.trans[f * 3..(f + 1) * 3]
        );
    }
    let (jo, je) = (joints(&original.body), joints(&edited.body));
    let q = edit_quality(&jo, &je, std::slice::from_ref(&made), 30.0).unwrap();
    let other = holistic(3, Edit::default());
    let seeds = edit_quality(&jo, &joints(&other.body), std::slice::from_ref(&made), 30.0)
        .unwrap()
        .new_difference_m;
    let fingers = (made.clone())
        .map(|f| {
            (66..156)
                .map(|i| (edited.poses[f * 156 + i] - original.poses[f * 156 + i]).abs())
                .sum::<f32>()
                / 90.0
        })
        .sum::<f32>()
        / made.len() as f32;
    eprintln!(
        "holistic regenerate: {q:?}; another seed differs by {seeds:.3} m; the fingers' rotations \
         by {fingers:.3} rad on average in the new part"
    );
    assert!(q.kept_max_m <= 1e-4, "{q:?}");
    assert_joins(&q, "the edit");
    assert!(
        q.new_difference_m >= REAL_POSE_SPREAD_M / 2.0,
        "the new part differs by {:.3} m; another seed by {seeds:.3} m",
        q.new_difference_m
    );
    assert!(
        fingers > 0.01,
        "the fingers are the old ones ({fingers} rad)"
    );
}

#[test]
fn a_continued_dance_starts_with_the_last_second_fingers_and_face_included() {
    let original = base();
    let keep = 150;
    let mut from = given(original);
    from.motion = SmplMotion::new(
        30.0,
        original.body.poses[..keep * 72].to_vec(),
        original.body.trans[..keep * 3].to_vec(),
    )
    .unwrap();
    from.holistic = Some(HolisticGiven {
        poses: original.poses[..keep * 156].to_vec(),
        face: original.face[..keep * 52].to_vec(),
    });
    let made = holistic(
        4,
        Edit {
            continue_from: Some(from),
            ..Edit::default()
        },
    );
    for f in 0..30 {
        let g = keep - 30 + f;
        assert_eq!(
            made.poses[f * 156..(f + 1) * 156],
            original.poses[g * 156..(g + 1) * 156],
            "frame {f}"
        );
        assert_eq!(
            made.face[f * 52..(f + 1) * 52],
            original.face[g * 52..(g + 1) * 52],
            "frame {f}"
        );
    }
    let j = joints(&made.body);
    let after = 30..made.body.frames();
    let q = edit_quality(&j, &j, std::slice::from_ref(&after), 30.0).unwrap();
    eprintln!("holistic continue: {q:?}");
    assert_joins(&q, "the edit");
}
