//! Editing a solo dance through the library (issue 44): a range made new, a dance continued,
//! kept joints, a keyframe pose and a root path, on a held-out song with the shipped model,
//! held to the issue's quality bounds: kept frames exactly kept, seamless joins, new motion
//! that is new and on the beat, constraints met.

mod edit_common;

use std::sync::OnceLock;

use edit_common::{REAL_POSE_SPREAD_M, assert_on_the_beat, generator, joints, shared};

use dancegen_generate::edit::{Edit, GivenMotion, KeyframePose};
use dancegen_generate::formation_file::FormationFile;
use dancegen_generate::request::CommonOptions;
use dancegen_generate::{CancelToken, Request, Song, SystemRequest};
use dancegen_metrics::edit::{EditQuality, edit_quality};
use dancegen_motion::repr::SmplMotion;

fn song() -> Song {
    Song::File(shared().join("data/music/sectoid/feelings.ogg"))
}

fn solo(seed: u64, start: f64, end: Option<f64>, edit: Edit) -> Request {
    Request {
        song: song(),
        system: SystemRequest::Solo(Default::default()),
        common: CommonOptions {
            seed,
            start: Some(start),
            end,
            edit,
            ..Default::default()
        },
        model: None,
        outputs: vec![],
    }
}

fn run(req: &Request) -> (SmplMotion, Vec<usize>) {
    let done = generator()
        .run(req, &|_| {}, &CancelToken::new())
        .unwrap_or_else(|e| panic!("{e}"));
    let beats = done
        .beat_times_s
        .iter()
        .map(|s| (s * 30.0).round() as usize)
        .collect();
    (done.dancers[0].motion.clone(), beats)
}

/// The base dance: 29 s of a held-out song.
fn base() -> &'static (SmplMotion, Vec<usize>) {
    static B: OnceLock<(SmplMotion, Vec<usize>)> = OnceLock::new();
    B.get_or_init(|| run(&solo(0, 60.0, Some(89.0), Edit::default())))
}

/// The issue's bound on the boundary-jerk ratio at the joins.
const JOIN_JERK_RATIO_MAX: f64 = 1.5;

fn check_joins(q: &EditQuality, jerk_ratio: bool) {
    let ratio = q.join_jerk_ratio.expect("joins inside the dance");
    if jerk_ratio {
        assert!(
            ratio < JOIN_JERK_RATIO_MAX,
            "boundary jerk ratio at the joins {ratio:.2}: {q:?}"
        );
    }
    assert!(
        q.join_root_step_m <= q.other_root_step_m + 0.05,
        "root step at a join {:.3} m against {:.3} m elsewhere",
        q.join_root_step_m,
        q.other_root_step_m
    );
    assert!(
        q.join_foot_slide_m <= q.other_foot_slide_m,
        "a planted foot slides {:.3} m in a frame at a join, {:.3} m elsewhere",
        q.join_foot_slide_m,
        q.other_foot_slide_m
    );
}

/// The edit of [`a_regenerated_range_is_new_on_the_beat_and_joins_the_kept_frames`]: the base
/// dance, the edited one and the frames made new.
fn regenerated() -> &'static (SmplMotion, Vec<std::ops::Range<usize>>) {
    static E: OnceLock<(SmplMotion, Vec<std::ops::Range<usize>>)> = OnceLock::new();
    E.get_or_init(|| {
        let (original, _) = base();
        let ranges = [[8.0, 14.0], [20.0, 21.5]];
        let edit = Edit {
            base: Some(GivenMotion::one("base".into(), original.clone())),
            regenerate: ranges.to_vec(),
            ..Edit::default()
        };
        let (edited, _) = run(&solo(3, 60.0, None, edit));
        let made = ranges
            .iter()
            .map(|&[a, b]| (a * 30.0) as usize..(b * 30.0) as usize)
            .collect();
        (edited, made)
    })
}

/// The issue asks for a boundary-jerk ratio under 1.5 over the joins (measured like the
/// long-form seams). With the quintic seam blend and the root handed over with its velocity
/// and acceleration it is 1.25 over the four joins (1.46, 1.05, 0.74 and 1.73 one by one; the
/// last is where the base dance spins at 20° a frame and the new part has to meet that turn);
/// 1.72 before.
#[test]
fn regenerated_joins_are_as_smooth_as_the_rest() {
    let (original, _) = base();
    let (edited, made) = regenerated();
    let (jo, je) = (joints(original), joints(edited));
    let q = edit_quality(&jo, &je, made, 30.0).unwrap();
    for b in made.iter().flat_map(|r| [r.start, r.end]) {
        let one = dancegen_metrics::longform::boundary_jerk_ratio(&je, 30.0, &[b]).unwrap();
        eprintln!("  join at frame {b}: boundary jerk ratio {one:?}");
    }
    check_joins(&q, true);
}

#[test]
fn a_regenerated_range_is_new_on_the_beat_and_joins_the_kept_frames() {
    let (original, beats) = base();
    let (edited, made) = regenerated();
    assert_eq!(edited.frames(), original.frames());
    // Kept frames: the input's rotations and root, exactly.
    for f in (0..edited.frames()).filter(|f| !made.iter().any(|r| r.contains(f))) {
        assert_eq!(
            edited.poses[f * 72..(f + 1) * 72],
            original.poses[f * 72..(f + 1) * 72]
        );
        assert_eq!(
            edited.trans[f * 3..(f + 1) * 3],
            original.trans[f * 3..(f + 1) * 3]
        );
    }
    let (jo, je) = (joints(original), joints(edited));
    let q = edit_quality(&jo, &je, made, 30.0).unwrap();
    eprintln!("regenerate {made:?}: {q:?}");
    assert!(q.kept_max_m <= 1e-4, "{q:?}");
    check_joins(&q, false);
    assert!(
        q.new_difference_m >= REAL_POSE_SPREAD_M / 2.0,
        "the new part differs by {:.3} m only",
        q.new_difference_m
    );
    let (whole, part) = assert_on_the_beat(&je, beats, &made[0], "the edit");
    eprintln!("BAS whole {whole:.3}, regenerated {part:.3}");
}

#[test]
fn a_continued_dance_starts_with_the_motions_last_second_and_joins_it() {
    let (original, _) = base();
    let edit = Edit {
        continue_from: Some(GivenMotion::one("base".into(), original.clone())),
        ..Edit::default()
    };
    // The dance continues on the song from where the base ended (89 s), one second early.
    let (cont, _) = run(&solo(1, 88.0, Some(98.0), edit));
    assert_eq!(cont.frames(), 300);
    let from = original.frames() - 30;
    assert_eq!(cont.poses[..30 * 72], original.poses[from * 72..]);
    assert_eq!(cont.trans[..90], original.trans[from * 3..]);
    // Against a "dance" that holds the kept second and then the new part: joins only at 30.
    let jc = joints(&cont);
    let made = vec![std::ops::Range {
        start: 30,
        end: 300,
    }];
    let q = edit_quality(&jc, &jc, &made, 30.0).unwrap();
    eprintln!("continue: {q:?}");
    check_joins(&q, true);
}

#[test]
fn unsupported_and_bad_edits_are_refused_before_any_work() {
    let (original, _) = base();
    let given = GivenMotion::one("base.npz".into(), original.clone());
    let mut group = solo(
        0,
        60.0,
        None,
        Edit {
            base: Some(given.clone()),
            regenerate: vec![[1.0, 2.0]],
            ..Edit::default()
        },
    );
    group.system = SystemRequest::Group(dancegen_generate::systems::group::GroupOptions::new(3));
    let e = generator()
        .run(&group, &|_| {}, &CancelToken::new())
        .unwrap_err();
    // A group edits a group: one dancer's dance is refused, the counts named.
    assert!(
        e.to_string()
            .contains("1 dancer, and this group dance has 3"),
        "{e}"
    );
    // What a system does not apply is refused by name.
    let (arms, _) = dancegen_generate::edit::parse_joint_set("--keep-joints", "arms").unwrap();
    let mut duet = solo(
        0,
        60.0,
        None,
        Edit {
            keep_joints: Some(dancegen_generate::edit::KeepJoints {
                spec: "arms".into(),
                joints: arms,
                root: false,
                from: given.clone(),
            }),
            ..Edit::default()
        },
    );
    duet.system = SystemRequest::Duet(dancegen_generate::systems::duet::DuetOptions::new(
        original.clone(),
        "leader",
    ));
    let e = generator()
        .run(&duet, &|_| {}, &CancelToken::new())
        .unwrap_err();
    assert!(
        e.to_string()
            .contains("--keep-joints is not supported by --system duet"),
        "{e}"
    );
    let outside = solo(
        0,
        60.0,
        None,
        Edit {
            base: Some(given),
            regenerate: vec![[29.0, 31.0]],
            ..Edit::default()
        },
    );
    let e = generator()
        .run(&outside, &|_| {}, &CancelToken::new())
        .unwrap_err();
    assert!(e.to_string().contains("outside the dance"), "{e}");
}

#[test]
fn kept_legs_and_root_stay_and_the_upper_body_is_new() {
    let (original, _) = base();
    let (joints_mask, root) =
        dancegen_generate::edit::parse_joint_set("--keep-joints", "lower").unwrap();
    let edit = Edit {
        keep_joints: Some(dancegen_generate::edit::KeepJoints {
            spec: "lower".into(),
            joints: joints_mask,
            root,
            from: GivenMotion::one("base".into(), original.clone()),
        }),
        ..Edit::default()
    };
    let (new, _) = run(&solo(5, 60.0, None, edit));
    assert_eq!(new.frames(), original.frames());
    for f in 0..new.frames() {
        for j in (0..24).filter(|j| joints_mask & (1 << j) != 0) {
            let at = f * 72 + 3 * j;
            assert_eq!(
                new.poses[at..at + 3],
                original.poses[at..at + 3],
                "frame {f} joint {j}"
            );
        }
        assert_eq!(
            new.trans[f * 3..f * 3 + 3],
            original.trans[f * 3..f * 3 + 3]
        );
    }
    let (jo, jn) = (joints(original), joints(&new));
    // The arms are new: wrists and hands relative to the pelvis, mean distance.
    let mut d = 0.0;
    for f in 0..new.frames() {
        for j in [20, 21, 22, 23] {
            let (a, b) = (f * 72 + 3 * j, f * 72);
            d += (0..3)
                .map(|c| ((jo[a + c] - jo[b + c]) - (jn[a + c] - jn[b + c])).powi(2))
                .sum::<f64>()
                .sqrt();
        }
    }
    let d = d / (4 * new.frames()) as f64;
    let (jerk_o, jerk_n) = (
        edit_common::mean_jerk(original),
        edit_common::mean_jerk(&new),
    );
    eprintln!(
        "kept lower: hands {d:.3} m from the original's; jerk {jerk_n:.0} against {jerk_o:.0}"
    );
    assert!(
        d >= REAL_POSE_SPREAD_M / 2.0,
        "the arms are the old ones ({d:.3} m)"
    );
    assert!(
        jerk_n <= 1.5 * jerk_o,
        "jerk {jerk_n:.0} against {jerk_o:.0}"
    );
}

/// `--keyframe`: frame 100 of the base dance is to be reached at 75 s of the song (the
/// dance's frame 450), with its floor position.
fn keyframed(joints_set: Option<&str>, root: bool) -> SmplMotion {
    let (original, _) = base();
    let pose = KeyframePose {
        spec: "base:100@75".into(),
        t: 75.0,
        pose: original.poses[100 * 72..101 * 72].to_vec(),
        trans: [0, 1, 2].map(|c| original.trans[100 * 3 + c]),
    };
    let keyframe_joints = joints_set.map(|s| {
        let (mask, _) = dancegen_generate::edit::parse_joint_set("--keyframe-joints", s).unwrap();
        (s.to_string(), mask)
    });
    let edit = Edit {
        keyframes: vec![pose],
        keyframe_joints,
        keyframe_root: root,
        ..Edit::default()
    };
    run(&solo(4, 60.0, Some(89.0), edit)).0
}

#[test]
fn a_keyframe_pose_is_reached_in_world_space_and_eased_into() {
    let (original, _) = base();
    let made = keyframed(None, true);
    let (jo, jm) = (joints(original), joints(&made));
    let worst = (0..24)
        .map(|j| {
            (0..3)
                .map(|c| (jm[(450 * 24 + j) * 3 + c] - jo[(100 * 24 + j) * 3 + c]).powi(2))
                .sum::<f64>()
                .sqrt()
        })
        .fold(0.0, f64::max);
    let ratio = dancegen_metrics::longform::boundary_jerk_ratio(&jm, 30.0, &[450]).unwrap();
    let steps: Vec<f64> = (1..made.frames())
        .map(|f| {
            let d = |c: usize| f64::from(made.trans[f * 3 + c] - made.trans[(f - 1) * 3 + c]);
            d(0).hypot(d(2))
        })
        .collect();
    let near = steps[445..455].iter().copied().fold(0.0, f64::max);
    let elsewhere = steps[..440].iter().copied().fold(0.0, f64::max);
    eprintln!(
        "keyframe: worst joint {worst:.4} m from the pose; boundary jerk ratio {ratio:?}; \
         root step {near:.3} m near it, {elsewhere:.3} m elsewhere"
    );
    assert!(
        worst <= 0.03,
        "a keyframed joint is {worst:.3} m from its target"
    );
    let ratio = ratio.expect("a frame inside the dance");
    assert!(
        ratio < JOIN_JERK_RATIO_MAX,
        "boundary jerk ratio {ratio:.2} at the keyframe"
    );
    assert!(
        near <= elsewhere + 0.05,
        "root step {near:.3} m at the keyframe"
    );
}

#[test]
fn keyframed_wrists_are_placed_by_their_arms_and_the_dance_keeps_its_own_height() {
    let (original, _) = base();
    let made = keyframed(Some("left_wrist,right_wrist"), false);
    let (jo, jm) = (joints(original), joints(&made));
    for j in [20, 21] {
        let rel = |m: &[f64], f: usize, c: usize| m[(f * 24 + j) * 3 + c] - m[f * 24 * 3 + c];
        let d = (0..3)
            .map(|c| (rel(&jm, 450, c) - rel(&jo, 100, c)).powi(2))
            .sum::<f64>()
            .sqrt();
        assert!(
            d <= 1e-3,
            "joint {j} is {d:.4} m from the pose around the pelvis"
        );
    }
    // The legs were not given: the pelvis height is the dance's, the feet on the floor.
    let feet = [7, 8, 10, 11].map(|j| jm[(450 * 24 + j) * 3 + 1]);
    let low = feet.iter().copied().fold(f64::INFINITY, f64::min);
    eprintln!(
        "wrists: pelvis {:.3} m against the pose's {:.3} m; lowest foot {low:.3} m",
        jm[450 * 72 + 1],
        jo[100 * 72 + 1]
    );
    assert!(
        low.abs() < 0.05,
        "the lowest foot is {low:.3} m off the floor"
    );
}

#[test]
fn a_path_is_followed_and_the_dance_on_it_stays_whole() {
    let json = r#"{"keyframes": [
        {"t": 62, "positions": [[0, 0]]},
        {"t": 70, "positions": [[1.5, 0.5]]},
        {"t": 78, "positions": [[-1, 1]]}]}"#;
    let file = FormationFile {
        label: "path.json".into(),
        json: json.into(),
    };
    let want = &file.parse(1, 1e9).unwrap().sample(30.0, 89 * 30)[0][60 * 30..];
    let edit = Edit {
        path: Some(file),
        ..Edit::default()
    };
    let (made, _) = run(&solo(6, 60.0, Some(89.0), edit));
    edit_common::assert_path_followed(&made, want, &base().0, "path");
}

/// `--edit --extend`: the 29 s base dance kept whole, then danced on to 95 s of the song.
#[test]
fn an_extended_dance_keeps_the_old_one_and_joins_the_new_part_smoothly() {
    let (original, _) = base();
    let edit = Edit {
        base: Some(GivenMotion::one("base".into(), original.clone())),
        extend: true,
        ..Edit::default()
    };
    let (longer, _) = run(&solo(6, 60.0, Some(95.0), edit));
    let n = original.frames();
    assert_eq!(longer.frames(), 35 * 30);
    assert_eq!(longer.poses[..n * 72], original.poses[..]);
    assert_eq!(longer.trans[..n * 3], original.trans[..]);
    let j = joints(&longer);
    let ratio = dancegen_metrics::longform::boundary_jerk_ratio(&j, 30.0, &[n])
        .unwrap()
        .expect("a join inside the dance");
    eprintln!("extend: boundary jerk ratio {ratio:.2} at the join");
    assert!(
        ratio < JOIN_JERK_RATIO_MAX,
        "boundary jerk ratio {ratio:.2}"
    );
}
