//! The selective state-space layer (Mamba v1, `src/ssm.rs`) against a pure-PyTorch reference
//! scan (`tools/parity/ssm.py`): outputs and gradients within 1e-4 of the largest reference
//! magnitude, with both scans; and the chunked scan equal to the sequential one.

mod common;

use common::{Fixture, assert_close};
use dancegen_nn::burn::tensor::activation::silu;
use dancegen_nn::burn::tensor::{Distribution, Tensor};
use dancegen_nn::ssm::{
    Mamba, MambaBlockConfig, MambaConfig, Scan, ScanInputs, chunk_len, selective_scan_chunked,
    selective_scan_sequential,
};
use dancegen_nn::weights::{self, Layout};
use dancegen_nn::{burn, device};

const REL: f64 = 1e-4;

fn mamba(fx: &Fixture, dev: &burn::tensor::Device) -> Mamba {
    let m = MambaConfig::new(fx.cfg_usize("d_model"))
        .with_d_state(fx.cfg_usize("d_state"))
        .init(dev);
    weights::load(m, &fx.weights_path(), Layout::PyTorch).unwrap()
}

/// Output and gradients of `fx` through `run`, checked against the fixture.
fn check(fx: &Fixture, model: &Mamba, run: impl Fn(&Mamba, Tensor<3>) -> Tensor<3>) {
    let dev = device::training();
    let x = fx.tensor::<3>("in.x", &dev).require_grad();
    let y = run(model, x.clone());
    let grads = (y.clone() * fx.tensor::<3>("in.probe", &dev))
        .sum()
        .backward();
    assert_close(fx, "out.y", y, REL);
    assert_close(fx, "grad.x", x.grad(&grads).unwrap(), REL);
    assert_close(fx, "grad.A_log", model.A_log.grad(&grads).unwrap(), REL);
    if fx.has("grad.dt_proj.weight") {
        // Burn stores Linear weights [in, out]; PyTorch [out, in].
        let gw = model.dt_proj.weight.grad(&grads).unwrap().transpose();
        assert_close(fx, "grad.dt_proj.weight", gw, REL);
    }
}

/// The layer with an explicit maximum chunk length (the public pieces `forward` is made of).
fn with_chunk(m: &Mamba, x: Tensor<3>, chunk: usize) -> Tensor<3> {
    let (inputs, z) = m.scan_inputs(x);
    m.out_proj
        .forward(selective_scan_chunked(inputs, Some(chunk)) * silu(z))
}

#[test]
fn sequential_scan_matches_pytorch() {
    for name in ["mamba", "mamba_large_delta"] {
        let fx = Fixture::load(name);
        let model = mamba(&fx, &device::training());
        check(&fx, &model, |m, x| m.forward_with(x, Scan::Sequential));
    }
}

#[test]
fn chunked_scan_matches_pytorch() {
    for name in ["mamba", "mamba_large_delta"] {
        let fx = Fixture::load(name);
        let model = mamba(&fx, &device::training());
        // The default, then at most 1 frame per chunk, a length that leaves a partial last
        // chunk, and one chunk spanning the whole sequence (or as long as the Δ range allows).
        check(&fx, &model, |m, x| m.forward_with(x, Scan::Chunked));
        for chunk in [1, 5, 64] {
            check(&fx, &model, |m, x| with_chunk(m, x, chunk));
        }
    }
}

/// The default scan (chunked) on the training and the inference device.
#[test]
fn default_scan_matches_pytorch_for_training_and_inference() {
    let fx = Fixture::load("mamba");
    let model = mamba(&fx, &device::training());
    check(&fx, &model, |m, x| m.forward(x));
    let dev = device::inference();
    let model = mamba(&fx, &dev);
    assert_close(&fx, "out.y", model.forward(fx.tensor("in.x", &dev)), REL);
}

#[test]
fn mamba_block_matches_pytorch() {
    let fx = Fixture::load("mamba_block");
    let dev = device::training();
    let block = MambaBlockConfig::new(MambaConfig::new(fx.cfg_usize("d_model"))).init(&dev);
    let block = weights::load(block, &fx.weights_path(), Layout::PyTorch).unwrap();
    let x = fx.tensor::<3>("in.x", &dev).require_grad();
    let y = block.forward(x.clone());
    let grads = (y.clone() * fx.tensor::<3>("in.probe", &dev))
        .sum()
        .backward();
    assert_close(&fx, "out.y", y, REL);
    assert_close(&fx, "grad.x", x.grad(&grads).unwrap(), REL);
    assert_close(
        &fx,
        "grad.norm.weight",
        block.norm.gamma.grad(&grads).unwrap(),
        REL,
    );
}

fn max_abs_diff<const D: usize>(a: Tensor<D>, b: Tensor<D>) -> f32 {
    (a - b).abs().max().into_scalar::<f32>()
}

fn max_abs<const D: usize>(a: Tensor<D>) -> f32 {
    a.abs().max().into_scalar::<f32>()
}

/// Random scan inputs with Δ in [0.01, `dt_max`] and A = −1..−16: `dt_max` 0.5 makes `|Δ·A|`
/// reach 8 (chunks of 7 frames, spanning up to 56 of the allowed 60), 2 reaches 32 (1 frame).
fn random_inputs(dev: &burn::tensor::Device, t: usize, dt_max: f64) -> ScanInputs {
    let (bs, di, n) = (2, 12, 16);
    let normal = Distribution::Normal(0.0, 1.0);
    let a_log: Vec<f32> = (0..di)
        .flat_map(|_| (1..=n).map(|k| (k as f32).ln()))
        .collect();
    ScanInputs {
        u: Tensor::random([bs, t, di], normal, dev).require_grad(),
        delta: Tensor::random([bs, t, di], Distribution::Uniform(0.01, dt_max), dev).require_grad(),
        a: Tensor::<1>::from_floats(a_log.as_slice(), dev)
            .reshape([di, n])
            .exp()
            .neg()
            .require_grad(),
        b: Tensor::random([bs, t, n], normal, dev).require_grad(),
        c: Tensor::random([bs, t, n], normal, dev).require_grad(),
        d: Tensor::random([di], normal, dev).require_grad(),
    }
}

/// The chunked scan equals the sequential one to 1e-5 (relative to the largest value), output
/// and the gradients of every input, for automatic and explicit (maximum) chunk lengths
/// including a partial last chunk, at the initial Δ range and at large ones.
#[test]
fn chunked_scan_equals_sequential() {
    let dev = device::training();
    for (t, dt_max) in [(50, 0.1), (61, 0.5), (61, 2.0)] {
        let s = random_inputs(&dev, t, dt_max);
        let probe = Tensor::<3>::random(s.u.dims(), Distribution::Normal(0.0, 1.0), &dev);
        let grads_of = |y: Tensor<3>| {
            let g = (y * probe.clone()).sum().backward();
            vec![
                s.u.grad(&g).unwrap().into_data(),
                s.delta.grad(&g).unwrap().into_data(),
                s.b.grad(&g).unwrap().into_data(),
                s.c.grad(&g).unwrap().into_data(),
                s.a.grad(&g).unwrap().into_data(),
                s.d.grad(&g).unwrap().into_data(),
            ]
        };
        let y_ref = selective_scan_sequential(s.clone());
        let g_ref = grads_of(y_ref.clone());
        let scale = max_abs(y_ref.clone());
        for chunk in [None, Some(1), Some(7), Some(t)] {
            let y = selective_scan_chunked(s.clone(), chunk);
            let err = max_abs_diff(y.clone(), y_ref.clone()) / scale;
            println!("T {t}, dt_max {dt_max}, chunk {chunk:?}: output rel err {err:.2e}");
            assert!(err < 1e-5, "chunk {chunk:?}: output differs by {err:.2e}");
            for (k, (g, r)) in grads_of(y).into_iter().zip(&g_ref).enumerate() {
                let (g, r) = (
                    g.try_into_vec::<f32>().unwrap(),
                    r.clone().try_into_vec::<f32>().unwrap(),
                );
                let scale = r.iter().fold(0f32, |m, v| m.max(v.abs()));
                let err = g
                    .iter()
                    .zip(&r)
                    .fold(0f32, |m, (a, b)| m.max((a - b).abs()))
                    / scale;
                println!("  grad {k}: rel err {err:.2e}");
                assert!(
                    err < 1e-5,
                    "chunk {chunk:?}: gradient {k} differs by {err:.2e}"
                );
            }
        }
    }
}

#[test]
fn chunk_length_respects_the_log_range() {
    use dancegen_nn::ssm::{CHUNK_LOG_RANGE, MAX_CHUNK};
    // Initial Δ ≤ 0.1 with A down to −16: |Δ·A| ≤ 1.6 → 37 frames, evened out over 150.
    let l = chunk_len(1.6, 150, MAX_CHUNK);
    assert!(l as f32 * 1.6 <= CHUNK_LOG_RANGE, "{l}");
    assert_eq!(l, 30);
    assert_eq!(chunk_len(0.0, 512, MAX_CHUNK), MAX_CHUNK);
    assert_eq!(chunk_len(1.6, 150, 10), 10);
    assert_eq!(chunk_len(1000.0, 10, MAX_CHUNK), 1);
    assert_eq!(chunk_len(f32::NAN, 10, MAX_CHUNK), 1);
    assert_eq!(chunk_len(0.5, 20, MAX_CHUNK), 20);
}
