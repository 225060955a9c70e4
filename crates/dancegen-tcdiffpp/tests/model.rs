//! The TCDiff++ network, losses and samplers on tiny models: what must hold whatever the
//! weights (masking, layouts, Eq. 17, the adaptor's reach, formation control landing on the
//! requested paths, determinism) and that the objective can be learned.

use dancegen_nn::burn::optim::{AdamWConfig, GradientsParams};
use dancegen_nn::burn::tensor::{Device, Distribution, Int, Tensor, TensorData};
use dancegen_nn::device;
use dancegen_nn::diffusion::{Conditioning, Denoiser, Schedule, Solver, Spacing};
use dancegen_nn::edge151::DIMS;
use dancegen_nn::progress::NoHook;
use dancegen_tcdiffpp::config::{DenoiserConfig, LongSampler, PrefixMode, SequenceMixer};
use dancegen_tcdiffpp::denoiser::{GroupCond, GroupDenoiser, MUSIC_DIMS, PreparedGroupDenoiser};
use dancegen_tcdiffpp::footwork::lower_body_channels;
use dancegen_tcdiffpp::layout::{GROUP_DIMS, N_MAX, channel};
use dancegen_tcdiffpp::losses::{GroupBatch, distance_consistency, group_loss, root_velocity};
use dancegen_tcdiffpp::prediction::Prediction;
use dancegen_tcdiffpp::sampler::{GroupRequest, GroupSampleOptions, RootXy, generate};
use dancegen_tcdiffpp::swap::identity_code;

const T: usize = 8;
/// Root x/y std of the test normaliser: not 1, so unit conversions are exercised.
const ROOT_STD: f64 = 0.5;

fn tiny(mixer: SequenceMixer) -> DenoiserConfig {
    DenoiserConfig {
        d_model: 32,
        n_layers: 2,
        n_heads: 2,
        d_ff: 64,
        music_layers: 1,
        dropout: 0.0,
        mixer,
        footwork_hidden: 16,
        ..DenoiserConfig::default()
    }
}

fn stats() -> (Vec<f64>, Vec<f64>) {
    let mean = vec![0.0; DIMS];
    let mut std = vec![1.0; DIMS];
    std[4] = ROOT_STD;
    std[5] = ROOT_STD;
    (mean, std)
}

fn net(cfg: &DenoiserConfig, device: &Device) -> GroupDenoiser {
    let (mean, std) = stats();
    cfg.init(&mean, &std, device)
}

fn values(x: Tensor<3>) -> Vec<f32> {
    x.into_data().convert::<f32>().try_to_vec::<f32>().unwrap()
}

fn cond(b: usize, t: usize, n: usize, device: &Device) -> GroupCond {
    let music = Tensor::<3>::random([b, t, MUSIC_DIMS], Distribution::Normal(0.0, 1.0), device);
    let code: Vec<f32> = (0..b).flat_map(|_| identity_code(n)).collect();
    let swap = Tensor::from_data(TensorData::new(code, [b, N_MAX * N_MAX]), device);
    GroupCond::free(music, vec![n; b], swap)
}

#[test]
fn empty_slots_neither_leak_nor_output() {
    let dev = device::inference();
    for mixer in [SequenceMixer::CrossAttention, SequenceMixer::Mamba] {
        let m = net(&tiny(mixer), &dev);
        let c = cond(1, T, 2, &dev);
        let x = Tensor::<3>::random([1, T, GROUP_DIMS], Distribution::Normal(0.0, 1.0), &dev);
        // The same active dancers, with garbage in the empty slots.
        let mut noisy = values(x.clone());
        let mut clean = noisy.clone();
        for f in 0..T {
            for c in channel(2, 0)..GROUP_DIMS {
                noisy[f * GROUP_DIMS + c] = 100.0;
                clean[f * GROUP_DIMS + c] = 0.0;
            }
        }
        let run = |v: Vec<f32>| {
            values(m.forward(
                Tensor::from_data(TensorData::new(v, [1, T, GROUP_DIMS]), &dev),
                &[500.0],
                &c,
                &[true],
            ))
        };
        let a = run(noisy);
        let b = run(clean);
        for f in 0..T {
            for ch in 0..GROUP_DIMS {
                let (va, vb) = (a[f * GROUP_DIMS + ch], b[f * GROUP_DIMS + ch]);
                if ch >= channel(2, 0) {
                    assert_eq!(va, 0.0, "{mixer:?}: empty slot output must be 0");
                } else {
                    assert!(
                        (va - vb).abs() < 1e-4,
                        "{mixer:?}: empty slots leaked: {va} vs {vb}"
                    );
                }
            }
        }
    }
}

#[test]
fn the_group_is_seen_together() {
    // Changing dancer 1 changes dancer 0's prediction at the same frame (fusion, attention).
    let dev = device::inference();
    let m = net(&tiny(SequenceMixer::CrossAttention), &dev);
    let c = cond(1, T, 2, &dev);
    let x = values(Tensor::<3>::random(
        [1, T, GROUP_DIMS],
        Distribution::Normal(0.0, 1.0),
        &dev,
    ));
    let mut y = x.clone();
    for f in 0..T {
        y[f * GROUP_DIMS + channel(1, 20)] += 3.0;
    }
    let run = |v: Vec<f32>| {
        values(m.forward(
            Tensor::from_data(TensorData::new(v, [1, T, GROUP_DIMS]), &dev),
            &[10.0],
            &c,
            &[true],
        ))
    };
    let (a, b) = (run(x), run(y));
    let changed = (0..T * GROUP_DIMS)
        .filter(|i| i % GROUP_DIMS < DIMS)
        .any(|i| (a[i] - b[i]).abs() > 1e-5);
    assert!(changed, "dancer 0 ignored dancer 1");
}

#[test]
fn stacked_guidance_branches_equal_the_separate_calls() {
    // Guided sampling runs the conditional and the null branch as one batch of 2B; each half
    // must be what the branch gives alone, for every element and with two different group
    // sizes in the batch (the padding masks are stacked too).
    let dev = device::inference();
    let m = net(&tiny(SequenceMixer::CrossAttention), &dev);
    let mut c = cond(2, T, 3, &dev);
    c.dancers = vec![3, 2];
    let prepared = PreparedGroupDenoiser::new(&m, c.clone(), true);
    let x = Tensor::<3>::random([2, T, GROUP_DIMS], Distribution::Normal(0.0, 1.0), &dev);
    let t = || Tensor::<1, Int>::from_data(TensorData::new(vec![400i64, 37], [2]), &dev);
    let (full, null) = prepared.predict_x0_guided(x.clone(), t(), &c);
    let full_alone = prepared.predict_x0(x.clone(), t(), Conditioning::Full(&c));
    let null_alone = prepared.predict_x0(x, t(), Conditioning::Null);
    for (stacked, alone, branch) in [
        (full, full_alone, "conditional"),
        (null, null_alone, "null"),
    ] {
        let (a, b) = (values(stacked), values(alone));
        assert_eq!(a.len(), b.len());
        let worst = a
            .iter()
            .zip(&b)
            .map(|(p, q)| (p - q).abs())
            .fold(0f32, f32::max);
        // Stacking changes only the batch size; every output row is computed from its own
        // inputs, so the halves can differ only by the GEMM kernels' summation order, a few
        // f32 ulps on outputs of order 1 (1e-5 is about 100 ulps at 1).
        assert!(
            worst < 1e-5,
            "{branch} branch differs by {worst} when stacked"
        );
    }
    // Guidance is meaningful here: the branches differ.
    let (full, null) = prepared.predict_x0_guided(
        Tensor::<3>::random([2, T, GROUP_DIMS], Distribution::Normal(0.0, 1.0), &dev),
        t(),
        &c,
    );
    let gap = values(full)
        .iter()
        .zip(values(null))
        .map(|(p, q)| (p - q).abs())
        .fold(0f32, f32::max);
    assert!(gap > 1e-4, "the music made no difference ({gap})");
}

#[test]
fn a_residual_fusion_projection_with_a_silent_mlp_is_the_identity() {
    // With its last layer zeroed the residual FP adds nothing (the network equals one without
    // FP), while the released, non-residual FP wipes the tokens: the residual is what carries
    // x_t past the MLP's hidden width.
    use dancegen_nn::burn::module::Param;
    let dev = device::inference();
    let silent = |residual: bool| {
        let mut m = net(
            &DenoiserConfig {
                fusion_residual: residual,
                ..tiny(SequenceMixer::CrossAttention)
            },
            &dev,
        );
        let fp = m.fusion.as_mut().expect("fusion on by default");
        let w = fp.linear3.weight.val();
        fp.linear3.weight = Param::from_tensor(w.zeros_like());
        if let Some(b) = &fp.linear3.bias {
            fp.linear3.bias = Some(Param::from_tensor(b.val().zeros_like()));
        }
        m
    };
    let residual = silent(true);
    let mut without = residual.clone();
    without.fusion = None;
    let wiped = silent(false);
    let c = cond(1, T, 3, &dev);
    let x = Tensor::<3>::random([1, T, GROUP_DIMS], Distribution::Normal(0.0, 1.0), &dev);
    let run = |m: &GroupDenoiser, x: Tensor<3>| values(m.forward(x, &[10.0], &c, &[true]));
    let (a, b) = (run(&residual, x.clone()), run(&without, x.clone()));
    assert!(a.iter().zip(&b).all(|(p, q)| (p - q).abs() < 1e-5));
    // The wiped network's output no longer depends on x_t.
    let y = Tensor::<3>::random([1, T, GROUP_DIMS], Distribution::Normal(0.0, 1.0), &dev);
    let (p, q) = (run(&wiped, x.clone()), run(&wiped, y.clone()));
    assert!(p.iter().zip(&q).all(|(u, v)| (u - v).abs() < 1e-5));
    let (r, s) = (run(&residual, x), run(&residual, y));
    assert!(r.iter().zip(&s).any(|(u, v)| (u - v).abs() > 1e-3));
}

#[test]
fn footwork_adaptor_touches_only_the_lower_body() {
    let dev = device::inference();
    let m = net(&tiny(SequenceMixer::CrossAttention), &dev);
    let fa = m.footwork.as_ref().expect("footwork on by default");
    let raw = Tensor::<3>::random([1, T * N_MAX, DIMS], Distribution::Normal(0.0, 1.0), &dev);
    let out = values(fa.forward(raw.clone()));
    let raw = values(raw);
    let lower = lower_body_channels();
    let mut replaced = 0;
    for (i, (o, r)) in out.iter().zip(&raw).enumerate() {
        if lower.contains(&(i % DIMS)) {
            replaced += usize::from((o - r).abs() > 1e-6);
        } else {
            assert_eq!(o, r, "channel {} must stay the decoder's", i % DIMS);
        }
    }
    assert!(replaced > 0);
}

#[test]
fn a_residual_footwork_adaptor_starts_as_the_identity_and_then_corrects_the_lower_body() {
    let dev = device::inference();
    let cfg = DenoiserConfig {
        footwork_residual: true,
        ..tiny(SequenceMixer::CrossAttention)
    };
    let mut m = net(&cfg, &dev);
    let raw = Tensor::<3>::random([1, T * N_MAX, DIMS], Distribution::Normal(0.0, 1.0), &dev);
    let fa = m.footwork.as_ref().expect("footwork on by default");
    assert_eq!(values(fa.forward(raw.clone())), values(raw.clone()));
    // Once its last layer is not silent, it adds to the lower body and nothing else.
    let fa = m.footwork.as_mut().unwrap();
    fa.csl3.layer.weight = fa.csl3.layer.weight.clone().map(|w| w.ones_like());
    let out = values(m.footwork.as_ref().unwrap().forward(raw.clone()));
    let lower = lower_body_channels();
    let raw = values(raw);
    for (i, (o, r)) in out.iter().zip(&raw).enumerate() {
        if lower.contains(&(i % DIMS)) {
            assert!((o - r).abs() > 1e-6, "channel {} not corrected", i % DIMS);
        } else {
            assert_eq!(o, r, "channel {} must stay the decoder's", i % DIMS);
        }
    }
}

#[test]
fn distance_consistency_is_equation_17() {
    let dev = device::inference();
    let (b, t, n) = (1, 2, 3);
    let mut gt = vec![0f32; b * t * GROUP_DIMS];
    let mut pred = gt.clone();
    let pos = |v: &mut Vec<f32>, f: usize, s: usize, x: f32, y: f32| {
        v[f * GROUP_DIMS + channel(s, 4)] = x;
        v[f * GROUP_DIMS + channel(s, 5)] = y;
    };
    // Ground truth: a line 1 m apart; prediction: dancer 2 one metre further right at frame 1.
    for f in 0..t {
        for s in 0..n {
            pos(&mut gt, f, s, s as f32, 0.0);
            pos(&mut pred, f, s, s as f32 + 0.5, 0.0); // the whole group shifted: no cost
        }
    }
    pos(&mut pred, 1, 2, 3.5, 0.0);
    let tt = |v: Vec<f32>| Tensor::<3>::from_data(TensorData::new(v, [b, t, GROUP_DIMS]), &dev);
    let l = distance_consistency(tt(pred), tt(gt), &[n]).into_scalar::<f32>();
    // Frame 1: pairs (0,2) and (1,2) each off by 1 m → Σ = 2; / (C − 1) = 1; mean over 2 frames.
    assert!((l - 0.5).abs() < 1e-6, "{l}");
}

#[test]
fn root_velocity_is_the_released_dis_loss_on_root_xy_only() {
    let dev = device::inference();
    let frames = 4;
    let at = |cells: &[(usize, usize, f32)]| {
        let mut v = vec![0f32; frames * GROUP_DIMS];
        for &(f, c, x) in cells {
            v[f * GROUP_DIMS + c] = x;
        }
        Tensor::<3>::from_data(TensorData::new(v, [1, frames, GROUP_DIMS]), &dev)
    };
    let x0 = at(&[]);
    let loss =
        |pred: Tensor<3>, active| root_velocity(pred, x0.clone(), active).into_scalar::<f32>();
    // A one-frame jump of slot 1's root x: changes +1 then −1 over 3 frame pairs, 2 channels.
    let jump = at(&[(1, channel(1, 4), 1.0)]);
    assert!((loss(jump.clone(), 2) - 2.0 / (2.0 * 2.0 * 3.0)).abs() < 1e-6);
    // The height (channel 6) and a rotation (channel 7) are not the root's x/y.
    assert_eq!(
        loss(at(&[(1, channel(0, 6), 1.0), (2, channel(0, 7), 3.0)]), 2),
        0.0
    );
    // A root that moves as the data's does is not penalised, however far it travels.
    let travel = at(&[
        (1, channel(0, 5), 1.0),
        (2, channel(0, 5), 2.0),
        (3, channel(0, 5), 3.0),
    ]);
    assert!(
        root_velocity(travel.clone(), travel, 2)
            .into_scalar::<f32>()
            .abs()
            < 1e-9
    );
}

#[test]
fn the_objective_is_learnable() {
    let dev = device::training();
    let cfg = tiny(SequenceMixer::CrossAttention);
    let mut m = net(&cfg, &dev);
    let schedule = Schedule::edge();
    let x0 = Tensor::<3>::random([2, T, GROUP_DIMS], Distribution::Normal(0.0, 0.5), &dev);
    let c = cond(2, T, 3, &dev);
    let batch = GroupBatch {
        x0,
        music: c.music.clone(),
        dancers: vec![3, 3],
        swap: c.swap.clone(),
    };
    let weights = Default::default();
    let training = Default::default();
    let mut optim = AdamWConfig::new().init();
    let mean_of = |m: &GroupDenoiser, seeds: std::ops::Range<u64>| -> f32 {
        seeds
            .clone()
            .map(|s| {
                group_loss(m, &schedule, &batch, &weights, &training, s)
                    .total
                    .into_scalar::<f32>()
            })
            .sum::<f32>()
            / seeds.count() as f32
    };
    let before = mean_of(&m, 1000..1008);
    for step in 0..300 {
        let l = group_loss(&m, &schedule, &batch, &weights, &training, step);
        for (name, v) in &l.parts {
            assert!(
                v.clone().into_scalar::<f32>().is_finite(),
                "{name} not finite"
            );
        }
        let grads = GradientsParams::from_grads(l.total.backward(), &m);
        m = optim.step(2e-3, m, grads);
    }
    let after = mean_of(&m, 1000..1008);
    assert!(after < 0.7 * before, "loss {before} → {after}");
}

/// Mean squared x̂0 error over the active channels after `steps` AdamW steps taught only at
/// `t = 10` (a nearly clean input) on fresh random windows, then on new windows.
fn copy_error_after(prediction: Prediction, steps: usize) -> f32 {
    let dev = device::training();
    let cfg = DenoiserConfig {
        prediction,
        ..tiny(SequenceMixer::CrossAttention)
    };
    let mut m = net(&cfg, &dev);
    let mut optim = AdamWConfig::new().init();
    let schedule = Schedule::edge();
    let (b, n, level) = (4, 3, 10);
    let mask = {
        let v: Vec<f32> = (0..GROUP_DIMS)
            .map(|c| f32::from(u8::from(c < n * DIMS)))
            .collect();
        Tensor::<3>::from_data(TensorData::new(v, [1, 1, GROUP_DIMS]), &dev)
    };
    let error = |m: &GroupDenoiser| {
        let x0 = Tensor::<3>::random([b, T, GROUP_DIMS], Distribution::Normal(0.0, 0.5), &dev)
            * mask.clone();
        let noise = Tensor::<3>::random([b, T, GROUP_DIMS], Distribution::Normal(0.0, 1.0), &dev);
        let x_t = schedule.q_sample(x0.clone(), &vec![level; b], noise) * mask.clone();
        let pred = m.forward(
            x_t,
            &vec![level as f32; b],
            &cond(b, T, n, &dev),
            &vec![true; b],
        );
        (pred * mask.clone() - x0).powf_scalar(2.0).sum() / (b * T * n * DIMS) as f64
    };
    for _ in 0..steps {
        let l = error(&m);
        let grads = GradientsParams::from_grads(l.backward(), &m);
        m = optim.step(1e-3, m, grads);
    }
    (0..4).map(|_| error(&m).into_scalar::<f32>()).sum::<f32>() / 4.0
}

#[test]
fn the_learned_skip_copies_a_nearly_clean_input_that_the_x0_network_cannot() {
    // Random windows fill all 151 channels of a token; the tiny network is 32 wide, so an x0
    // network can pass at most 32 of them through (error near 0.25 · 119/151 ≈ 0.2), while
    // the learned skip carries the input past the width (docs/group-collapse.md §15).
    let x0 = copy_error_after(Prediction::X0, 150);
    let skip = copy_error_after(Prediction::LearnedSkip, 150);
    eprintln!("copy error: x0 network {x0}, learned skip {skip}");
    assert!(
        x0 > 0.15,
        "x0 network error {x0}: the width no longer limits it?"
    );
    assert!(skip < 0.05, "learned skip error {skip} (x0 network: {x0})");
}

/// The long samplers' test case: 37 frames in 16-frame windows, 3 dancers, a periodic music.
const SAMPLED: (usize, usize, usize) = (37, 16, 3);

/// A tiny network, the schedule, the music and the requested paths of [`SAMPLED`].
fn sampled_case(dev: &Device) -> (GroupDenoiser, Schedule, Vec<f32>, Vec<Option<RootXy>>) {
    let (frames, _, n) = SAMPLED;
    let music = (0..frames * MUSIC_DIMS)
        .map(|i| ((i % 7) as f32) * 0.1)
        .collect();
    (
        net(&tiny(SequenceMixer::CrossAttention), dev),
        Schedule::edge(),
        music,
        request_paths(frames, n),
    )
}

/// 4 linear DDIM steps with guidance 2.
fn short_sampling(sampler: LongSampler, prefix: PrefixMode, seed: u64) -> GroupSampleOptions {
    GroupSampleOptions {
        steps: 4,
        eta: 1.0,
        spacing: Spacing::Linear,
        solver: Solver::Ddim,
        guidance: 2.0,
        sampler,
        prefix,
        seed,
    }
}

#[test]
fn a_formation_listed_right_to_left_is_danced_as_the_same_formation_left_to_right() {
    // The network knows slots sorted left to right at frame 0 only; the order in which a
    // FORMATION.json lists its dancers must not change the dance, only its labels.
    let dev = device::inference();
    let (m, schedule, music, paths) = sampled_case(&dev);
    let (frames, window, n) = SAMPLED;
    let mut reversed = paths.clone();
    for f in 0..frames {
        for d in 0..n {
            reversed[f * N_MAX + d] = paths[f * N_MAX + n - 1 - d];
        }
    }
    for sampler in [LongSampler::Lgds, LongSampler::Parallel] {
        let opts = short_sampling(sampler, PrefixMode::Clean, 5);
        let run = |control: &[Option<RootXy>]| {
            let req = GroupRequest {
                music: &music,
                frames,
                dancers: n,
                control: Some(control),
                known: None,
            };
            generate(&m, &schedule, window, &req, &opts, &dev, &NoHook).unwrap()
        };
        let (a, b) = (run(&paths), run(&reversed));
        for f in 0..frames {
            for d in 0..n {
                let at = |v: &[f32], dancer: usize| {
                    v[f * GROUP_DIMS + channel(dancer, 0)..f * GROUP_DIMS + channel(dancer + 1, 0)]
                        .to_vec()
                };
                assert_eq!(
                    at(&a, d),
                    at(&b, n - 1 - d),
                    "{sampler:?}: frame {f}, dancer {d} listed first and last"
                );
            }
        }
    }
}

fn request_paths(frames: usize, n: usize) -> Vec<Option<RootXy>> {
    // Dancers on a line 1.2 m apart, drifting right and back; raw Z-up metres.
    let mut c = vec![None; frames * N_MAX];
    for f in 0..frames {
        for d in 0..n {
            let x = 1.2 * d as f32 - 0.6 * (n - 1) as f32 + 0.5 * (f as f32 / 7.0).sin();
            c[f * N_MAX + d] = Some([x, 0.3 * d as f32]);
        }
    }
    c
}

#[test]
fn both_long_samplers_follow_requested_paths_and_are_seeded() {
    let dev = device::inference();
    let (m, schedule, music, paths) = sampled_case(&dev);
    let (frames, window, n) = SAMPLED;
    for sampler in [LongSampler::Lgds, LongSampler::Parallel] {
        for prefix in [PrefixMode::Clean, PrefixMode::Renoised] {
            let opts = short_sampling(sampler, prefix, 3);
            let req = GroupRequest {
                music: &music,
                frames,
                dancers: n,
                control: Some(&paths),
                known: None,
            };
            let out = generate(&m, &schedule, window, &req, &opts, &dev, &NoHook).unwrap();
            assert_eq!(out.len(), frames * GROUP_DIMS);
            for f in 0..frames {
                for d in 0..n {
                    let want = paths[f * N_MAX + d].unwrap();
                    for k in 0..2 {
                        let got = out[f * GROUP_DIMS + channel(d, 4 + k)];
                        assert!(
                            (got - want[k]).abs() < 1e-4,
                            "{sampler:?}/{prefix:?} frame {f} dancer {d}: {got} vs {}",
                            want[k]
                        );
                    }
                }
                assert!(
                    out[f * GROUP_DIMS + channel(n, 0)..(f + 1) * GROUP_DIMS]
                        .iter()
                        .all(|&v| v == 0.0)
                );
            }
            // Free dances: finite, seeded.
            let free = GroupRequest {
                control: None,
                ..req
            };
            let a = generate(&m, &schedule, window, &free, &opts, &dev, &NoHook).unwrap();
            let b = generate(&m, &schedule, window, &free, &opts, &dev, &NoHook).unwrap();
            let c = generate(
                &m,
                &schedule,
                window,
                &free,
                &GroupSampleOptions {
                    seed: 4,
                    ..opts.clone()
                },
                &dev,
                &NoHook,
            )
            .unwrap();
            assert!(a.iter().all(|v| v.is_finite()));
            assert_eq!(a, b, "{sampler:?}: same seed, same dance");
            assert_ne!(a, c, "{sampler:?}: another seed, another dance");
        }
    }
}

#[test]
fn the_mamba_decoder_samples_long_dances() {
    let dev = device::inference();
    let m = net(&tiny(SequenceMixer::Mamba), &dev);
    let schedule = Schedule::edge();
    let (frames, window, n) = (40, 16, 5);
    let music = vec![0.1f32; frames * MUSIC_DIMS];
    let opts = GroupSampleOptions {
        steps: 3,
        eta: 1.0,
        spacing: Spacing::Linear,
        solver: Solver::Ddim,
        guidance: 1.0,
        sampler: LongSampler::Lgds,
        prefix: PrefixMode::Clean,
        seed: 9,
    };
    let req = GroupRequest {
        music: &music,
        frames,
        dancers: n,
        control: None,
        known: None,
    };
    let out = generate(&m, &schedule, window, &req, &opts, &dev, &NoHook).unwrap();
    assert_eq!(out.len(), frames * GROUP_DIMS);
    assert!(out.iter().all(|v| v.is_finite()));
}
