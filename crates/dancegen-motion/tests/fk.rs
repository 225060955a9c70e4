//! Forward kinematics and skeleton tables (rule and offsets: anchors.md C.4; mirrors: C.3).

use dancegen_motion::fk::{
    FkError, LocalRotations, fk_axis_angle_f32, fk_axis_angle_f64, fk_frame, forward_kinematics,
};
use dancegen_motion::rotation::Mat3;
use dancegen_motion::skeleton::{
    SMPL24_MIRROR, SMPLH52_MIRROR, SMPLH52_NAMES, SMPLX55_MIRROR, SMPLX55_NAMES, Skeleton,
};
use std::f64::consts::FRAC_PI_2;
use std::time::Instant;

fn close(a: [f64; 3], b: [f64; 3], tol: f64) -> bool {
    (0..3).all(|i| (a[i] - b[i]).abs() < tol)
}

fn joint(pos: &[f64], j: usize) -> [f64; 3] {
    [pos[3 * j], pos[3 * j + 1], pos[3 * j + 2]]
}

/// Deterministic LCG in [-1, 1).
fn lcg_values(n: usize, seed: u64) -> Vec<f64> {
    let mut s = seed;
    (0..n)
        .map(|_| {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            2.0 * ((s >> 11) as f64 / (1u64 << 53) as f64) - 1.0
        })
        .collect()
}

#[test]
fn identity_pose_gives_cumulative_offsets() {
    let s = Skeleton::smpl24();
    let trans = [0.5, 0.9, -0.2];
    let pos = fk_axis_angle_f64(&s, &[0.0; 72], &trans).unwrap();
    let rest = s.rest_positions();
    for (j, r) in rest.iter().enumerate() {
        let expected = [r[0] + trans[0], r[1] + trans[1], r[2] + trans[2]];
        assert!(close(joint(&pos, j), expected, 1e-12), "joint {j}");
    }
    // Spot check by hand: left knee = lhip + lknee offsets.
    let o = s.offsets();
    let lknee = [o[1][0] + o[4][0], o[1][1] + o[4][1], o[1][2] + o[4][2]];
    assert!(close(
        joint(&pos, 4),
        [lknee[0] + 0.5, lknee[1] + 0.9, lknee[2] - 0.2],
        1e-12
    ));
    // The root sits exactly at the translation.
    assert_eq!(joint(&pos, 0), trans);
}

#[test]
fn elbow_rotation_moves_wrist() {
    let s = Skeleton::smpl24();
    let lelbow = s.index_of("lelbow").unwrap();
    let lwrist = s.index_of("lwrist").unwrap();
    let mut aa = vec![0.0; 72];
    // +90° about Y at the left elbow.
    aa[3 * lelbow + 1] = FRAC_PI_2;
    let pos = fk_axis_angle_f64(&s, &aa, &[0.0; 3]).unwrap();
    let rest = fk_axis_angle_f64(&s, &[0.0; 72], &[0.0; 3]).unwrap();
    // Everything up to the elbow is unchanged.
    assert!(close(joint(&pos, lelbow), joint(&rest, lelbow), 1e-12));
    // Ry(90°) maps (x, y, z) to (z, y, −x): the forearm turns from +X (pointing left) to −Z.
    let off = s.offsets()[lwrist];
    let e = joint(&rest, lelbow);
    let expected = [e[0] + off[2], e[1] + off[1], e[2] - off[0]];
    assert!(close(joint(&pos, lwrist), expected, 1e-12));
    // The bone length is preserved.
    let d = |a: [f64; 3], b: [f64; 3]| {
        ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
    };
    assert!((d(joint(&pos, lwrist), e) - d(joint(&rest, lwrist), e)).abs() < 1e-12);
    // The right arm is unaffected.
    let rwrist = s.index_of("rwrist").unwrap();
    assert!(close(joint(&pos, rwrist), joint(&rest, rwrist), 1e-12));
}

#[test]
fn f32_f64_and_matrix_inputs_agree() {
    let s = Skeleton::smpl24();
    let frames = 50;
    let aa64: Vec<f64> = lcg_values(frames * 72, 1).iter().map(|v| v * 2.0).collect();
    let tr64: Vec<f64> = lcg_values(frames * 3, 2);
    let aa32: Vec<f32> = aa64.iter().map(|&v| v as f32).collect();
    let tr32: Vec<f32> = tr64.iter().map(|&v| v as f32).collect();
    let p64 = fk_axis_angle_f64(&s, &aa64, &tr64).unwrap();
    let p32 = fk_axis_angle_f32(&s, &aa32, &tr32).unwrap();
    assert_eq!(p64.len(), frames * 24 * 3);
    let max_err = p64
        .iter()
        .zip(&p32)
        .map(|(a, b)| (a - *b as f64).abs())
        .fold(0.0, f64::max);
    assert!(max_err < 1e-5, "f32 vs f64 max error {max_err}");

    // Matrix input and world-rotation output agree with the axis-angle path and with fk_frame.
    let mats: Vec<f64> = aa64
        .chunks_exact(3)
        .flat_map(|c| {
            Mat3::from_axis_angle([c[0], c[1], c[2]])
                .0
                .into_iter()
                .flatten()
        })
        .collect();
    let out = forward_kinematics(&s, LocalRotations::Matrix(&mats), &tr64, true).unwrap();
    assert!(
        out.positions
            .iter()
            .zip(&p64)
            .all(|(a, b)| (a - b).abs() < 1e-12)
    );
    let world = out.world_rotations.unwrap();
    let f = 7;
    let local: Vec<Mat3> = aa64[f * 72..(f + 1) * 72]
        .chunks_exact(3)
        .map(|c| Mat3::from_axis_angle([c[0], c[1], c[2]]))
        .collect();
    let mut pos = vec![[0.0; 3]; 24];
    let mut w = vec![Mat3::IDENTITY; 24];
    fk_frame(
        &s,
        &local,
        [tr64[3 * f], tr64[3 * f + 1], tr64[3 * f + 2]],
        &mut pos,
        &mut w,
    );
    for j in 0..24 {
        assert!(close(pos[j], joint(&p64[f * 72..], j), 1e-12));
        let flat: Vec<f64> = w[j].0.into_iter().flatten().collect();
        let got = &world[(f * 24 + j) * 9..(f * 24 + j + 1) * 9];
        assert!(
            flat.iter().zip(got).all(|(a, b)| (a - b).abs() < 1e-12),
            "joint {j}"
        );
    }
}

#[test]
fn shape_errors_are_reported() {
    let s = Skeleton::smpl24();
    assert!(matches!(
        fk_axis_angle_f32(&s, &[0.0; 71], &[0.0; 3]),
        Err(FkError::RotationShape { len: 71, .. })
    ));
    assert!(matches!(
        fk_axis_angle_f32(&s, &[0.0; 144], &[0.0; 3]),
        Err(FkError::TranslationShape {
            rotation_frames: 2,
            ..
        })
    ));
    assert_eq!(fk_axis_angle_f32(&s, &[], &[]).unwrap(), Vec::<f32>::new());
}

#[test]
fn mirror_permutations_are_involutions_mapping_left_to_right() {
    let smpl = Skeleton::smpl24();
    let names = smpl.names();
    let tables: [(&[usize], Vec<&str>); 3] = [
        (&SMPL24_MIRROR, names.iter().map(String::as_str).collect()),
        (&SMPLX55_MIRROR, SMPLX55_NAMES.to_vec()),
        (&SMPLH52_MIRROR, SMPLH52_NAMES.to_vec()),
    ];
    for (perm, names) in tables {
        assert_eq!(perm.len(), names.len());
        for (j, &m) in perm.iter().enumerate() {
            assert_eq!(perm[m], j, "not an involution at {j}");
            let (a, b) = (names[j], names[m]);
            let swapped = if let Some(r) = a.strip_prefix("left_") {
                format!("right_{r}")
            } else if let Some(r) = a.strip_prefix("right_") {
                format!("left_{r}")
            } else if let Some(r) = a.strip_prefix('l') {
                format!("r{r}")
            } else if let Some(r) = a.strip_prefix('r').filter(|_| a != "root") {
                format!("l{r}")
            } else {
                a.to_owned()
            };
            assert_eq!(b, swapped, "mirror of {a}");
        }
    }
    // Mirrored rest offsets of SMPL 24 are approximately x-reflections of each other (the SMPL
    // template is nearly symmetric), which confirms the pairing geometrically.
    let o = smpl.offsets();
    for (j, &m) in SMPL24_MIRROR.iter().enumerate() {
        assert!(
            (o[j][0] + o[m][0]).abs() < 0.03,
            "joint {j}: {:?} vs {:?}",
            o[j],
            o[m]
        );
        assert!((o[j][1] - o[m][1]).abs() < 0.03, "joint {j}");
    }
}

/// Throughput on one hour of 30 fps motion (108,000 frames × 24 joints). Run with
/// `cargo test --release -p dancegen-motion --test fk -- --ignored --nocapture`.
#[test]
#[ignore]
fn fk_throughput_one_hour() {
    let s = Skeleton::smpl24();
    let frames = 108_000;
    let aa: Vec<f32> = lcg_values(frames * 72, 11)
        .iter()
        .map(|&v| v as f32)
        .collect();
    let tr: Vec<f32> = lcg_values(frames * 3, 12)
        .iter()
        .map(|&v| v as f32)
        .collect();
    let _ = fk_axis_angle_f32(&s, &aa[..72 * 1000], &tr[..3000]).unwrap(); // warm up the pool
    let mut best = f64::INFINITY;
    for _ in 0..5 {
        let t0 = Instant::now();
        let pos = fk_axis_angle_f32(&s, &aa, &tr).unwrap();
        best = best.min(t0.elapsed().as_secs_f64());
        assert_eq!(pos.len(), frames * 72);
    }
    let mut best_rot = f64::INFINITY;
    for _ in 0..3 {
        let t0 = Instant::now();
        let out = forward_kinematics(&s, LocalRotations::AxisAngle(&aa), &tr, true).unwrap();
        best_rot = best_rot.min(t0.elapsed().as_secs_f64());
        assert!(out.world_rotations.is_some());
    }
    let single = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let t0 = Instant::now();
    single.install(|| fk_axis_angle_f32(&s, &aa, &tr).unwrap());
    let one = t0.elapsed().as_secs_f64();
    println!(
        "FK SMPL24 {frames} frames: positions {:.1} ms ({:.2e} frames/s, {} threads); \
         +world rotations {:.1} ms ({:.2e} frames/s); 1 thread {:.1} ms ({:.2e} frames/s)",
        best * 1e3,
        frames as f64 / best,
        rayon::current_num_threads(),
        best_rot * 1e3,
        frames as f64 / best_rot,
        one * 1e3,
        frames as f64 / one,
    );
}
