//! Editing a holistic dance through the library (issue 44): a range made new and a dance
//! continued, fingers and face included, kept joints, a keyframe and a path, with the shipped
//! SoulNet model and a held-out song.

mod edit_common;

use std::sync::OnceLock;

use edit_common::{
    REAL_POSE_SPREAD_M, assert_joins, feelings_beats, generator, joints, mean_jerk, shared,
};

use dancegen_generate::edit::{
    Edit, GivenMotion, HolisticGiven, KeepJoints, KeyframePose, parse_joint_set,
};
use dancegen_generate::formation_file::FormationFile;
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
    let beats = feelings_beats(30.0, 54.0);
    let old_part = edit_common::bas_of_range(&jo, &beats, &made);
    eprintln!(
        "BAS in the range: the original {old_part:.3}, another seed's plain dance {:.3}",
        edit_common::bas_of_range(&joints(&other.body), &beats, &made)
    );
    let (whole, part) = (
        edit_common::bas(&je, &beats),
        edit_common::bas_of_range(&je, &beats, &made),
    );
    eprintln!(
        "holistic regenerate: {q:?}; another seed differs by {seeds:.3} m; the fingers' rotations \
         by {fingers:.3} rad on average in the new part; BAS {part:.3} in the new part, \
         {whole:.3} overall"
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

#[test]
fn kept_legs_and_root_stay_and_the_rest_is_new_fingers_and_face_included() {
    let original = base();
    let (mask, root) = parse_joint_set("--keep-joints", "lower").unwrap();
    let edit = Edit {
        keep_joints: Some(KeepJoints {
            spec: "lower".into(),
            joints: mask,
            root,
            from: GivenMotion::one("base".into(), original.body.clone()),
        }),
        ..Edit::default()
    };
    let made = holistic(5, edit);
    let t = original.body.frames();
    assert_eq!(made.body.frames(), t);
    for f in 0..t {
        for j in (0..24).filter(|j| mask & (1 << j) != 0) {
            let at = f * 72 + 3 * j;
            assert_eq!(
                made.body.poses[at..at + 3],
                original.body.poses[at..at + 3],
                "frame {f} joint {j}"
            );
            assert_eq!(
                made.poses[f * 156 + 3 * j..f * 156 + 3 * j + 3],
                original.body.poses[at..at + 3],
                "the SMPL-H rotations, frame {f} joint {j}"
            );
        }
        assert_eq!(
            made.body.trans[f * 3..f * 3 + 3],
            original.body.trans[f * 3..f * 3 + 3],
            "frame {f}"
        );
    }
    // The arms are new: the wrists relative to the pelvis, mean distance.
    let (jo, jm) = (joints(&original.body), joints(&made.body));
    let mut d = 0.0;
    for f in 0..t {
        for j in [20, 21] {
            d += (0..3)
                .map(|c| {
                    let rel = |m: &[f64]| m[(f * 24 + j) * 3 + c] - m[f * 72 + c];
                    (rel(&jo) - rel(&jm)).powi(2)
                })
                .sum::<f64>()
                .sqrt();
        }
    }
    let d = d / (2 * t) as f64;
    let fingers = (0..t * 156)
        .filter(|i| i % 156 >= 66)
        .map(|i| f64::from((made.poses[i] - original.poses[i]).abs()))
        .sum::<f64>()
        / (t * 90) as f64;
    let (jerk_m, jerk_o) = (mean_jerk(&made.body), mean_jerk(&original.body));
    eprintln!(
        "holistic kept lower: wrists {d:.3} m from the original's, fingers {fingers:.3} rad; \
         jerk {jerk_m:.0} against {jerk_o:.0}"
    );
    assert!(
        d >= REAL_POSE_SPREAD_M / 2.0,
        "the arms are the old ones ({d:.3} m)"
    );
    assert!(fingers > 0.01, "the fingers are the old ones ({fingers})");
    assert!(
        jerk_m <= 1.5 * jerk_o,
        "jerk {jerk_m:.0} against {jerk_o:.0}"
    );
}

#[test]
fn a_keyframe_pose_is_reached_in_world_space_and_eased_into() {
    let original = base();
    // The base dance's frame 100, with its floor position, reached at 40 s of the song (the
    // dance's frame 300) by a dance of another seed.
    let key = KeyframePose {
        spec: "base:100@40".into(),
        t: 40.0,
        pose: original.body.poses[100 * 72..101 * 72].to_vec(),
        trans: [0, 1, 2].map(|c| original.body.trans[100 * 3 + c]),
    };
    let made = holistic(
        6,
        Edit {
            keyframes: vec![key],
            keyframe_root: true,
            ..Edit::default()
        },
    );
    let (jo, jm) = (joints(&original.body), joints(&made.body));
    let worst = (0..24)
        .map(|j| {
            (0..3)
                .map(|c| (jm[(300 * 24 + j) * 3 + c] - jo[(100 * 24 + j) * 3 + c]).powi(2))
                .sum::<f64>()
                .sqrt()
        })
        .fold(0.0, f64::max);
    let around = 300..301;
    let q = edit_quality(&jm, &jm, std::slice::from_ref(&around), 30.0).unwrap();
    eprintln!(
        "holistic keyframe: worst joint {worst:.4} m from the pose; {q:?}; jerk {:.0} against \
         {:.0}",
        mean_jerk(&made.body),
        mean_jerk(&original.body)
    );
    assert!(
        worst <= 0.03,
        "a keyframed joint is {worst:.3} m from its target"
    );
    assert_joins(&q, "around the keyframe");
}

#[test]
fn a_path_is_followed_and_the_dance_on_it_stays_whole() {
    let json = r#"{"keyframes": [
        {"t": 32, "positions": [[0, 0]]},
        {"t": 40, "positions": [[1.5, 0.5]]},
        {"t": 48, "positions": [[-1, 1]]}]}"#;
    let file = FormationFile {
        label: "path.json".into(),
        json: json.into(),
    };
    let want = &file.parse(1, 1e9).unwrap().sample(30.0, 54 * 30)[0][30 * 30..];
    let made = holistic(
        7,
        Edit {
            path: Some(file),
            ..Edit::default()
        },
    );
    edit_common::assert_path_followed(&made.body, want, &base().body, "holistic path");
}

/// New parts are on the beat: the mean BAS of 8-14 s regenerated with seeds 1-5 is at least
/// the mean BAS of those whole edited dances − 0.05 (the issue's bound, on the mean: the BAS
/// of a 6 s range is a lottery of its few beats, 0.008 to 0.380 for plain dances of seeds
/// 1-5 in this range). The same range of plain dances of those seeds is reported beside it.
#[test]
fn new_parts_are_on_the_beat_over_seeds() {
    let original = base();
    let beats = feelings_beats(30.0, 54.0);
    let made = 240..420;
    let (mut plain, mut part, mut whole) = (Vec::new(), Vec::new(), Vec::new());
    for seed in 1..=5 {
        let p = holistic(seed, Edit::default());
        plain.push(edit_common::bas_of_range(&joints(&p.body), &beats, &made));
        let e = holistic(
            seed,
            Edit {
                base: Some(given(original)),
                regenerate: vec![[8.0, 14.0]],
                ..Edit::default()
            },
        );
        let j = joints(&e.body);
        part.push(edit_common::bas_of_range(&j, &beats, &made));
        whole.push(edit_common::bas(&j, &beats));
    }
    edit_common::on_the_beat_over_seeds(&part, &whole, &plain, "holistic").unwrap();
}
