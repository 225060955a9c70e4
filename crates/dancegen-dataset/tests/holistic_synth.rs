//! Synthetic hands and face on a real AIST++ body and a real song: the rules of
//! `holistic_synth` produce moving, beat-tied, body- and music-dependent fingers and faces.

mod common;

use dancegen_dataset::Song;
use dancegen_dataset::holistic_synth::hand_poses::{POSES, pose_id};
use dancegen_dataset::holistic_synth::hands::{HandContext, pose_scores};
use dancegen_dataset::holistic_synth::{
    FaceInputs, SynthInputs, synthesize_face, synthesize_hands,
};
use dancegen_formats::aistpp::load_motion;
use dancegen_motion::face::arkit::{ARKIT_COUNT, arkit_index};

/// EDGE-35 columns: onset envelope 0, chroma 21..33.
const ONSET: usize = 0;
const CHROMA: std::ops::Range<usize> = 21..33;

struct Clip {
    joints: Vec<f32>,
    onset: Vec<f32>,
    chroma: Vec<f32>,
    beats: Vec<usize>,
}

fn clip() -> Clip {
    let path = common::aistpp_motions().join("gJS_sFM_cAll_d02_mJS4_ch09.pkl");
    let m = load_motion(&path)
        .unwrap()
        .to_smpl_motion()
        .resample_stride(2);
    let joints = m.joints_world().unwrap();
    let song = Song::analyse(&common::song("metal_madness.ogg")).unwrap();
    let t = m.frames().min(song.frames());
    let f = &song.features;
    Clip {
        joints: joints[..t * 72].to_vec(),
        onset: (0..t).map(|r| f.data[r * f.cols + ONSET]).collect(),
        chroma: (0..t)
            .flat_map(|r| f.data[r * f.cols + CHROMA.start..r * f.cols + CHROMA.end].to_vec())
            .collect(),
        beats: song
            .beat_frames
            .iter()
            .copied()
            .filter(|&b| b < t)
            .collect(),
    }
}

fn std(x: impl Iterator<Item = f32> + Clone) -> f32 {
    let n = x.clone().count() as f32;
    let mean = x.clone().sum::<f32>() / n;
    (x.map(|v| (v - mean).powi(2)).sum::<f32>() / n).sqrt()
}

#[test]
fn fingers_move_change_shape_on_beats_and_stay_in_range() {
    let c = clip();
    let t = c.joints.len() / 72;
    let inp = SynthInputs {
        fps: 30.0,
        joints: &c.joints,
        onset: &c.onset,
        beats: &c.beats,
        seed: 4,
    };
    let h = synthesize_hands(&inp);
    assert_eq!(h.axis_angles.len(), t * 30 * 3);
    assert_eq!(h, synthesize_hands(&inp), "deterministic");
    assert_ne!(
        h,
        synthesize_hands(&SynthInputs { seed: 5, ..inp }),
        "seeded"
    );
    // Not frozen: every finger joint's angle varies over the clip by more than 2 degrees.
    let angle = |f: usize, j: usize| {
        let a = &h.axis_angles[(f * 30 + j) * 3..(f * 30 + j) * 3 + 3];
        (a[0] * a[0] + a[1] * a[1] + a[2] * a[2])
            .sqrt()
            .to_degrees()
    };
    let stds: Vec<f32> = (0..30)
        .map(|j| std((0..t).map(move |f| angle(f, j))))
        .collect();
    eprintln!(
        "{t} frames, {} beats; finger angle std (deg): {stds:.1?}",
        c.beats.len()
    );
    assert!(stds.iter().all(|&s| s > 2.0), "{stds:?}");
    // Within the anatomical ranges (flexion ≤ 100°, with spread ≤ 101°).
    let max = (0..t)
        .flat_map(|f| (0..30).map(move |j| (f, j)))
        .map(|(f, j)| angle(f, j));
    assert!(max.clone().fold(0.0, f32::max) <= 101.2);
    // Shape changes start 3 frames before a beat; both hands change, several shapes are used.
    for hand in 0..2 {
        let mut changes = 0;
        let mut used = std::collections::BTreeSet::new();
        for f in 1..t {
            let (a, b) = (h.targets[(f - 1) * 2 + hand], h.targets[f * 2 + hand]);
            used.insert(b);
            if a != b {
                changes += 1;
                assert!(
                    c.beats.contains(&(f + 3)),
                    "hand {hand}: change at {f}, not 3 before a beat"
                );
            }
        }
        eprintln!("hand {hand}: {changes} shape changes, shapes used {used:?}");
        assert!(
            changes >= 5 && used.len() >= 3,
            "hand {hand}: {changes} changes, {used:?}"
        );
    }
}

#[test]
fn the_shape_follows_the_body_and_the_music() {
    // Over many noisy choices, a raised, extended arm in loud music opens the hand (spread);
    // a low, bent, slow arm in quiet music picks a calm shape.
    let mut rng = dancegen_motion::rng::SplitMix64(1);
    let tally = |c: HandContext, rng: &mut dancegen_motion::rng::SplitMix64| {
        let mut n = [0usize; POSES.len()];
        for _ in 0..2000 {
            let s = pose_scores(&c);
            let noisy: Vec<f32> = s
                .iter()
                .map(|v| v + 0.3 * dancegen_dataset::holistic_synth::signal::gumbel(rng))
                .collect();
            let i = (0..noisy.len())
                .max_by(|&a, &b| noisy[a].total_cmp(&noisy[b]))
                .unwrap();
            n[i] += 1;
        }
        n
    };
    let raised = tally(
        HandContext {
            height: 1.4,
            extension: 1.0,
            speed: 0.6,
            energy: 0.9,
        },
        &mut rng,
    );
    let calm = tally(
        HandContext {
            height: 0.2,
            extension: 0.4,
            speed: 0.1,
            energy: 0.1,
        },
        &mut rng,
    );
    let top = |n: &[usize]| (0..n.len()).max_by_key(|&i| n[i]).unwrap();
    eprintln!("raised: {raised:?}\ncalm: {calm:?}");
    assert_eq!(POSES[top(&raised)].name, "spread");
    assert!(["relaxed", "cupped", "graceful", "pinch"].contains(&POSES[top(&calm)].name));
    // The choice is a distribution, not a lookup.
    assert!(raised.iter().filter(|&&k| k > 0).count() >= 3);
    assert!(raised[pose_id("spread").unwrap()] < 2000);
}

#[test]
fn face_blinks_breathes_and_follows_the_mood() {
    let c = clip();
    let t = c.joints.len() / 72;
    let inp = FaceInputs {
        fps: 30.0,
        frames: t,
        onset: &c.onset,
        chroma: &c.chroma,
        beats: &c.beats,
        seed: 2,
    };
    let f = synthesize_face(&inp);
    assert_eq!(f.weights.len(), t * ARKIT_COUNT);
    assert!(f.weights.iter().all(|w| (0.0..=1.0).contains(w)));
    let col = |name: &str| {
        let k = arkit_index(name).unwrap();
        f.weights
            .iter()
            .skip(k)
            .step_by(ARKIT_COUNT)
            .copied()
            .collect::<Vec<f32>>()
    };
    // Blinks: count closures (rising through 0.9), about 17 a minute.
    let blink = col("eyeBlinkLeft");
    let closures = blink
        .windows(2)
        .filter(|w| w[0] < 0.9 && w[1] >= 0.9)
        .count();
    let per_minute = closures as f32 / (t as f32 / 30.0 / 60.0);
    eprintln!(
        "{t} frames: {closures} blinks ({per_minute:.1}/min), valence {:.2}",
        f.valence
    );
    assert!((5.0..40.0).contains(&per_minute), "{per_minute}");
    // Jaw and brows move; nothing is frozen that the rules drive.
    for name in ["jawOpen", "browInnerUp", "eyeLookOutLeft"] {
        let s = std(col(name).into_iter());
        eprintln!("{name}: std {s:.3}");
        assert!(s > 0.02, "{name} std {s}");
    }
    // Jaw opening follows the energy: correlated with the smoothed onset.
    let jaw = col("jawOpen");
    let e = dancegen_dataset::holistic_synth::signal::smooth(&c.onset, 7);
    let corr = {
        let (mj, me) = (
            jaw.iter().sum::<f32>() / t as f32,
            e.iter().sum::<f32>() / t as f32,
        );
        let cov: f32 = jaw.iter().zip(&e).map(|(a, b)| (a - mj) * (b - me)).sum();
        cov / (std(jaw.iter().copied()) * std(e.iter().copied()) * t as f32)
    };
    eprintln!("jaw vs energy correlation {corr:.2}");
    assert!(corr > 0.5, "{corr}");
    // Mood from the mode: a major triad reads happier than a minor one.
    let triad = |third: usize| {
        let mut row = [0.0f32; 12];
        row[0] = 1.0;
        row[third] = 0.8;
        row[7] = 0.7;
        row.repeat(10)
    };
    use dancegen_dataset::holistic_synth::face::valence;
    assert!(valence(&triad(4), 0.5) > 0.3 && valence(&triad(3), 0.5) < -0.3);
    // ... and the same music in major smiles more than in minor, which frowns.
    let mean_of = |third: usize, name: &str| {
        let chroma = triad(third).repeat(t / 10 + 1);
        let g = synthesize_face(&FaceInputs {
            chroma: &chroma[..t * 12],
            ..inp
        });
        let k = arkit_index(name).unwrap();
        g.weights.iter().skip(k).step_by(ARKIT_COUNT).sum::<f32>() / t as f32
    };
    let (smile_major, smile_minor) = (mean_of(4, "mouthSmileLeft"), mean_of(3, "mouthSmileLeft"));
    let frown_minor = mean_of(3, "mouthFrownLeft");
    eprintln!("smile major {smile_major:.3}, minor {smile_minor:.3}; frown minor {frown_minor:.3}");
    assert!(smile_major > 0.3 && smile_minor < 0.05 && frown_minor > 0.1);
}

/// `holistic` gives every clip, held-out ones too, a `holistic/<clip>.npz` with moving
/// synthetic hands and a face, listed in the manifest; a rebuild is identical.
#[test]
fn dataset_build_attaches_hands_and_faces() {
    use dancegen_dataset::{BuildOptions, build};
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("set");
    let mut opts = BuildOptions::pseudo(
        &out,
        vec![
            common::salsa("60_01_scaled.bvh"),
            common::salsa("61_01_scaled.bvh"),
        ],
        vec![common::song("metal_madness.ogg")],
    );
    opts.hold_out = vec!["61_01_scaled".into()];
    opts.holistic = true;
    let m = build(&opts, &()).expect("build").manifest;
    assert_eq!(m.clips.len(), 2);
    let mut first = Vec::new();
    for c in &m.clips {
        let rel = c.holistic.as_deref().expect("a holistic file");
        assert_eq!(
            rel.starts_with("held_out/"),
            c.motion.starts_with("held_out/"),
            "{rel}"
        );
        let members = dancegen_io::read_npz(&out.join(rel)).unwrap();
        let get = |n: &str| {
            members
                .iter()
                .find(|(k, _)| k == n)
                .map(|(_, a)| a)
                .unwrap()
        };
        assert_eq!(get("hands").shape, [c.frames, 30, 3]);
        assert_eq!(get("face").shape, [c.frames, 52]);
        assert_eq!(get("hand_targets").shape, [c.frames, 2]);
        assert!(get("face").data.iter().all(|v| (0.0..=1.0).contains(v)));
        let hands = &get("hands").data;
        let spread = hands.iter().cloned().fold(f64::MIN, f64::max)
            - hands.iter().cloned().fold(f64::MAX, f64::min);
        assert!(spread > 0.5, "{}: hands barely move ({spread} rad)", c.name);
        first.push(std::fs::read(out.join(rel)).unwrap());
    }
    // Rebuilt: the same bytes.
    build(&opts, &()).unwrap();
    for (c, bytes) in m.clips.iter().zip(&first) {
        assert_eq!(
            &std::fs::read(out.join(c.holistic.as_deref().unwrap())).unwrap(),
            bytes
        );
    }
    // Not for couples.
    opts.pairing = dancegen_dataset::Pairing::Duet;
    let e = build(&opts, &()).unwrap_err().to_string();
    assert!(e.contains("--holistic"), "{e}");
}
