//! The reactive pipeline on a small random model: output shape and length, determinism, and
//! that the follower moves with the leader (the pair stays a couple wherever it stands).

use dancegen_motion::repr::motion::{POSE_DIMS, SMPL_JOINTS};
use dancegen_motion::repr::{DuetFollower, DuetLeader, SmplMotion};
use dancegen_nn::device;
use dancegen_reactdance::blc::{LatentSampling, LongForm};
use dancegen_reactdance::bundle::{BundleConfig, DuetModel, KIND, MeanStd};
use dancegen_reactdance::config::{
    DenoiserConfig, HfsqAutoencoderConfig, MUSIC_DIMS, SamplingDefaults,
};
use dancegen_reactdance::pipeline::generate_follower;

fn model() -> DuetModel {
    let dev = device::inference();
    dev.seed(9);
    let autoencoder = HfsqAutoencoderConfig {
        width: 16,
        depth: 1,
        ..Default::default()
    };
    let denoiser = DenoiserConfig {
        d_model: 32,
        n_layers: 1,
        n_heads: 4,
        d_ff: 64,
        block_tokens: 8,
        timesteps: 100,
        ..Default::default()
    };
    let dims = DuetFollower::DIMS + DuetLeader::DIMS;
    DuetModel {
        dir: "memory".into(),
        autoencoder: autoencoder.init(&dev),
        denoiser: denoiser.init(
            autoencoder.latent_dim(),
            autoencoder.frames_per_token(),
            &dev,
        ),
        config: BundleConfig {
            kind: KIND.into(),
            name: "test".into(),
            fps: 30.0,
            heading_sigma: 20.0,
            autoencoder,
            denoiser,
            sampling: SamplingDefaults::default(),
        },
        norm: MeanStd {
            kind: "mean_std".into(),
            mean: vec![0.0; dims],
            std: vec![1.0; dims],
        },
    }
}

fn leader(frames: usize) -> SmplMotion {
    let mut poses = vec![0f32; frames * POSE_DIMS];
    let mut trans = Vec::new();
    for f in 0..frames {
        let s = f as f32 * 0.1;
        for j in 0..SMPL_JOINTS {
            poses[f * POSE_DIMS + 3 * j] = 0.2 * (s + j as f32).sin();
        }
        poses[f * POSE_DIMS + 1] = 0.03 * f as f32;
        trans.extend([0.01 * f as f32, 0.95, 0.2 * s.cos()]);
    }
    SmplMotion::new(30.0, poses, trans).unwrap()
}

fn sampling(long_form: LongForm) -> LatentSampling {
    LatentSampling {
        steps: 3,
        eta: 1.0,
        guidance: vec![1.0, 0.5],
        seed: 4,
        long_form,
    }
}

#[test]
fn follower_has_the_leaders_length_and_moves_with_it() {
    let m = model();
    let dev = device::inference();
    // 75 frames: not a whole number of 4-frame tokens nor of 8-token blocks.
    let l = leader(75);
    let music: Vec<f32> = (0..80 * MUSIC_DIMS)
        .map(|i| (i as f32 * 0.01).sin())
        .collect();
    for lf in [LongForm::Blc, LongForm::Autoregressive] {
        let a = generate_follower(&m, &l, &music, &sampling(lf), None, &dev).unwrap();
        assert_eq!(a.follower.frames(), 75, "{lf:?}");
        assert!(
            a.follower
                .poses
                .iter()
                .chain(&a.follower.trans)
                .all(|v| v.is_finite())
        );
        let again = generate_follower(&m, &l, &music, &sampling(lf), None, &dev).unwrap();
        assert_eq!(
            a.follower.trans, again.follower.trans,
            "{lf:?}: same seed, same dance"
        );
        // The couple moved 3 m sideways and 0.5 m up (a raised floor): the follower moves too.
        let mut moved = l.clone();
        for p in moved.trans.chunks_exact_mut(3) {
            p[0] += 3.0;
            p[1] += 0.5;
        }
        let b = generate_follower(&m, &moved, &music, &sampling(lf), None, &dev).unwrap();
        for (pa, pb) in a
            .follower
            .trans
            .chunks_exact(3)
            .zip(b.follower.trans.chunks_exact(3))
        {
            assert!(
                (pb[0] - pa[0] - 3.0).abs() < 1e-3,
                "{lf:?}: x {pa:?} -> {pb:?}"
            );
            assert!(
                (pb[1] - pa[1] - 0.5).abs() < 1e-3,
                "{lf:?}: y {pa:?} -> {pb:?}"
            );
            assert!((pb[2] - pa[2]).abs() < 1e-3, "{lf:?}: z {pa:?} -> {pb:?}");
        }
    }
}

#[test]
fn too_little_music_is_an_error() {
    let m = model();
    let e = generate_follower(
        &m,
        &leader(40),
        &vec![0.0; 20 * MUSIC_DIMS],
        &sampling(LongForm::Blc),
        None,
        &device::inference(),
    )
    .err()
    .unwrap();
    assert!(
        e.contains("20 music frames") && e.contains("40-frame leader"),
        "{e}"
    );
}

/// Frames in which the two bodies interpenetrate (hands exempt), on world joints.
fn penetrating_frames(a: &SmplMotion, b: &SmplMotion) -> usize {
    use dancegen_motion::capsule_body::frame_joints;
    use dancegen_refine::couple_separation::deepest_overlap;
    let j = |m: &SmplMotion| -> Vec<f64> {
        m.joints_world()
            .unwrap()
            .into_iter()
            .map(f64::from)
            .collect()
    };
    let (ja, jb) = (j(a), j(b));
    (0..a.frames())
        .filter(|&f| deepest_overlap(&frame_joints(&ja, f), &frame_joints(&jb, f), 0.0).is_some())
        .count()
}

#[test]
fn separation_moves_the_follower_out_of_the_leader_and_changes_nothing_else() {
    use dancegen_refine::couple_separation::SeparationConfig;
    let m = model();
    let dev = device::inference();
    let l = leader(48);
    let music = vec![0.1f32; 48 * MUSIC_DIMS];
    let s = sampling(LongForm::Blc);
    let raw = generate_follower(&m, &l, &music, &s, None, &dev).unwrap();
    // An untrained model puts the follower about where the leader is.
    assert_eq!(raw.separation_max_m, 0.0);
    let sep = SeparationConfig::default();
    let out = generate_follower(&m, &l, &music, &s, Some(&sep), &dev).unwrap();
    // Fewer overlapping frames; not necessarily none: the rounds bound how fast the follower
    // may be moved, and an untrained model's follower starts inside the leader.
    let (before, after) = (
        penetrating_frames(&raw.follower, &l),
        penetrating_frames(&out.follower, &l),
    );
    assert!(
        after < before,
        "{after} of 48 frames overlap, {before} before"
    );
    assert_eq!(out.follower.poses, raw.follower.poses);
    let mut largest = 0.0f64;
    for (a, b) in raw
        .follower
        .trans
        .chunks_exact(3)
        .zip(out.follower.trans.chunks_exact(3))
    {
        assert_eq!(a[1], b[1], "heights are kept");
        largest = largest.max(f64::from(b[0] - a[0]).hypot(f64::from(b[2] - a[2])));
    }
    assert!(largest > 0.05 && (largest - out.separation_max_m).abs() < 1e-4);
}
