//! The Lodge++ inference path on a tiny randomly initialised model: every sampler produces the
//! song's length of finite frames, hard cues hold exactly, and the penetration guidance lowers
//! the capsule penetration energy of a pose with the forearm inside the chest.

use dancegen_lodgepp::bundle::{BundleConfig, GptSection, MeanStd, SamplingDefaults, SoloModel};
use dancegen_lodgepp::config::{ChoreoGptConfig, PddmConfig, PddmTable};
use dancegen_lodgepp::layout::{DIMS, MAIN_DIMS, leg_channels, rot6d};
use dancegen_lodgepp::library::PrimitiveLibrary;
use dancegen_lodgepp::penetration::{CapsulePairs, PenetrationGuidance, guide, penetration_energy};
use dancegen_lodgepp::pipeline::{GenerateOptions, Sampler};
use dancegen_lodgepp::sampler::{FootRefineScope, HardCues, PddmSampleOptions, sample_windows};
use dancegen_lodgepp::{Device, inference_device};
use dancegen_motion::rotation::Mat3;
use dancegen_nn::autoencoder::MotionAutoencoderConfig;
use dancegen_nn::burn::module::Param;
use dancegen_nn::burn::tensor::{Tensor, TensorData};
use dancegen_nn::conv::ConvCodecConfig;
use dancegen_nn::loss::FkSkeleton;
use dancegen_nn::quant::QuantizerConfig;
use dancegen_nn::quant::vq::EmaVqConfig;

const WINDOW: usize = 32;

/// A T-pose-ish frame: identity rotations, root at 0.9 m height (Z-up).
fn rest_frame() -> Vec<f32> {
    let mut f = vec![0f32; DIMS];
    f[6] = 0.9;
    let id = Mat3::IDENTITY.to_6d();
    for j in 0..24 {
        for k in 0..6 {
            f[rot6d(j, k)] = id[k] as f32;
        }
    }
    f
}

fn tiny_model(device: &Device) -> SoloModel {
    tiny_model_with(device, false)
}

/// [`tiny_model`], sampling in per-window heading frames when `canonical_heading`.
fn tiny_model_with(device: &Device, canonical_heading: bool) -> SoloModel {
    let genres = vec!["a".to_string(), "b".to_string()];
    let vqvae = MotionAutoencoderConfig::new(
        ConvCodecConfig::new(MAIN_DIMS, MAIN_DIMS)
            .with_width(16)
            .with_depth(1)
            .with_code_dim(8),
        QuantizerConfig::Vq(EmaVqConfig::new(16, 8)),
    );
    let gpt = ChoreoGptConfig {
        d_model: 16,
        n_layers: 1,
        n_heads: 2,
        music_d: 12,
        music_layers: 1,
        music_heads: 2,
        window_tokens: 16,
        overlap_tokens: 4,
        dropout: 0.0,
    };
    let mut pddm: PddmTable = toml::from_str("").unwrap();
    pddm.pddm = PddmConfig {
        d_model: 16,
        n_layers: 1,
        n_heads: 2,
        d_ff: 32,
        music_layers: 1,
        dropout: 0.0,
        foot_refine: true,
        window: WINDOW,
        canonical_heading,
        x0_skip: false,
    };
    pddm.shift.steps = 8;
    pddm.genres = genres.clone();
    pddm.use_discriminator = false;
    // Raw = normalised (identity statistics) except heights etc. are fine for a smoke test.
    let norm = MeanStd {
        kind: "mean_std".into(),
        mean: rest_frame().iter().map(|&v| f64::from(v)).collect(),
        std: vec![0.1; DIMS],
    };
    let vqvae_norm = norm.clone();
    // A library of real-looking clips: rest pose with a swinging elbow.
    let motion: Vec<f32> = (0..200)
        .flat_map(|t| {
            let mut f = vec![0f32; DIMS];
            f[rot6d(18, 0)] = (t as f32 * 0.3).sin();
            f
        })
        .collect();
    let library = PrimitiveLibrary::build([(motion.as_slice(), Some(0))]);
    assert!(!library.is_empty());
    let config = BundleConfig {
        kind: "lodgepp".into(),
        name: "tiny".into(),
        fps: 30.0,
        genres: genres.clone(),
        default_genre: "a".into(),
        vqvae: vqvae.clone(),
        gpt: GptSection {
            gpt: gpt.clone(),
            codes: 16,
        },
        pddm: pddm.clone(),
        sampling: SamplingDefaults {
            steps: 8,
            penetration_steps: 2,
            ..Default::default()
        },
    };
    SoloModel {
        dir: ".".into(),
        vqvae: vqvae.init(device),
        gpt: gpt.init(16, genres.len(), device),
        pddm: pddm.init(&norm.mean, &norm.std, device).denoiser,
        config,
        vqvae_norm,
        norm,
        library,
    }
}

#[test]
fn every_sampler_dances_the_whole_song() {
    let device = inference_device();
    let grad = device.clone().autodiff();
    let frames = 150;
    let music: Vec<f32> = (0..frames * 35)
        .map(|i| ((i % 35) as f32 * 0.1).sin())
        .collect();
    let beats: Vec<usize> = (0..frames).step_by(12).collect();
    for (canonical, sampler) in [false, true].into_iter().flat_map(|c| {
        [Sampler::Lodgepp, Sampler::Autoregressive, Sampler::Edge].map(move |s| (c, s))
    }) {
        let model = tiny_model_with(&device, canonical);
        let mut opts = GenerateOptions::defaults(&model, 1, 3);
        opts.sampler = sampler;
        let d = model.generate(&music, &beats, &opts, &device, &grad);
        assert_eq!(
            d.n_frames, frames,
            "{sampler:?}, heading frames {canonical}"
        );
        assert_eq!(d.frames.len(), frames * DIMS);
        assert!(
            d.frames.iter().all(|v| v.is_finite()),
            "{sampler:?}, heading frames {canonical}"
        );
        let again = model.generate(&music, &beats, &opts, &device, &grad);
        assert_eq!(
            d.frames, again.frames,
            "{sampler:?} (heading frames {canonical}) is deterministic given the seed"
        );
        if sampler == Sampler::Lodgepp {
            assert_eq!(d.windows, frames.div_ceil(WINDOW));
        }
    }
}

#[test]
fn hard_cues_hold_exactly() {
    let device = inference_device();
    let grad = device.clone().autodiff();
    let model = tiny_model(&device);
    let (b, t) = (2, WINDOW);
    let cond = dancegen_lodgepp::denoiser::PddmCond {
        music: Tensor::zeros([b, t, 35], &device),
        genre: vec![0, 1],
        primitives: Tensor::zeros([b, t, DIMS], &device),
        mask: Tensor::zeros([b, t, 1], &device),
        music_encoded: None,
    };
    let mut m = vec![0f32; b * t * DIMS];
    let mut v = vec![0f32; b * t * DIMS];
    for f in 0..4 {
        for c in 0..DIMS {
            m[f * DIMS + c] = 1.0;
            v[f * DIMS + c] = 0.25 + c as f32 * 1e-3;
        }
    }
    let cues = HardCues {
        values: Tensor::from_data(TensorData::new(v.clone(), [b, t, DIMS]), &device),
        mask: Tensor::from_data(TensorData::new(m.clone(), [b, t, DIMS]), &device),
    };
    let opts = PddmSampleOptions {
        steps: 8,
        guidance: 2.0,
        refine: true,
        refine_last_steps: None,
        refine_scope: Default::default(),
        penetration: None,
        seed: 1,
    };
    let shift = model.config.pddm.shift.schedule();
    let x = sample_windows(
        &model.pddm,
        &shift,
        &cond,
        Some(&cues),
        &opts,
        &device,
        &grad,
    );
    let x: Vec<f32> = x.into_data().convert::<f32>().try_to_vec::<f32>().unwrap();
    for i in 0..x.len() {
        if m[i] == 1.0 {
            assert_eq!(x[i], v[i]);
        }
    }
}

#[test]
fn the_foot_refine_block_acts_on_the_steps_and_channels_asked() {
    let device = inference_device();
    let grad = device.clone().autodiff();
    let mut model = tiny_model(&device);
    // A fresh block adds nothing (its output projection starts at zero): give it a visible
    // refinement, as a trained one has.
    let block = model
        .pddm
        .refine
        .as_mut()
        .expect("the tiny model has the block");
    let w = block.output.weight.val();
    block.output.weight = Param::from_tensor(w.ones_like() * 0.05);
    let (b, t) = (1, WINDOW);
    let music: Vec<f32> = (0..b * t * 35).map(|i| (i % 7) as f32 * 0.1).collect();
    let cond = dancegen_lodgepp::denoiser::PddmCond {
        music: Tensor::from_data(TensorData::new(music, [b, t, 35]), &device),
        genre: vec![0],
        primitives: Tensor::zeros([b, t, DIMS], &device),
        mask: Tensor::zeros([b, t, 1], &device),
        music_encoded: None,
    };
    let shift = model.config.pddm.shift.schedule();
    let sample_with = |steps: usize,
                       refine: bool,
                       refine_last_steps: Option<usize>,
                       refine_scope: FootRefineScope|
     -> Vec<f32> {
        let opts = PddmSampleOptions {
            steps,
            guidance: 2.0,
            refine,
            refine_last_steps,
            refine_scope,
            penetration: None,
            seed: 3,
        };
        sample_windows(&model.pddm, &shift, &cond, None, &opts, &device, &grad)
            .into_data()
            .convert::<f32>()
            .try_to_vec::<f32>()
            .unwrap()
    };
    let sample = |refine: bool, refine_last_steps: Option<usize>| {
        sample_with(8, refine, refine_last_steps, FootRefineScope::All)
    };
    let (off, every) = (sample(false, None), sample(true, None));
    assert_ne!(off, every, "the block changes the sample");
    assert_eq!(sample(true, Some(0)), off, "on no step = off");
    assert_eq!(sample(true, Some(8)), every, "on all 8 steps = every step");
    assert_eq!(sample(false, Some(2)), off, "refine = false wins");
    let last_two = sample(true, Some(2));
    assert!(
        last_two != off && last_two != every,
        "on the last 2 of 8 steps: in between"
    );

    // One step: the sample is that step's x̂0, so the scope shows channel by channel. `Legs`
    // takes the refined values on the leg channels and the main decoder's elsewhere.
    let one = |refine: bool, scope| sample_with(1, refine, None, scope);
    let off1 = one(false, FootRefineScope::All);
    let every1 = one(true, FootRefineScope::All);
    let legs1 = one(true, FootRefineScope::Legs);
    let legs = leg_channels();
    // `main + (refined − main) · 1` equals `refined` only up to f32 rounding of the two
    // operations (a few ulps, ~1e-7 relative); 1e-5 leaves room for the sampler's last step,
    // which is the same function of x̂0 in all three runs.
    for (i, &v) in legs1.iter().enumerate() {
        let want = if legs.contains(&(i % DIMS)) {
            every1[i]
        } else {
            off1[i]
        };
        assert!(
            (v - want).abs() <= 1e-5 * (1.0 + want.abs()),
            "value {i}: {v} vs {want}"
        );
    }
    assert_ne!(legs1, off1, "the legs are refined");
    assert_ne!(legs1, every1, "the arms are not");
}

#[test]
fn penetration_guidance_pulls_the_forearm_out_of_the_chest() {
    let device = inference_device();
    let grad = device.clone().autodiff();
    // Identity statistics: normalised = raw.
    let denorm = dancegen_lodgepp::kinematics::Denormalize::from_mean_std(
        &[0.0; DIMS],
        &[1.0; DIMS],
        &device,
    );
    let pairs = CapsulePairs::new();
    let energy = |x: &Tensor<3>| -> f32 {
        let j =
            dancegen_lodgepp::kinematics::joints(denorm.apply(x.clone()), &FkSkeleton::smpl24())
                .reshape([1, 24, 3]);
        penetration_energy(pairs.depths(j)).into_scalar()
    };
    // The most penetrating of a grid of left shoulder / elbow bends about the body's vertical
    // axis (arm swung in front of and into the chest).
    let pose = |a: f64, b: f64| {
        let mut f = rest_frame();
        let bend = |angle: f64| Mat3::from_axis_angle([0.0, angle, 0.0]).to_6d();
        for (j, r) in [(16usize, bend(a)), (18, bend(b))] {
            for k in 0..6 {
                f[rot6d(j, k)] = r[k] as f32;
            }
        }
        f
    };
    let mut best = (0.0f32, rest_frame());
    for i in -10..=10 {
        for k in -10..=10 {
            let f = pose(i as f64 * 0.3, k as f64 * 0.3);
            let e = energy(&Tensor::from_data(
                TensorData::new(f.clone(), [1, 1, DIMS]),
                &device,
            ));
            if e > best.0 {
                best = (e, f);
            }
        }
    }
    let f = best.1;
    let x0 = Tensor::<3>::from_data(TensorData::new(f.clone(), [1, 1, DIMS]), &device);
    let before = energy(&x0);
    assert!(
        before > 0.5,
        "the constructed pose penetrates (energy {before})"
    );
    let g = PenetrationGuidance {
        scale: 0.05,
        iterations: 20,
    };
    // A batch of [rest pose, penetrating pose]: the rest window has no point inside and must
    // come back bit-identical, the other one is pulled out.
    let rest = rest_frame();
    let batch = Tensor::<3>::from_data(
        TensorData::new([rest.clone(), f.clone()].concat(), [2, 1, DIMS]),
        &device,
    );
    let both: Vec<f32> = guide(batch, &denorm, &pairs, &g, &grad)
        .into_data()
        .convert::<f32>()
        .try_to_vec::<f32>()
        .unwrap();
    assert_eq!(
        &both[..DIMS],
        rest.as_slice(),
        "a window without penetration moved"
    );
    let after_x = Tensor::<3>::from_data(
        TensorData::new(both[DIMS..].to_vec(), [1, 1, DIMS]),
        &device,
    );
    let after = energy(&after_x);
    println!("penetration energy {before:.3} -> {after:.3}");
    assert!(after < 0.5 * before, "{before} -> {after}");
    // Only arm rotations moved.
    let moved: Vec<f32> = after_x
        .into_data()
        .convert::<f32>()
        .try_to_vec::<f32>()
        .unwrap();
    for c in 0..DIMS {
        let arm = [13usize, 14, 16, 17, 18, 19, 20, 21, 22, 23]
            .iter()
            .any(|&j| (rot6d(j, 0)..rot6d(j, 0) + 6).contains(&c));
        if !arm {
            assert_eq!(moved[c], f[c], "channel {c} is not an arm rotation");
        }
    }
}

#[test]
fn foot_lock_holds_a_planted_foot_of_a_gliding_body() {
    // A standing body whose root glides 2 cm per frame along x (Z-up), left foot labelled
    // planted, right foot lifted (knee bent) and labelled free.
    let t = 20;
    let mut frames = Vec::with_capacity(t * DIMS);
    for f in 0..t {
        let mut fr = rest_frame();
        fr[4] = 0.02 * f as f32;
        fr[0] = 1.0; // left ankle contact label
        fr[2] = 1.0; // left toe
        let knee = Mat3::from_axis_angle([1.2, 0.0, 0.0]).to_6d();
        for k in 0..6 {
            fr[rot6d(5, k)] = knee[k] as f32;
        }
        frames.extend(fr);
    }
    let skel = FkSkeleton::smpl24();
    let foot = |frames: &[f32], f: usize, j: usize| {
        let all = dancegen_lodgepp::kinematics::joints_host(frames, &skel);
        [all[(f * 24 + j) * 3], all[(f * 24 + j) * 3 + 1]]
    };
    let before_right: Vec<[f32; 2]> = (0..t).map(|f| foot(&frames, f, 8)).collect();
    dancegen_lodgepp::planted_feet::lock_planted_feet(&mut frames);
    let left0 = foot(&frames, 0, 7);
    for (f, right_before) in before_right.iter().enumerate() {
        let l = foot(&frames, f, 7);
        assert!(
            (l[0] - left0[0]).abs() < 1e-5 && (l[1] - left0[1]).abs() < 1e-5,
            "frame {f}: planted left ankle moved to {l:?} from {left0:?}"
        );
        // The lifted right foot moves with the body: its glide relative to the held foot is
        // gone too, since nothing else moved.
        let r = foot(&frames, f, 8);
        assert!((r[0] - (right_before[0] - 0.02 * f as f32)).abs() < 1e-5);
    }
    // No contact labels: the foot at the support height still counts as planted (geometry);
    // once the body is in the air (feet 40 cm up from frame 10) its glide is left alone.
    let mut jump = Vec::with_capacity(t * DIMS);
    for f in 0..t {
        let mut fr = rest_frame();
        fr[4] = 0.02 * f as f32;
        fr[6] = if f < 10 { 0.9 } else { 1.3 };
        jump.extend(fr);
    }
    dancegen_lodgepp::planted_feet::lock_planted_feet(&mut jump);
    // The correction is smoothed over ROOT_LOCK_SMOOTHING_FRAMES (σ 2): the corner at the
    // take-off spreads over ±6 frames, and the standing foot drifts up to ~1.6 cm in the frame before it
    // (the leg IK, not run here, takes such residuals up on bent legs).
    let x = |f: usize| jump[f * DIMS + 4];
    for f in 1..10 {
        let tol = if f < 4 { 1e-5 } else { 2.5e-2 };
        assert!(
            (x(f) - x(0)).abs() < tol,
            "frame {f}: standing foot glides ({})",
            x(f) - x(0)
        );
    }
    for f in 11..t {
        let tol = if f > 16 { 1e-5 } else { 5e-3 };
        assert!(
            (x(f) - x(f - 1) - 0.02).abs() < tol,
            "frame {f}: in the air, glide kept"
        );
    }
}

#[test]
fn leg_ik_holds_both_planted_feet_when_one_leg_swings() {
    // A body standing with bent knees, both feet labelled planted; the right hip turns a
    // little more every frame, so its foot slides. The root lock can hold one foot; the leg IK
    // holds the other. (A straight leg cannot reach a moved target: that case is reported as
    // unreached, see dancegen_refine::foot_ik.)
    let t = 24;
    let mut frames = Vec::with_capacity(t * DIMS);
    let set = |fr: &mut [f32], j: usize, m: Mat3| {
        let d = m.to_6d();
        for k in 0..6 {
            fr[rot6d(j, k)] = d[k] as f32;
        }
    };
    for f in 0..t {
        let mut fr = rest_frame();
        fr[..4].iter_mut().for_each(|c| *c = 1.0);
        set(&mut fr, 1, Mat3::from_axis_angle([-0.3, 0.0, 0.0]));
        set(&mut fr, 4, Mat3::from_axis_angle([0.6, 0.0, 0.0]));
        set(&mut fr, 5, Mat3::from_axis_angle([0.6, 0.0, 0.0]));
        let swing = Mat3::from_axis_angle([0.0, 0.0, 0.01 * f as f64]);
        set(&mut fr, 2, swing * Mat3::from_axis_angle([-0.3, 0.0, 0.0]));
        frames.extend(fr);
    }
    let original = frames.clone();
    let skel = FkSkeleton::smpl24();
    let report = dancegen_lodgepp::planted_feet::clean_planted_feet(&mut frames);
    assert!(report.adjusted > 0);
    let joints = dancegen_lodgepp::kinematics::joints_host(&frames, &skel);
    let at =
        |f: usize, j: usize| -> [f32; 3] { std::array::from_fn(|a| joints[(f * 24 + j) * 3 + a]) };
    for j in [7, 8, 10, 11] {
        for f in 1..t {
            let (p, q) = (at(f, j), at(0, j));
            let d = ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt();
            // Frames are stored in f32 (6D and root): the pins hold to micrometres.
            assert!(d < 1e-5, "joint {j} moved {d} m by frame {f}");
        }
    }
    // Only the root's horizontal path and the legs' rotations changed.
    let legs: Vec<usize> = [1, 2, 4, 5, 7, 8]
        .iter()
        .flat_map(|&j| rot6d(j, 0)..rot6d(j, 0) + 6)
        .collect();
    for (i, (a, b)) in frames.iter().zip(&original).enumerate() {
        let c = i % DIMS;
        if !(legs.contains(&c) || c == 4 || c == 5) {
            assert_eq!(a, b, "channel {c} changed");
        }
    }
}

/// `PlantedRule::Both`: a low foot the model labels free is left to glide (footwork that slides
/// close to the floor); `Either` pins it. With the label on, both rules hold it.
#[test]
fn planted_rule_both_leaves_a_low_unlabelled_foot_alone() {
    use dancegen_lodgepp::planted_feet::{PlantedRule, lock_planted_feet_with};
    let t = 20;
    let gliding = |label: f32| {
        let mut frames = Vec::with_capacity(t * DIMS);
        for f in 0..t {
            let mut fr = rest_frame();
            fr[4] = 0.02 * f as f32;
            fr[..4].iter_mut().for_each(|c| *c = label);
            frames.extend(fr);
        }
        frames
    };
    let travel = |frames: &[f32]| frames[(t - 1) * DIMS + 4] - frames[4];
    for (label, rule, want) in [
        (0.0, PlantedRule::Either, 0.0),
        (0.0, PlantedRule::Both, 0.02 * (t - 1) as f32),
        (1.0, PlantedRule::Both, 0.0),
    ] {
        let mut frames = gliding(label);
        lock_planted_feet_with(&mut frames, rule);
        let got = travel(&frames);
        assert!(
            (got - want).abs() < 1e-4,
            "label {label}, {rule:?}: travel {got}, want {want}"
        );
    }
}

/// `foot_ik = false` keeps the foot lock's root pass and drops its leg IK: the legs' rotations
/// are the model's (as with no foot lock at all), only the root's path moves. With the IK on
/// the legs' rotations change. A bundle without the key keeps both passes.
#[test]
fn foot_ik_off_leaves_the_legs_as_generated() {
    let device = inference_device();
    let grad = device.clone().autodiff();
    let frames = 96;
    let music: Vec<f32> = (0..frames * 35)
        .map(|i| ((i % 35) as f32 * 0.1).sin())
        .collect();
    let beats: Vec<usize> = (0..frames).step_by(12).collect();
    let model = tiny_model(&device);
    let run = |lock: bool, ik: bool| {
        let mut opts = GenerateOptions::defaults(&model, 1, 5);
        opts.foot_lock = lock;
        opts.foot_ik = ik;
        model.generate(&music, &beats, &opts, &device, &grad).frames
    };
    let (free, root_only, both) = (run(false, false), run(true, false), run(true, true));
    let legs: Vec<usize> = [1, 2, 4, 5, 7, 8]
        .iter()
        .flat_map(|&j| rot6d(j, 0)..rot6d(j, 0) + 6)
        .collect();
    let leg_values = |f: &[f32]| -> Vec<f32> {
        f.chunks_exact(DIMS)
            .flat_map(|fr| legs.iter().map(|&c| fr[c]).collect::<Vec<_>>())
            .collect()
    };
    assert_eq!(leg_values(&root_only), leg_values(&free));
    assert_ne!(
        leg_values(&both),
        leg_values(&free),
        "the leg IK pinned no foot"
    );
    let root_x = |f: &[f32]| f.chunks_exact(DIMS).map(|fr| fr[4]).collect::<Vec<_>>();
    assert_ne!(
        root_x(&root_only),
        root_x(&free),
        "the root lock moved no root"
    );
    let parsed: SamplingDefaults = toml::from_str("foot_lock = true").unwrap();
    assert!(parsed.foot_ik, "older bundles keep both passes");
    let off: SamplingDefaults = toml::from_str("foot_ik = false").unwrap();
    assert!(!off.foot_ik);
}
