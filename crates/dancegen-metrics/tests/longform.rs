//! Unit tests of the long-form metrics (`dancegen_metrics::longform`) on synthetic motions.

use dancegen_metrics::longform::{boundary_jerk_ratio, mean_joint_jerk, motion_freezing};
use dancegen_metrics::{FRAME_LEN, NUM_JOINTS};

const FPS: f64 = 30.0;

/// Every joint on its own circle (radius 0.2 m, 0.5 Hz, joint-dependent phase and centre):
/// smooth, with constant speed and constant jerk magnitude.
fn circling(frames: usize) -> Vec<f64> {
    let mut v = vec![0.0; frames * FRAME_LEN];
    let omega = 2.0 * std::f64::consts::PI * 0.5 / FPS;
    for t in 0..frames {
        for j in 0..NUM_JOINTS {
            let phase = omega * t as f64 + j as f64 * 0.3;
            let i = t * FRAME_LEN + j * 3;
            v[i] = 0.1 * j as f64 + 0.2 * phase.cos();
            v[i + 1] = 0.05 * j as f64;
            v[i + 2] = 0.2 * phase.sin();
        }
    }
    v
}

/// Holds the pose of frame `from - 1` for all frames `>= from`.
fn freeze_from(mut v: Vec<f64>, from: usize) -> Vec<f64> {
    let frames = v.len() / FRAME_LEN;
    let pose = v[(from - 1) * FRAME_LEN..from * FRAME_LEN].to_vec();
    for t in from..frames {
        v[t * FRAME_LEN..(t + 1) * FRAME_LEN].copy_from_slice(&pose);
    }
    v
}

#[test]
fn freezing_of_frozen_second_half_is_half() {
    // 20 s + 1 frame = 600 steps = 20 windows; frames 300.. hold frame 299 → steps 299.. are 0
    // (301 of 600, so the median is 0 and the exact-zero rule counts the still windows).
    let frames = 20 * 30 + 1;
    let v = freeze_from(circling(frames), 300);
    let f = motion_freezing(&v, FPS).unwrap().unwrap();
    println!("frozen second half: {f}");
    // Window 9 (steps 270..300) has 29 moving steps; windows 10..19 are still.
    assert_eq!(f, 0.5);
}

#[test]
fn freezing_extremes() {
    let moving = circling(10 * 30 + 1);
    assert_eq!(motion_freezing(&moving, FPS).unwrap(), Some(0.0));
    // Still for more than half the time: the median is 0, still windows still count.
    let mostly_still = freeze_from(circling(10 * 30 + 1), 60);
    assert_eq!(motion_freezing(&mostly_still, FPS).unwrap(), Some(0.8));
    let still = freeze_from(circling(10 * 30 + 1), 1);
    assert_eq!(motion_freezing(&still, FPS).unwrap(), Some(1.0));
    // Less than one complete window.
    assert_eq!(motion_freezing(&circling(30), FPS).unwrap(), None);
    assert!(motion_freezing(&[0.0; 5], FPS).is_err());
}

#[test]
fn freezing_counts_slow_windows() {
    // From frame 400 on the motion continues at 1 % of the speed: still counts as frozen
    // (< 5 % of the median). Steps 399.. are slow (201 of 600, fewer than half, so the median
    // is a normal speed); windows 14..19 are fully slow, window 13 has 9 normal steps.
    let frames = 20 * 30 + 1;
    let mut v = circling(frames);
    let anchor = v[399 * FRAME_LEN..400 * FRAME_LEN].to_vec();
    for frame in v[400 * FRAME_LEN..].chunks_exact_mut(FRAME_LEN) {
        for (x, &a) in frame.iter_mut().zip(&anchor) {
            *x = a + 0.01 * (*x - a);
        }
    }
    let f = motion_freezing(&v, FPS).unwrap().unwrap();
    assert_eq!(f, 0.3);
}

#[test]
fn smooth_motion_has_ratio_one() {
    let v = circling(300);
    let jerk = mean_joint_jerk(&v, FPS).unwrap();
    assert_eq!(jerk.len(), 297);
    let r = boundary_jerk_ratio(&v, FPS, &[60, 120, 180, 240])
        .unwrap()
        .unwrap();
    println!("smooth ratio: {r}");
    assert!((r - 1.0).abs() < 1e-6, "{r}");
}

#[test]
fn discontinuity_at_boundary_gives_large_ratio() {
    let mut v = circling(300);
    // Pose jump of 5 cm on every joint between frames 149 and 150.
    for t in 150..300 {
        for j in 0..NUM_JOINTS {
            v[t * FRAME_LEN + j * 3] += 0.05;
        }
    }
    let at = boundary_jerk_ratio(&v, FPS, &[150]).unwrap().unwrap();
    println!("jump at boundary: {at}");
    assert!(at > 100.0, "{at}");
    // Same motion scored at boundaries away from the jump: the jump inflates "elsewhere".
    let away = boundary_jerk_ratio(&v, FPS, &[60, 240]).unwrap().unwrap();
    println!("jump away from boundaries: {away}");
    assert!(away < 1.0, "{away}");
}

#[test]
fn undefined_ratios() {
    let v = circling(300);
    // No boundary → no band.
    assert_eq!(boundary_jerk_ratio(&v, FPS, &[]).unwrap(), None);
    // Boundary far outside the sequence → no band sample.
    assert_eq!(boundary_jerk_ratio(&v, FPS, &[10_000]).unwrap(), None);
    // Too short for a third difference.
    assert_eq!(boundary_jerk_ratio(&circling(3), FPS, &[1]).unwrap(), None);
    // Linear motion with exactly representable positions: zero jerk everywhere.
    let mut lin = vec![0.0; 100 * FRAME_LEN];
    for t in 0..100 {
        for j in 0..NUM_JOINTS {
            lin[t * FRAME_LEN + j * 3] = 0.25 * t as f64;
        }
    }
    assert_eq!(boundary_jerk_ratio(&lin, FPS, &[50]).unwrap(), None);
}
