//! Transformer building blocks against PyTorch (`tools/parity/blocks.py`): outputs and
//! gradients within 1e-4 of the largest reference magnitude.

mod common;

use common::{Fixture, assert_close};
use dancegen_nn::attention::{AttnMasks, MultiHeadAttention, MultiHeadAttentionConfig};
use dancegen_nn::burn::tensor::{Bool, Device, Tensor};
use dancegen_nn::device;
use dancegen_nn::mask::AttnMask;
use dancegen_nn::pos_encoding::{Rotary, sinusoidal};
use dancegen_nn::timestep::{TimestepMlpConfig, sinusoidal_timestep};
use dancegen_nn::transformer::{DecoderContext, EncoderLayerConfig, FilmDecoderLayerConfig};
use dancegen_nn::weights::{self, Layout};

const REL: f64 = 1e-4;

fn bool_tensor<const D: usize>(fx: &Fixture, key: &str, dev: &Device) -> Tensor<D, Bool> {
    fx.tensor::<D>(key, dev).greater_elem(0.5)
}

fn mha(fx: &Fixture, dev: &Device, d_context: Option<usize>) -> MultiHeadAttention {
    let m = MultiHeadAttentionConfig::new(fx.cfg_usize("d_model"), fx.cfg_usize("n_heads"))
        .with_d_context(d_context)
        .init(dev);
    weights::load(m, &fx.weights_path(), Layout::PyTorch).unwrap()
}

#[test]
fn self_attention_with_every_mask() {
    let fx = Fixture::load("mha_masks");
    let dev = device::training();
    let model = mha(&fx, &dev, None);
    let x = fx.tensor::<3>("in.x", &dev).require_grad();
    let t = x.dims()[1];
    let block = fx.cfg_usize("block");
    for (key, mask) in [
        ("full", AttnMask::Full),
        ("causal", AttnMask::Causal),
        ("block_diagonal", AttnMask::BlockDiagonal { block }),
        (
            "periodic_block_causal",
            AttnMask::PeriodicBlockCausal { block },
        ),
    ] {
        let masks = AttnMasks {
            attn: mask.tensor(t, t, &dev),
            key_padding: None,
        };
        let y = model.forward(x.clone(), x.clone(), x.clone(), &masks);
        if key == "causal" {
            let probe = fx.tensor::<3>("in.probe", &dev);
            let grads = (y.clone() * probe).sum().backward();
            assert_close(&fx, "grad.causal.x", x.grad(&grads).unwrap(), REL);
            // Burn stores Linear weights [in, out]; PyTorch [out, in].
            let gw = model.q_proj.weight.grad(&grads).unwrap().transpose();
            assert_close(&fx, "grad.causal.q_proj.weight", gw, REL);
        }
        assert_close(&fx, &format!("out.{key}"), y, REL);
    }
    let masks = AttnMasks {
        attn: AttnMask::Causal.tensor(t, t, &dev),
        key_padding: Some(bool_tensor::<2>(&fx, "in.key_padding", &dev)),
    };
    let y = model.forward(x.clone(), x.clone(), x, &masks);
    assert_close(&fx, "out.causal_key_padding", y, REL);
}

#[test]
fn cross_attention_with_key_padding() {
    let fx = Fixture::load("cross_attention");
    let dev = device::inference();
    let model = mha(&fx, &dev, Some(fx.cfg_usize("d_context")));
    let q = fx.tensor::<3>("in.q", &dev);
    let kv = fx.tensor::<3>("in.kv", &dev);
    let masks = AttnMasks {
        attn: None,
        key_padding: Some(bool_tensor::<2>(&fx, "in.key_padding", &dev)),
    };
    assert_close(&fx, "out.y", model.forward(q, kv.clone(), kv, &masks), REL);
}

#[test]
fn encoder_layers_match_pytorch() {
    for name in ["encoder_post_norm", "encoder_pre_norm"] {
        let fx = Fixture::load(name);
        let dev = device::training();
        let layer = EncoderLayerConfig::new(
            fx.cfg_usize("d_model"),
            fx.cfg_usize("n_heads"),
            fx.cfg_usize("d_ff"),
        )
        .with_norm_first(fx.config["norm_first"].as_bool().unwrap())
        .init(&dev);
        let layer = weights::load(layer, &fx.weights_path(), Layout::PyTorch).unwrap();
        let x = fx.tensor::<3>("in.x", &dev).require_grad();
        let y = layer.forward(x.clone(), &AttnMasks::default(), None);
        let grads = (y.clone() * fx.tensor::<3>("in.probe", &dev))
            .sum()
            .backward();
        assert_close(&fx, "out.y", y, REL);
        assert_close(&fx, "grad.x", x.grad(&grads).unwrap(), REL);
    }
}

#[test]
fn film_decoder_layer_matches_edge_formula() {
    let fx = Fixture::load("film_decoder");
    let dev = device::training();
    let layer = FilmDecoderLayerConfig::new(
        fx.cfg_usize("d_model"),
        fx.cfg_usize("n_heads"),
        fx.cfg_usize("d_ff"),
    )
    .with_d_context(Some(fx.cfg_usize("d_context")))
    .init(&dev);
    let layer = weights::load(layer, &fx.weights_path(), Layout::PyTorch).unwrap();
    let x = fx.tensor::<3>("in.x", &dev).require_grad();
    let t = x.dims()[1];
    let rotary = Rotary::new(fx.cfg_usize("d_model")).tables(fx.cfg_usize("rotary_start"), t, &dev);
    let self_masks = AttnMasks {
        attn: AttnMask::BlockDiagonal {
            block: fx.cfg_usize("block"),
        }
        .tensor(t, t, &dev),
        key_padding: None,
    };
    let ctx = DecoderContext {
        memory: fx.tensor("in.memory", &dev),
        cond: fx.tensor::<2>("in.cond", &dev).unsqueeze_dim(1),
        self_masks: &self_masks,
        cross_masks: &AttnMasks::default(),
        rotary: Some(&rotary),
    };
    let y = layer.forward(x.clone(), &ctx);
    let grads = (y.clone() * fx.tensor::<3>("in.probe", &dev))
        .sum()
        .backward();
    assert_close(&fx, "out.y", y, REL);
    assert_close(&fx, "grad.x", x.grad(&grads).unwrap(), REL);
    assert_close(
        &fx,
        "grad.norm1.weight",
        layer.norm1.gamma.grad(&grads).unwrap(),
        REL,
    );
    assert_close(
        &fx,
        "grad.film2.linear.weight",
        layer.film2.linear.weight.grad(&grads).unwrap().transpose(),
        REL,
    );
}

#[test]
fn timestep_rotary_and_sinusoidal_tables() {
    let fx = Fixture::load("timestep");
    let dev = device::inference();
    let d = fx.cfg_usize("d");
    let t: Vec<f32> = fx.raw("in.t").1.clone();
    assert_close(
        &fx,
        "out.sinusoidal_t",
        sinusoidal_timestep(&t, d, &dev),
        REL,
    );
    let mlp = weights::load(
        TimestepMlpConfig::new(d).init(&dev),
        &fx.weights_path(),
        Layout::PyTorch,
    )
    .unwrap();
    assert_close(&fx, "out.mlp", mlp.forward(&t, &dev), REL);
    let x = fx.tensor::<3>("in.x", &dev);
    let rot = Rotary::new(d).rotate(x, fx.cfg_usize("rotary_start"));
    assert_close(&fx, "out.rotary", rot, REL);
    assert_close(&fx, "out.sinusoidal_pe", sinusoidal(0, 20, d, &dev), REL);
}

#[test]
fn checkpoint_errors_name_the_tensor() {
    let fx = Fixture::load("mha_masks");
    let dev = device::inference();
    // A model with another width: every tensor mismatches, and the error says which.
    let wrong = MultiHeadAttentionConfig::new(8, 2).init(&dev);
    let e = weights::load(wrong, &fx.weights_path(), Layout::PyTorch)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("q_proj.weight") && e.contains("mha_masks.weights"),
        "{e}"
    );
    // A checkpoint without the attention's tensors.
    let other = Fixture::load("timestep");
    let model = MultiHeadAttentionConfig::new(16, 4).init(&dev);
    let e = weights::load(model, &other.weights_path(), Layout::PyTorch)
        .unwrap_err()
        .to_string();
    assert!(e.contains("missing") && e.contains("k_proj"), "{e}");
    let e = weights::load(
        MultiHeadAttentionConfig::new(16, 4).init(&dev),
        std::path::Path::new("/nonexistent/model.safetensors"),
        Layout::Burn,
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("/nonexistent/model.safetensors"), "{e}");
}
