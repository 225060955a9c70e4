//! The optimizers and gradient tools against their definitions, on tiny tensors.

use dancegen_nn::burn;

use burn::nn::LinearConfig;
use burn::optim::{GradientsParams, Optimizer};
use burn::tensor::{Device, Tensor, TensorData};
use dancegen_train::config::{Decay, ScheduleConfig};
use dancegen_train::optim::{EDGE_ADAN_BETAS, EdgeAdan, clip_global_norm, global_norm, lr_at};

fn t1(v: &[f32], device: &Device) -> Tensor<1> {
    Tensor::from_data(TensorData::new(v.to_vec(), [v.len()]), device)
}

fn vec1(t: Tensor<1>) -> Vec<f32> {
    t.into_data().try_to_vec::<f32>().unwrap()
}

/// `Stanford-TML/EDGE:model/adan.py` `Adan.step`, transcribed line by line in f64 for one
/// tensor: returns the parameters after each step.
fn edge_adan_reference(
    theta0: &[f64],
    grads: &[Vec<f64>],
    lr: f64,
    wd: f64,
    betas: [f64; 3],
    eps: f64,
) -> Vec<Vec<f64>> {
    let n = theta0.len();
    let (b1, b2, b3) = (betas[0], betas[1], betas[2]);
    let mut data = theta0.to_vec();
    let (mut m, mut v, mut nn, mut prev) = (vec![0.0; n], vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let mut out = Vec::new();
    for (step0, g) in grads.iter().enumerate() {
        if step0 > 0 {
            for i in 0..n {
                m[i] = m[i] * (1.0 - b1) + g[i] * b1;
                let diff = g[i] - prev[i];
                v[i] = v[i] * (1.0 - b2) + diff * b2;
                let next_n = (g[i] + (1.0 - b2) * diff).powi(2);
                nn[i] = nn[i] * (1.0 - b3) + next_n * b3;
            }
        }
        let step = (step0 + 1) as i32;
        let corr = |b: f64| 1.0 / (1.0 - (1.0 - b).powi(step));
        let (cm, cv, cn) = (corr(b1), corr(b2), corr(b3));
        for i in 0..n {
            let size = lr / ((nn[i] * cn).sqrt() + eps);
            let denom = 1.0 + wd * lr;
            data[i] = (data[i] - size * (m[i] * cm + (1.0 - b2) * v[i] * cv)) / denom;
        }
        prev.clone_from(g);
        out.push(data.clone());
    }
    out
}

#[test]
fn edge_adan_follows_edges_update_rule_step_by_step() {
    let device = Device::flex();
    let theta0 = [0.5f32, -1.25, 2.0, 0.0];
    let grads: Vec<Vec<f32>> = vec![
        vec![0.3, -0.2, 1.5, -0.7],
        vec![-0.1, 0.4, 1.1, 0.2],
        vec![0.25, 0.05, -0.9, 0.6],
        vec![0.0, -0.3, 0.2, -0.4],
        vec![1.0, 0.9, -0.5, 0.1],
    ];
    // EDGE's recipe (anchors.md D.1): lr 4e-4, weight decay 0.02, betas (0.02, 0.08, 0.01).
    let (lr, wd, eps) = (4e-4, 0.02, 1e-8);
    let opt = EdgeAdan {
        betas: EDGE_ADAN_BETAS,
        eps,
        weight_decay: wd,
    };
    let want = edge_adan_reference(
        &theta0.map(f64::from),
        &grads
            .iter()
            .map(|g| g.iter().map(|&x| x as f64).collect())
            .collect::<Vec<_>>(),
        lr,
        wd,
        EDGE_ADAN_BETAS,
        eps,
    );
    let mut theta = t1(&theta0, &device);
    let mut state = None;
    for (k, g) in grads.iter().enumerate() {
        let (t, s) = opt.step(lr, theta, t1(g, &device), state);
        theta = t;
        state = s;
        let got = vec1(theta.clone());
        for (i, (&a, &b)) in got.iter().zip(&want[k]).enumerate() {
            let moved = (b - theta0[i] as f64).abs();
            // f32 parameters round by up to half an ulp per step; beyond that, agreement to
            // 0.1% of the distance moved (a different rule is off by a large part of it).
            let ulps = (k + 1) as f64 * f32::EPSILON as f64 * b.abs().max(1e-3);
            assert!(
                (a as f64 - b).abs() <= ulps + 1e-3 * moved,
                "step {} element {i}: {a} vs reference {b}",
                k + 1
            );
        }
    }
    // EDGE's first step moves nothing but the weight decay: θ / (1 + λ·lr).
    let first = &want[0];
    assert!((first[0] - 0.5 / (1.0 + wd * lr)).abs() < 1e-12);
    // Later steps move by about lr per step (so the comparison above has something to check).
    assert!((want[4][1] - first[1]).abs() > 4e-4);
}

#[test]
fn global_norm_clipping_scales_all_gradients_together() {
    let device = Device::flex().autodiff();
    let lin = LinearConfig::new(2, 2).init(&device);
    let mut grads = GradientsParams::new();
    // ‖w‖ = ‖(3, 0, 0, 4)‖ = 5, ‖b‖ = ‖(0, 12)‖ = 12, global = 13.
    let inner = Device::flex();
    let w = Tensor::<2>::from_data(TensorData::new(vec![3.0f32, 0.0, 0.0, 4.0], [2, 2]), &inner);
    let b = t1(&[0.0, 12.0], &inner);
    grads.register(lin.weight.id, w);
    grads.register(lin.bias.as_ref().unwrap().id, b);
    assert!((global_norm(&lin, &grads) - 13.0).abs() < 1e-6);

    let before = clip_global_norm(&lin, &mut grads, 6.5);
    assert!((before - 13.0).abs() < 1e-6);
    // torch.nn.utils.clip_grad_norm_: every gradient × 6.5 / (13 + 1e-6).
    let coef = (6.5 / (13.0 + 1e-6)) as f32;
    let w = grads
        .get::<2>(lin.weight.id)
        .unwrap()
        .into_data()
        .try_to_vec::<f32>()
        .unwrap();
    let b = vec1(grads.get::<1>(lin.bias.as_ref().unwrap().id).unwrap());
    for (got, want) in w.iter().chain(&b).zip([3.0, 0.0, 0.0, 4.0, 0.0, 12.0]) {
        assert!((got - want * coef).abs() < 1e-6, "{got} vs {}", want * coef);
    }
    // The bias keeps its share of the global norm (a per-tensor clip to 6.5 would leave it
    // at 6.5 and the weight at 5).
    assert!((global_norm(&lin, &grads) - 6.5).abs() < 1e-4);

    // Below the threshold nothing changes.
    let after = clip_global_norm(&lin, &mut grads, 100.0);
    assert!((after - 6.5).abs() < 1e-4);
    assert!((global_norm(&lin, &grads) - 6.5).abs() < 1e-4);
}

#[test]
fn schedule_warms_up_linearly_then_decays_to_min_lr() {
    let s = |decay| ScheduleConfig {
        warmup_steps: 10,
        decay,
        min_lr: 1e-5,
    };
    let peak = 1e-3;
    // Warm-up: lr·(k+1)/10 for the update of step k.
    assert!((lr_at(0, 110, peak, &s(Decay::Cosine)) - 1e-4).abs() < 1e-15);
    assert!((lr_at(9, 110, peak, &s(Decay::Cosine)) - peak).abs() < 1e-15);
    // Cosine: peak right after warm-up, the midpoint halfway, min_lr at the last step.
    assert!((lr_at(10, 110, peak, &s(Decay::Cosine)) - peak).abs() < 1e-15);
    let mid = lr_at(10 + 99 / 2, 110, peak, &s(Decay::Cosine));
    let half = 1e-5 + (peak - 1e-5) * 0.5 * (1.0 + (std::f64::consts::PI * 49.0 / 99.0).cos());
    assert!((mid - half).abs() < 1e-12);
    assert!((lr_at(109, 110, peak, &s(Decay::Cosine)) - 1e-5).abs() < 1e-15);
    // Linear: straight line from peak to min_lr.
    let l = lr_at(10 + 33, 110, peak, &s(Decay::Linear));
    assert!((l - (peak + (1e-5 - peak) * 33.0 / 99.0)).abs() < 1e-15);
    assert!((lr_at(109, 110, peak, &s(Decay::Linear)) - 1e-5).abs() < 1e-15);
    assert_eq!(lr_at(80, 110, peak, &s(Decay::Constant)), peak);
}

#[test]
fn official_adan_takes_the_papers_betas_and_moves_on_the_first_step() {
    use dancegen_train::config::{OptimizerConfig, OptimizerKind};
    use dancegen_train::optim::build_optimizer;
    let device = Device::flex().autodiff();
    let lin = LinearConfig::new(2, 1).init(&device);
    let w0 = lin.weight.val().into_data().try_to_vec::<f32>().unwrap();
    let (lr, wd) = (1e-2, 0.02);
    let cfg = |kind| OptimizerConfig {
        kind,
        lr,
        weight_decay: wd,
        betas: Some(EDGE_ADAN_BETAS.to_vec()),
        eps: 1e-8,
        grad_clip_norm: None,
    };
    let grads = || {
        let mut g = GradientsParams::new();
        let w =
            Tensor::<2>::from_data(TensorData::new(vec![0.5f32, -2.0], [2, 1]), &Device::flex());
        g.register(lin.weight.id, w);
        g
    };
    // sail-sg / Burn with β = 1 − (paper β): the first update is lr·g/|g| (bias-corrected), then
    // the proximal decay; EDGE's variant only decays.
    let step = |kind| {
        let mut o = build_optimizer(&cfg(kind));
        let l = o.step(lr, lin.clone(), grads());
        l.weight.val().into_data().try_to_vec::<f32>().unwrap()
    };
    let official = step(OptimizerKind::AdanOfficial);
    let edge = step(OptimizerKind::Adan);
    for (i, g) in [0.5f64, -2.0].iter().enumerate() {
        let want = (w0[i] as f64 - lr * g.signum()) / (1.0 + wd * lr);
        assert!(
            (official[i] as f64 - want).abs() < 1e-6,
            "{} vs {want}",
            official[i]
        );
        let decay_only = w0[i] as f64 / (1.0 + wd * lr);
        assert!(
            (edge[i] as f64 - decay_only).abs() < 1e-6,
            "{} vs {decay_only}",
            edge[i]
        );
    }
}

#[derive(serde::Deserialize)]
struct AdanFixture {
    shape: [usize; 2],
    lr: f64,
    weight_decay: f64,
    betas: [f64; 3],
    eps: f64,
    theta0: Vec<f32>,
    grads: Vec<Vec<f32>>,
    thetas: Vec<Vec<f32>>,
}

/// `tools/parity/adan.py`: EDGE's optimizer run by PyTorch (float32) on a [3, 4] parameter.
#[test]
fn edge_adan_matches_pytorch_fixture() {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/adan_edge.json");
    let f: AdanFixture = serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap();
    let device = Device::flex();
    let opt = EdgeAdan {
        betas: f.betas,
        eps: f.eps,
        weight_decay: f.weight_decay,
    };
    let t2 = |v: &[f32]| Tensor::<2>::from_data(TensorData::new(v.to_vec(), f.shape), &device);
    let mut theta = t2(&f.theta0);
    let mut state = None;
    for (k, (g, want)) in f.grads.iter().zip(&f.thetas).enumerate() {
        let (t, s) = opt.step(f.lr, theta, t2(g), state);
        theta = t;
        state = s;
        let got = theta.clone().into_data().try_to_vec::<f32>().unwrap();
        for (i, ((&a, &b), &a0)) in got.iter().zip(want).zip(&f.theta0).enumerate() {
            // Within a few float32 ulps of the parameter, or 1e-4 of the distance moved.
            let moved = (b as f64 - a0 as f64).abs();
            let tol = 4.0 * (k + 1) as f64 * f32::EPSILON as f64 * (b as f64).abs() + 1e-4 * moved;
            assert!(
                ((a - b) as f64).abs() <= tol,
                "step {} element {i}: {a} vs PyTorch {b}",
                k + 1
            );
        }
    }
    let last = f.thetas.last().unwrap();
    assert!(
        last.iter()
            .zip(&f.theta0)
            .any(|(a, b)| (a - b).abs() > 5e-4)
    );
}
