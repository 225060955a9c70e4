//! The floor under a generated dance, frame by frame (`planted_floor_track`): it follows a root
//! that drifts against planted legs, leaves a jump in the air, and stays put under a real take.

mod common;

use dancegen_formats::dispatch::{
    ConvertOptions, LoadOptions, LoadedMotion, convert_motion, load_motion_file_with,
};
use dancegen_motion::repr::SmplMotion;
use dancegen_motion::repr::motion::{FOOT_JOINTS, planted_floor_track};

fn lowest_foot(m: &SmplMotion) -> Vec<f32> {
    let j = m.joints_world().unwrap();
    (0..m.frames())
        .map(|f| {
            FOOT_JOINTS
                .iter()
                .map(|&k| j[(f * 24 + k) * 3 + 1])
                .fold(f32::INFINITY, f32::min)
        })
        .collect()
}

/// A dancer standing still in the rest pose (feet planted) for 10 s at 30 fps whose root rises
/// 0.2 m between 4 and 5 s, as a generated dance's root drifts against its legs; from 7 to
/// 7.5 s it jumps 0.3 m (root and feet moving fast).
fn drifting_standing_dancer() -> SmplMotion {
    let (t, fps) = (300, 30.0f32);
    let mut trans = Vec::with_capacity(t * 3);
    for f in 0..t {
        let s = f as f32 / fps;
        let drift = 0.2 * ((s - 4.0).clamp(0.0, 1.0));
        let jump = if (7.0..7.5).contains(&s) {
            0.3 * (std::f32::consts::PI * (s - 7.0) / 0.5).sin()
        } else {
            0.0
        };
        trans.extend([0.0, 1.0 + drift + jump, 0.0]);
    }
    SmplMotion::new(fps, vec![0.0; t * 72], trans).unwrap()
}

#[test]
fn the_tracked_floor_follows_a_drifting_root_and_keeps_the_jump() {
    let mut m = drifting_standing_dancer();
    let low_before = lowest_foot(&m);
    // One floor for the clip leaves the second half 0.2 m up.
    assert!((low_before[270] - low_before[30] - 0.2).abs() < 1e-4);
    m.put_feet_on_tracked_floor().unwrap();
    let low = lowest_foot(&m);
    // Planted stretches well away from the drift and the jump stand on the floor.
    for f in (0..100).chain(180..200).chain(250..300) {
        assert!(
            low[f].abs() < 0.005,
            "frame {f}: lowest foot {:.3} m",
            low[f]
        );
    }
    // The jump is still a jump: at its top the feet are about 0.3 m up.
    let top = low[210..225]
        .iter()
        .copied()
        .fold(f32::NEG_INFINITY, f32::max);
    assert!((0.25..0.35).contains(&top), "jump top {top:.3} m");
}

#[test]
fn a_real_take_has_one_floor() {
    // Real salsa at its true 60 fps: the tracked floor moves only by capture and retargeting
    // noise (the planted lowest joint is an ankle in some frames, a toe in others; measured
    // 2.6 cm over 60_13), far less than the 0.2 m drift it follows in generated dances.
    let path = common::shared_dir().join("data/cmu-salsa/60_13_scaled.bvh");
    let loaded = load_motion_file_with(
        &path,
        &LoadOptions {
            source_fps: Some(60.0),
            ..Default::default()
        },
    )
    .unwrap();
    let opts = ConvertOptions {
        fps: Some(30.0),
        to_smpl24: true,
        ..Default::default()
    };
    let LoadedMotion::Smpl(m) = convert_motion(&path, loaded, &opts).unwrap() else {
        panic!("not SMPL");
    };
    let track = planted_floor_track(&m.joints_world().unwrap(), m.fps).unwrap();
    let lo = track.iter().copied().fold(f32::INFINITY, f32::min);
    let hi = track.iter().copied().fold(f32::NEG_INFINITY, f32::max);
    eprintln!("60_13 tracked floor spans {:.1} cm", (hi - lo) * 100.0);
    assert!(
        hi - lo < 0.04,
        "the floor under a real take moved {:.3} m",
        hi - lo
    );
}

/// A dancer in the rest pose gliding along x at 1 m/s for 2 s (its feet slide, so no foot is
/// planted) whose root rises 0.1 m during the glide, standing still before and after.
fn gliding_dancer() -> SmplMotion {
    let (t, fps) = (300, 30.0f32);
    let mut trans = Vec::with_capacity(t * 3);
    for f in 0..t {
        let s = f as f32 / fps;
        let u = ((s - 4.0) / 2.0).clamp(0.0, 1.0);
        let rise = 0.1 * (std::f32::consts::PI * u).sin();
        trans.extend([u * 2.0, 1.0 + rise, 0.0]);
    }
    SmplMotion::new(fps, vec![0.0; t * 72], trans).unwrap()
}

#[test]
fn a_glide_longer_than_a_flight_stands_on_its_sliding_foot() {
    let mut m = gliding_dancer();
    let before = lowest_foot(&m);
    assert!(before[150] - before[30] > 0.09, "the glide is 0.1 m up");
    m.put_feet_on_tracked_floor().unwrap();
    let low = lowest_foot(&m);
    // Every frame of the glide stands on the floor, within what the tracker's 0.5 s Gaussian
    // leaves of a 0.1 m rise over 2 s (measured: 2.6 cm; without the flight rule the middle of
    // the glide is 0.1 m up).
    let worst = low[120..180]
        .iter()
        .copied()
        .fold(0.0f32, |a, b| a.max(b.abs()));
    assert!(
        worst < 0.03,
        "lowest foot {worst:.3} m from the floor in the glide"
    );
}
