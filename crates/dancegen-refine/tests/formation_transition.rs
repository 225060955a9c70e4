//! Transitions between formations: exact endpoints, swaps that keep 0.45 m, collisions named.

use dancegen_refine::formation::transition::{
    SWAP_LATERAL_OFFSET_M, TransitionError, TransitionKind, UPSTAGE_PASS_DEPTH_M, bow,
    plan_transition, swap_targets,
};
use dancegen_refine::formation::{
    MIN_SEPARATION_M, StagePos, min_pairwise_distance, order_left_to_right,
};

/// `n` dancers in a line across the stage, `spacing` apart.
fn line(n: usize, spacing: f64) -> Vec<StagePos> {
    (0..n)
        .map(|i| [(i as f64 - (n as f64 - 1.0) / 2.0) * spacing, 0.0])
        .collect()
}

#[test]
fn neighbour_swaps_in_a_line_keep_apart_and_end_swapped() {
    for n in 2..=5 {
        let from = line(n, 0.9);
        for i in 0..n - 1 {
            let to = swap_targets(&from, i, i + 1);
            let kinds = [
                TransitionKind::LateralSwap { a: i, b: i + 1 },
                TransitionKind::LateralSwap { a: i + 1, b: i },
                TransitionKind::UpstagePass {
                    behind: i,
                    front: i + 1,
                },
                TransitionKind::UpstagePass {
                    behind: i + 1,
                    front: i,
                },
            ];
            // 2–4 beats at 90–180 BPM (group.md §4.4) is 20–80 frames at 30 fps.
            for kind in kinds {
                for frames in [2, 3, 20, 45, 80] {
                    let paths = plan_transition(&from, &to, kind, frames)
                        .unwrap_or_else(|e| panic!("n {n}, {kind:?}, {frames} frames: {e}"));
                    for d in 0..n {
                        assert_eq!(paths[d].len(), frames);
                        assert_eq!(paths[d][0], from[d]);
                        assert_eq!(paths[d][frames - 1], to[d]);
                    }
                    let closest = min_pairwise_distance(&paths).unwrap();
                    assert!(
                        closest.pair.distance >= MIN_SEPARATION_M,
                        "{kind:?}: {closest:?}"
                    );
                    let end: Vec<StagePos> = paths.iter().map(|p| p[frames - 1]).collect();
                    let mut expected: Vec<usize> = (0..n).collect();
                    expected.swap(i, i + 1);
                    assert_eq!(order_left_to_right(&end), expected);
                }
            }
        }
    }
}

#[test]
fn swaps_bow_the_way_they_say() {
    let from = line(2, 0.9);
    let to = swap_targets(&from, 0, 1);
    let mid = 30; // frame 30 of 61 is τ = ½
    let lateral = plan_transition(&from, &to, TransitionKind::LateralSwap { a: 0, b: 1 }, 61);
    let lateral = lateral.unwrap();
    // Dancer 0 (on the left) passes downstage, dancer 1 upstage, 0.4 m each.
    assert!((lateral[0][mid][1] - SWAP_LATERAL_OFFSET_M).abs() < 1e-12);
    assert!((lateral[1][mid][1] + SWAP_LATERAL_OFFSET_M).abs() < 1e-12);
    let pass = TransitionKind::UpstagePass {
        behind: 1,
        front: 0,
    };
    let pass = plan_transition(&from, &to, pass, 61).unwrap();
    assert!((pass[1][mid][1] + UPSTAGE_PASS_DEPTH_M).abs() < 1e-12);
    assert!(pass[1].iter().all(|p| p[1] <= 0.0));
    assert!(
        pass[0].iter().all(|p| p[1] == 0.0),
        "the front dancer stays on its line"
    );
    assert_eq!(bow(0.0), 0.0);
    assert_eq!(bow(1.0), 0.0);
    assert_eq!(bow(0.5), 1.0);
}

#[test]
fn straight_swap_collision_is_reported_with_pair_and_frame() {
    let from = line(3, 0.9);
    let to = swap_targets(&from, 1, 2);
    let err = plan_transition(&from, &to, TransitionKind::Direct, 31).unwrap_err();
    assert_eq!(
        err,
        TransitionError::TooClose {
            a: 1,
            b: 2,
            frame: 15,
            distance: 0.0
        }
    );
    let message = err.to_string();
    assert!(
        message.contains("dancers 1 and 2") && message.contains("frame 15"),
        "{message}"
    );
    // A front-to-back exchange cannot pass upstage along its own line.
    let column = [[0.0, 0.45], [0.0, -0.45]];
    let to = swap_targets(&column, 0, 1);
    let pass = TransitionKind::UpstagePass {
        behind: 0,
        front: 1,
    };
    assert!(matches!(
        plan_transition(&column, &to, pass, 31),
        Err(TransitionError::TooClose { a: 0, b: 1, .. })
    ));
    // ...but a lateral swap goes round sideways.
    let lateral = TransitionKind::LateralSwap { a: 0, b: 1 };
    assert!(plan_transition(&column, &to, lateral, 31).is_ok());
    // Moving the whole group keeps the spacing.
    let shifted: Vec<StagePos> = from.iter().map(|p| [p[0] + 1.0, p[1] - 2.0]).collect();
    assert!(plan_transition(&from, &shifted, TransitionKind::Direct, 40).is_ok());
}

#[test]
fn bad_requests_are_errors() {
    let from = line(2, 0.9);
    let swap = TransitionKind::LateralSwap { a: 0, b: 1 };
    assert_eq!(
        plan_transition(&from, &from[..1], swap, 10),
        Err(TransitionError::LengthMismatch { from: 2, to: 1 })
    );
    assert_eq!(
        plan_transition(&from, &from, swap, 1),
        Err(TransitionError::TooFewFrames { frames: 1 })
    );
    let nan = [[0.0, 0.0], [f64::NAN, 0.0]];
    assert_eq!(
        plan_transition(&from, &nan, swap, 10),
        Err(TransitionError::NotFinite {
            formation: "second",
            dancer: 1
        })
    );
    let far = TransitionKind::UpstagePass {
        behind: 0,
        front: 7,
    };
    assert_eq!(
        plan_transition(&from, &from, far, 10),
        Err(TransitionError::NoSuchDancer {
            dancer: 7,
            dancers: 2
        })
    );
    let same = TransitionKind::LateralSwap { a: 1, b: 1 };
    assert_eq!(
        plan_transition(&from, &from, same, 10),
        Err(TransitionError::SameDancer(1))
    );
}
