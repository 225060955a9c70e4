//! Motion autoencoder pieces against PyTorch references written from the published formulas
//! (`tools/parity/quant.py`): the T2M-GPT conv encoder/decoder (forward + input gradient), EMA
//! VQ (forward, straight-through gradient, one EMA training step with dead-code reset,
//! first-call initialisation), MoMask residual VQ (all levels and a forced quantize-dropout),
//! SoulNet hierarchical RVQ, FSQ (codes, indices, gradient, index round trip) and grouped
//! residual FSQ. Within 1e-4 of the largest reference magnitude; indices exactly.

mod common;

use common::{Fixture, assert_close};
use dancegen_nn::burn::tensor::{Int, Tensor};
use dancegen_nn::conv::ConvCodecConfig;
use dancegen_nn::device;
use dancegen_nn::quant::fsq::FsqConfig;
use dancegen_nn::quant::hfsq::HfsqConfig;
use dancegen_nn::quant::hrvq::HierarchicalRvqConfig;
use dancegen_nn::quant::rvq::ResidualVqConfig;
use dancegen_nn::quant::vq::EmaVqConfig;
use dancegen_nn::weights::{self, Layout};

const REL: f64 = 1e-4;

fn codec(fx: &Fixture) -> ConvCodecConfig {
    ConvCodecConfig::new(fx.cfg_usize("input_dim"), fx.cfg_usize("output_dim"))
        .with_width(fx.cfg_usize("width"))
        .with_depth(fx.cfg_usize("depth"))
        .with_down_t(fx.cfg_usize("down_t"))
        .with_stride_t(fx.cfg_usize("stride_t"))
        .with_dilation_growth_rate(fx.cfg_usize("dilation_growth_rate"))
        .with_code_dim(fx.cfg_usize("code_dim"))
}

fn assert_ints<const D: usize>(fx: &Fixture, key: &str, actual: Tensor<D, Int>) {
    let (shape, expected) = fx.raw(key);
    assert_eq!(actual.dims().to_vec(), *shape, "{}: {key} shape", fx.name);
    let got: Vec<i64> = actual
        .into_data()
        .convert::<i64>()
        .try_into_vec::<i64>()
        .unwrap();
    let exp: Vec<i64> = expected.iter().map(|&v| v as i64).collect();
    assert_eq!(got, exp, "{}: {key}", fx.name);
    println!("{}: {key}: {} indices equal", fx.name, exp.len());
}

#[test]
fn conv_encoder_forward_and_input_gradient() {
    let fx = Fixture::load("conv_encoder");
    let dev = device::training();
    let enc = weights::load(
        codec(&fx).init_encoder(&dev),
        &fx.weights_path(),
        Layout::PyTorch,
    )
    .unwrap();
    let x = fx.tensor::<3>("in.x", &dev).require_grad();
    let y = enc.forward(x.clone());
    let grads = (y.clone() * fx.tensor::<3>("in.probe", &dev))
        .sum()
        .backward();
    assert_close(&fx, "grad.x", x.grad(&grads).unwrap(), REL);
    assert_close(&fx, "out.y", y, REL);
}

#[test]
fn conv_decoder_forward_and_gradients() {
    let fx = Fixture::load("conv_decoder");
    let dev = device::training();
    let dec = weights::load(
        codec(&fx).init_decoder(&dev),
        &fx.weights_path(),
        Layout::PyTorch,
    )
    .unwrap();
    let z = fx.tensor::<3>("in.z", &dev).require_grad();
    let y = dec.forward(z.clone());
    let grads = (y.clone() * fx.tensor::<3>("in.probe", &dev))
        .sum()
        .backward();
    assert_close(&fx, "grad.z", z.grad(&grads).unwrap(), REL);
    assert_close(
        &fx,
        "grad.conv_in.weight",
        dec.conv_in.weight.grad(&grads).unwrap(),
        REL,
    );
    assert_close(&fx, "out.y", y, REL);
}

#[test]
fn ema_vq_inference_training_step_and_init() {
    let fx = Fixture::load("vq_ema");
    let cfg = EmaVqConfig::new(fx.cfg_usize("nb_code"), fx.cfg_usize("code_dim"));

    // Inference: nearest code, straight-through gradient (+ commitment), perplexity.
    let dev = device::inference().autodiff();
    let vq = cfg.init(&dev);
    vq.set_codebook(fx.tensor::<2>("in.codebook", &dev));
    let x = fx.tensor::<3>("in.x", &dev).require_grad();
    let probe = fx.tensor::<3>("in.probe", &dev);
    // An autodiff input means training: take the inference path on the inner device for the
    // forward values, and check the gradient with a training call on a fresh copy below.
    let plain = device::inference();
    let vq_eval = cfg.init(&plain);
    vq_eval.set_codebook(fx.tensor::<2>("in.codebook", &plain));
    let o = vq_eval.forward(fx.tensor::<3>("in.x", &plain));
    assert_close(&fx, "out.eval.quantized", o.quantized, REL);
    assert_ints(&fx, "out.eval.indices", o.indices);
    assert_close(&fx, "out.eval.commit", o.commit_loss, REL);
    assert_close(&fx, "out.eval.perplexity", o.perplexity.unwrap(), REL);

    // Training step: same forward values and gradient (the output uses the codebook before the
    // update), then the EMA state after the update, with dead codes reset to the first inputs.
    let o = vq.forward(x.clone());
    let grads = ((o.quantized.clone() * probe).sum() + o.commit_loss).backward();
    assert_close(&fx, "grad.eval.x", x.grad(&grads).unwrap(), REL);
    assert_close(&fx, "out.train.quantized", o.quantized, REL);
    assert_ints(&fx, "out.train.indices", o.indices);
    assert_close(&fx, "out.train.perplexity", o.perplexity.unwrap(), REL);
    assert_close(&fx, "out.train.codebook", vq.codebook.value_sync(), REL);
    assert_close(&fx, "out.train.code_sum", vq.code_sum.value_sync(), REL);
    assert_close(&fx, "out.train.code_count", vq.code_count.value_sync(), REL);

    // First training call on a fresh quantizer: initialised from the inputs, then one update.
    let fresh = cfg.init(&dev);
    assert!(!fresh.is_initialised());
    fresh.forward(fx.tensor::<3>("in.x", &dev));
    assert!(fresh.is_initialised());
    assert_close(&fx, "out.init.codebook", fresh.codebook.value_sync(), REL);
}

#[test]
fn residual_vq_levels_and_forced_dropout() {
    let fx = Fixture::load("rvq");
    let dev = device::inference();
    let cfg = ResidualVqConfig::new(EmaVqConfig::new(
        fx.cfg_usize("nb_code"),
        fx.cfg_usize("code_dim"),
    ))
    .with_num_quantizers(fx.cfg_usize("num_quantizers"));
    let rvq = weights::load(cfg.init(&dev), &fx.weights_path(), Layout::PyTorch).unwrap();
    let q = fx.cfg_usize("num_quantizers");
    for keep in [q, 2] {
        let o = rvq.forward_keep(fx.tensor::<3>("in.x", &dev), Some(keep));
        assert_close(
            &fx,
            &format!("out.keep{keep}.quantized"),
            o.quantized.clone(),
            REL,
        );
        assert_ints(&fx, &format!("out.keep{keep}.indices"), o.indices.clone());
        assert_close(&fx, &format!("out.keep{keep}.commit"), o.commit_loss, REL);
        assert_close(
            &fx,
            &format!("out.keep{keep}.quantized"),
            rvq.decode_indices(o.indices),
            REL,
        );
    }
    // Straight-through gradient: the autodiff device is training mode, which with no dropout and
    // an initialised codebook changes only the EMA state after the output is taken.
    let tdev = device::training();
    for keep in [q, 2] {
        let rvq = weights::load(cfg.init(&tdev), &fx.weights_path(), Layout::PyTorch).unwrap();
        let x = fx.tensor::<3>("in.x", &tdev).require_grad();
        let o = rvq.forward_keep(x.clone(), Some(keep));
        let probe = fx.tensor::<3>("in.probe", &tdev);
        let grads = ((o.quantized * probe).sum() + o.commit_loss).backward();
        assert_close(
            &fx,
            &format!("grad.keep{keep}.x"),
            x.grad(&grads).unwrap(),
            REL,
        );
    }
}

#[test]
fn soulnet_hierarchical_rvq() {
    let fx = Fixture::load("hrvq");
    let cfg = HierarchicalRvqConfig::new(EmaVqConfig::new(
        fx.cfg_usize("nb_code"),
        fx.cfg_usize("code_dim"),
    ))
    .with_num_quantizers(fx.cfg_usize("num_quantizers"));
    let dev = device::inference();
    let m = weights::load(cfg.init(&dev), &fx.weights_path(), Layout::PyTorch).unwrap();
    let o = m.forward(fx.tensor::<3>("in.x", &dev));
    assert_close(&fx, "out.quantized", o.quantized.clone(), REL);
    assert_ints(&fx, "out.indices", o.indices.clone());
    assert_close(&fx, "out.commit", o.commit_loss, REL);
    // decode_indices sums each part's codes: equal to the forward output's values.
    assert_close(&fx, "out.quantized", m.decode_indices(o.indices), REL);

    let tdev = device::training();
    let m = weights::load(
        cfg.with_quantize_dropout_prob(0.0).init(&tdev),
        &fx.weights_path(),
        Layout::PyTorch,
    )
    .unwrap();
    let x = fx.tensor::<3>("in.x", &tdev).require_grad();
    let o = m.forward(x.clone());
    let grads =
        ((o.quantized * fx.tensor::<3>("in.probe", &tdev)).sum() + o.commit_loss).backward();
    assert_close(&fx, "grad.x", x.grad(&grads).unwrap(), REL);
    assert_close(
        &fx,
        "grad.conv1d.weight",
        m.conv1d.weight.grad(&grads).unwrap(),
        REL,
    );
}

fn levels(fx: &Fixture) -> Vec<usize> {
    fx.config["levels"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_u64().unwrap() as usize)
        .collect()
}

#[test]
fn fsq_codes_indices_gradient_round_trip() {
    let fx = Fixture::load("fsq");
    let dev = device::training();
    let f = FsqConfig::new(levels(&fx)).init(&dev);
    let x = fx.tensor::<3>("in.x", &dev).require_grad();
    let o = f.forward(x.clone());
    let grads = (o.quantized.clone() * fx.tensor::<3>("in.probe", &dev))
        .sum()
        .backward();
    assert_close(&fx, "grad.x", x.grad(&grads).unwrap(), REL);
    assert_close(&fx, "out.codes", o.quantized.clone(), REL);
    assert_ints(&fx, "out.indices", o.indices.clone());
    assert_close(&fx, "out.codes", f.decode_indices(o.indices), REL);
    // Every index → code → index.
    let n = f.codebook_size();
    let all = Tensor::<1, Int>::arange(0..n as i64, &dev).reshape([1, n, 1]);
    let codes = f.indices_to_codes(all.clone());
    assert_close(&fx, "out.all_codes", codes.clone(), REL);
    let back: Vec<i64> = f
        .codes_to_indices(codes)
        .into_data()
        .convert::<i64>()
        .try_into_vec()
        .unwrap();
    assert_eq!(
        back,
        (0..n as i64).collect::<Vec<_>>(),
        "FSQ index round trip"
    );
}

#[test]
fn grouped_residual_fsq() {
    let fx = Fixture::load("hfsq");
    let dev = device::training();
    let cfg = HfsqConfig::new(fx.cfg_usize("dim"), levels(&fx))
        .with_groups(fx.cfg_usize("groups"))
        .with_num_levels(fx.cfg_usize("num_levels"));
    let h = cfg.init(&dev);
    let x = fx.tensor::<3>("in.x", &dev).require_grad();
    let o = h.forward(x.clone());
    let grads = (o.quantized.clone() * fx.tensor::<3>("in.probe", &dev))
        .sum()
        .backward();
    assert_close(&fx, "grad.x", x.grad(&grads).unwrap(), REL);
    assert_close(&fx, "out.quantized", o.quantized.clone(), REL);
    for (r, l) in o.levels.iter().enumerate() {
        assert_close(&fx, &format!("out.level{r}"), l.clone(), REL);
    }
    assert_ints(&fx, "out.indices", o.indices.clone());
    assert_close(&fx, "out.quantized", h.decode_indices(o.indices), REL);
}
