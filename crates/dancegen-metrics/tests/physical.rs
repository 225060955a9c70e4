//! The physical-plausibility figures on motions whose answers are known: the SMPL rest body
//! standing, floating, gliding, teleporting, stepping and with its legs crossed.

use dancegen_formats::bvh_motion::smpl_fk_f64;
use dancegen_metrics::physical::{LEAN_M, SPIKE_SPEED_MS, count_steps, physical, shins_crossed};

const FPS: f64 = 30.0;

/// `frames` frames of the SMPL rest pose (every local rotation identity), the pelvis at
/// `root(t)`, then grounded so the lowest foot joint of the rest pose is at y = 0.
fn rest_body(frames: usize, root: impl Fn(usize) -> [f32; 3]) -> Vec<f64> {
    let poses = vec![0.0_f32; frames * 72];
    let trans: Vec<f32> = (0..frames).flat_map(&root).collect();
    let mut j = smpl_fk_f64(&poses, &trans).unwrap();
    let still = smpl_fk_f64(&[0.0; 72], &[0.0; 3]).unwrap();
    let floor = [7, 8, 10, 11]
        .iter()
        .map(|&k| still[k * 3 + 1])
        .fold(f64::INFINITY, f64::min);
    for v in j.chunks_exact_mut(3) {
        v[1] -= floor;
    }
    j
}

fn joint_mut(j: &mut [f64], t: usize, k: usize) -> &mut [f64] {
    &mut j[(t * 24 + k) * 3..(t * 24 + k) * 3 + 3]
}

#[test]
fn a_standing_body_is_on_the_floor_and_still() {
    let j = rest_body(90, |_| [0.0, 0.0, 0.0]);
    let p = physical(&j, FPS).unwrap();
    assert!(
        p.floor_median.abs() < 1e-9 && p.floor_p05.abs() < 1e-9,
        "{p:?}"
    );
    assert_eq!(p.float_pct, 0.0);
    assert_eq!(p.foot_slide, Some(0.0));
    assert!(p.jerk_mean < 1e-6 && p.jerk_p99 < 1e-6);
    assert_eq!((p.max_step, p.spikes), (0.0, 0));
    assert_eq!(p.leg_cross_pct, 0.0);
    assert_eq!(p.lean_pct, 0.0);
    assert_eq!(
        (p.joint_speed, p.pelvis_speed, p.step_rate),
        (0.0, 0.0, 0.0)
    );
}

#[test]
fn a_lifted_body_floats_and_its_feet_are_never_in_contact() {
    let j = rest_body(60, |_| [0.0, 0.3, 0.0]);
    let p = physical(&j, FPS).unwrap();
    assert!((p.floor_median - 0.3).abs() < 1e-6, "{p:?}");
    assert_eq!(p.float_pct, 100.0);
    assert_eq!(p.foot_slide, None, "no foot joint is ever in contact");
    // Half the time lifted: the float share and the floor percentiles follow.
    let j = rest_body(60, |t| [0.0, if t < 30 { 0.0 } else { 0.3 }, 0.0]);
    let p = physical(&j, FPS).unwrap();
    assert_eq!(p.float_pct, 50.0);
    assert!(p.floor_p05.abs() < 1e-6 && (p.floor_p95 - 0.3).abs() < 1e-6);
}

#[test]
fn a_gliding_body_slides_at_its_speed_with_no_jerk_and_no_steps() {
    // 1.5 m/s along x: every planted foot joint slides at 1.5 m/s, no step is taken (the feet
    // never rest), and a constant velocity has zero jerk.
    let v = 1.5_f32;
    let j = rest_body(60, |t| [v * t as f32 / FPS as f32, 0.0, 0.0]);
    let p = physical(&j, FPS).unwrap();
    let slide = p.foot_slide.unwrap();
    assert!((slide - 1.5).abs() < 1e-4, "{slide}");
    assert!((p.pelvis_speed - 1.5).abs() < 1e-4 && (p.joint_speed - 1.5).abs() < 1e-4);
    assert!(p.jerk_mean < 1e-2, "{}", p.jerk_mean);
    assert_eq!(p.step_rate, 0.0);
}

#[test]
fn a_teleport_is_one_spike_of_its_size() {
    // A 1.2 m jump between frames 40 and 41 (the holistic teleport of issue 41), back at 41.
    let j = rest_body(90, |t| [if t == 41 { 1.2 } else { 0.0 }, 0.0, 0.0]);
    let p = physical(&j, FPS).unwrap();
    assert!((p.max_step - 1.2).abs() < 1e-6, "{}", p.max_step);
    assert_eq!(p.spikes, 2, "there and back");
    assert!(p.jerk_p99 > 1e4);
    // A fast but human move is not a spike: 10 m/s for one frame step.
    let j = rest_body(90, |t| {
        [if t > 41 { 10.0 / FPS as f32 } else { 0.0 }, 0.0, 0.0]
    });
    const { assert!(10.0 < SPIKE_SPEED_MS) };
    assert_eq!(physical(&j, FPS).unwrap().spikes, 0);
}

#[test]
fn crossed_shins_are_found_and_parallel_ones_are_not() {
    let j = rest_body(1, |_| [0.0, 0.0, 0.0]);
    let frame = |j: &[f64]| -> [[f64; 3]; 24] {
        std::array::from_fn(|k| [j[k * 3], j[k * 3 + 1], j[k * 3 + 2]])
    };
    let rest = frame(&j);
    assert!(!shins_crossed(&rest));
    // Swap the legs below the hips sideways: knees, ankles and feet on the other side.
    let mut crossed = rest;
    for (l, r) in [(4, 5), (7, 8), (10, 11)] {
        let (lx, rx) = (crossed[l][0], crossed[r][0]);
        crossed[l][0] = rx;
        crossed[r][0] = lx;
    }
    assert!(shins_crossed(&crossed));
    // The ankles alone swapped, one foot in front of the other (fifth position, a cross-body
    // step): dance, not crossed legs.
    let mut fifth = rest;
    let (lx, rx) = (rest[7][0], rest[8][0]);
    fifth[7][0] = rx;
    fifth[8][0] = lx;
    fifth[7][2] += 0.15;
    fifth[10][2] += 0.15;
    assert!(
        !shins_crossed(&fifth),
        "ankles crossed, one in front: shins clear"
    );
    // Shin axes 2 cm apart: the shins run into each other.
    let mut touching = rest;
    touching[7][0] = 0.5 * (rest[7][0] + rest[8][0]) + 0.01;
    touching[8][0] = touching[7][0] - 0.02;
    assert!(shins_crossed(&touching), "shin axes 2 cm apart");
    // Real-sized check on a clip: every frame crossed gives 100 %.
    let mut clip = rest_body(30, |_| [0.0, 0.0, 0.0]);
    for t in 0..30 {
        for (l, r) in [(4, 5), (7, 8), (10, 11)] {
            let lx = joint_mut(&mut clip, t, l)[0];
            let rx = joint_mut(&mut clip, t, r)[0];
            joint_mut(&mut clip, t, l)[0] = rx;
            joint_mut(&mut clip, t, r)[0] = lx;
        }
    }
    assert_eq!(physical(&clip, FPS).unwrap().leg_cross_pct, 100.0);
}

#[test]
fn steps_are_counted_when_a_foot_travels_between_rests() {
    // The left foot (ankle 7, toe 10) steps 20 cm forward once a second: 10 frames of motion
    // (a raised-cosine lift of 5 cm), 20 frames of rest. 4 s → 4 steps of the left foot.
    let frames = 120;
    let mut j = rest_body(frames, |_| [0.0, 0.0, 0.0]);
    for t in 0..frames {
        let (cycle, phase) = (t / 30, t % 30);
        let progress = if phase < 10 { phase as f64 / 10.0 } else { 1.0 };
        let z = 0.2 * (cycle as f64 + progress);
        let lift = if phase < 10 {
            0.05 * (std::f64::consts::PI * progress).sin()
        } else {
            0.0
        };
        for k in [7, 10] {
            let p = joint_mut(&mut j, t, k);
            p[2] += z;
            p[1] += lift;
        }
    }
    assert_eq!(count_steps(&j, FPS, 7, 10).unwrap(), 4);
    assert_eq!(count_steps(&j, FPS, 8, 11).unwrap(), 0);
    let p = physical(&j, FPS).unwrap();
    assert!(
        (p.step_rate - 4.0 * FPS / 119.0).abs() < 1e-9,
        "{}",
        p.step_rate
    );
    // Read at twice the rate, the same frames step twice as often.
    let fast = physical(&j, 2.0 * FPS).unwrap();
    assert!((fast.step_rate - 2.0 * p.step_rate).abs() < 1e-9);
    assert!((fast.joint_speed - 2.0 * p.joint_speed).abs() < 1e-9);
}

#[test]
fn jitter_raises_the_jerk() {
    // ±1 cm noise on every joint every other frame: jerk ≈ 8 · 0.01 · 30³ per joint.
    let mut j = rest_body(60, |_| [0.0, 0.0, 0.0]);
    for t in 0..60 {
        let s = if t % 2 == 0 { 0.01 } else { -0.01 };
        for k in 0..24 {
            joint_mut(&mut j, t, k)[0] += s;
        }
    }
    let p = physical(&j, FPS).unwrap();
    let expected = 8.0 * 0.01 * FPS.powi(3);
    assert!(
        (p.jerk_mean - expected).abs() < 1e-6 * expected,
        "{}",
        p.jerk_mean
    );
}

#[test]
fn bad_input_is_an_error() {
    assert!(physical(&[0.0; 72 * 3], FPS).is_err(), "three frames");
    assert!(physical(&[0.0; 71], FPS).is_err(), "not whole frames");
    let j = rest_body(10, |_| [0.0, 0.0, 0.0]);
    assert!(physical(&j, 0.0).is_err());
    assert!(physical(&j, f64::NAN).is_err());
}

#[test]
fn entries_name_each_figure_by_its_key() {
    let j = rest_body(60, |t| [0.0, if t < 30 { 0.0 } else { 0.3 }, 0.0]);
    let p = physical(&j, FPS).unwrap();
    let get = |k: &str| p.entries().into_iter().find(|(n, _)| *n == k).unwrap().1;
    assert_eq!(get("float"), Some(p.float_pct));
    assert_eq!(get("floor_p95"), Some(p.floor_p95));
    assert_eq!(get("jerk"), Some(p.jerk_mean));
    assert_eq!(get("spikes"), Some(p.spikes as f64));
    assert_eq!(get("step_rate"), Some(p.step_rate));
    let keys: Vec<&str> = p.entries().iter().map(|(k, _)| *k).collect();
    assert_eq!(keys, dancegen_metrics::physical::KEYS);
}

#[test]
fn a_pelvis_off_its_feet_leans() {
    // The standing body with its pelvis (only) moved sideways: 40 frames by 0.1 m less than
    // LEAN_M, 20 by 0.1 m more (the rest pose's own pelvis stands well within 0.1 m of the ankles'
    // midpoint); the ankles stay where they were.
    let mut j = rest_body(60, |_| [0.0, 0.0, 0.0]);
    for t in 0..60 {
        let off = if t < 40 { LEAN_M - 0.1 } else { LEAN_M + 0.1 };
        let pelvis = joint_mut(&mut j, t, 0);
        pelvis[0] += off * 0.6;
        pelvis[2] += off * 0.8;
    }
    let p = physical(&j, FPS).unwrap();
    assert!((p.lean_pct - 100.0 / 3.0).abs() < 1e-9, "{}", p.lean_pct);
}
