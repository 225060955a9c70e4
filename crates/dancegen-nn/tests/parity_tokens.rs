//! Token models against PyTorch (`tools/parity/gpt.py`): GPT logits with a prefix, greedy
//! decoding through the KV cache equal to full recomputation, the masked transformer's logits,
//! and the properties of masked iterative decoding.

mod common;

use common::{Fixture, assert_close};
use dancegen_nn::burn::tensor::{Tensor, TensorData};
use dancegen_nn::device;
use dancegen_nn::gpt::{Gpt, GptConfig, KvCache, SamplingOptions};
use dancegen_nn::masked::{MaskedSampling, MaskedTransformerConfig};
use dancegen_nn::weights::{self, Layout};

const REL: f64 = 1e-4;

fn gpt(fx: &Fixture) -> Gpt {
    let dev = device::inference();
    let m = GptConfig::new(
        fx.cfg_usize("vocab"),
        fx.cfg_usize("d_model"),
        fx.cfg_usize("n_layers"),
        fx.cfg_usize("n_heads"),
        fx.cfg_usize("max_len"),
    )
    .init(&dev);
    weights::load(m, &fx.weights_path(), Layout::PyTorch).unwrap()
}

#[test]
fn gpt_logits_and_cached_greedy_decoding_match_pytorch() {
    let fx = Fixture::load("gpt");
    let dev = device::inference();
    let model = gpt(&fx);
    let prefix = fx.tensor::<3>("in.prefix", &dev);
    let tokens = fx.int_tensor::<2>("in.tokens", &dev);
    assert_close(
        &fx,
        "out.logits",
        model.forward(prefix.clone(), tokens),
        REL,
    );

    let (shape, want) = fx.raw("out.greedy");
    let got = model.generate(prefix, shape[1], &SamplingOptions::default());
    let got: Vec<i64> = got
        .into_data()
        .convert::<i64>()
        .try_into_vec::<i64>()
        .unwrap();
    let want: Vec<i64> = want.iter().map(|&v| v as i64).collect();
    assert_eq!(
        got, want,
        "greedy tokens (KV cache) vs PyTorch full recomputation"
    );
}

#[test]
fn kv_cache_steps_equal_full_forward() {
    let fx = Fixture::load("gpt");
    let dev = device::inference();
    let model = gpt(&fx);
    let prefix = fx.tensor::<3>("in.prefix", &dev);
    let tokens = fx.int_tensor::<2>("in.tokens", &dev);
    let full = model.forward(prefix.clone(), tokens.clone());
    let t = tokens.dims()[1];
    let mut cache = KvCache::default();
    let mut logits = vec![model.step(prefix, &mut cache)];
    for i in 0..t - 1 {
        let tok = tokens.clone().narrow(1, i, 1);
        logits.push(model.step(model.tok_emb.forward(tok), &mut cache));
    }
    assert_eq!(cache.len(), 3 + t - 1);
    let stepped: Tensor<3> = Tensor::stack(logits, 1);
    let diff = (stepped - full.clone()).abs().max().into_scalar::<f32>();
    let scale = full.abs().max().into_scalar::<f32>();
    println!("cached vs full logits: max abs diff {diff:.3e} of {scale:.3e}");
    assert!(diff <= 1e-4 * scale, "{diff} vs {scale}");
}

#[test]
fn top_k_sampling_is_seeded_and_stays_in_the_top_k() {
    let fx = Fixture::load("gpt");
    let dev = device::inference();
    let model = gpt(&fx);
    let prefix = fx.tensor::<3>("in.prefix", &dev);
    let opts = SamplingOptions {
        greedy: false,
        temperature: 1.0,
        top_k: Some(1),
        seed: 7,
    };
    // top-1 sampling is greedy decoding.
    let a = model.generate(prefix.clone(), 6, &opts);
    let g = model.generate(prefix.clone(), 6, &SamplingOptions::default());
    assert_eq!(a.to_data(), g.to_data());
    let k = 3;
    let opts = SamplingOptions {
        top_k: Some(k),
        temperature: 3.0,
        ..opts
    };
    let x = model.generate(prefix.clone(), 12, &opts);
    let y = model.generate(prefix.clone(), 12, &opts);
    assert_eq!(x.to_data(), y.to_data(), "same seed, same tokens");
    // Every sampled token is among the k most likely given the prefix and the tokens before it.
    let logits: Vec<f32> = model
        .forward(prefix, x.clone())
        .into_data()
        .convert::<f32>()
        .try_into_vec::<f32>()
        .unwrap();
    let toks: Vec<i64> = x
        .into_data()
        .convert::<i64>()
        .try_into_vec::<i64>()
        .unwrap();
    let v = fx.cfg_usize("vocab");
    let mut off_argmax = 0;
    for (p, &tok) in toks.iter().enumerate() {
        let row = &logits[p * v..(p + 1) * v];
        let rank = row.iter().filter(|&&l| l > row[tok as usize]).count();
        assert!(rank < k, "position {p}: token {tok} has rank {rank}");
        off_argmax += usize::from(rank > 0);
    }
    // At temperature 3 the draws are not all the argmax.
    assert!(off_argmax > 0, "top-k sampling never left the argmax");
}

#[test]
fn masked_transformer_logits_match_pytorch() {
    let fx = Fixture::load("masked_transformer");
    let dev = device::inference();
    let m = MaskedTransformerConfig::new(
        fx.cfg_usize("vocab"),
        fx.cfg_usize("d_model"),
        fx.cfg_usize("n_layers"),
        fx.cfg_usize("n_heads"),
        fx.cfg_usize("d_ff"),
        fx.cfg_usize("d_cond"),
    )
    .with_dropout(0.0)
    .init(&dev);
    let m = weights::load(m, &fx.weights_path(), Layout::PyTorch).unwrap();
    let logits = m.forward(fx.int_tensor("in.tokens", &dev), fx.tensor("in.cond", &dev));
    assert_close(&fx, "out.logits", logits, REL);

    // Decoding: no [MASK] left, every token a code, deterministic for a seed.
    let cond = fx.tensor::<2>("in.cond", &dev);
    let opts = MaskedSampling {
        steps: 6,
        seed: 3,
        ..Default::default()
    };
    let a = m.sample(cond.clone(), 9, &opts);
    let b = m.sample(cond, 9, &opts);
    assert_eq!(a.to_data(), b.to_data());
    let ids: Vec<i64> = a
        .into_data()
        .convert::<i64>()
        .try_into_vec::<i64>()
        .unwrap();
    assert_eq!(ids.len(), 18);
    assert!(
        ids.iter().all(|&i| (0..m.vocab as i64).contains(&i)),
        "{ids:?}"
    );
}

#[test]
fn masked_decoding_follows_a_confident_model() {
    // With the head's bias making code 4 overwhelmingly likely, every token decodes to 4.
    let dev = device::inference();
    let mut m = MaskedTransformerConfig::new(8, 16, 1, 4, 32, 4)
        .with_dropout(0.0)
        .init(&dev);
    let mut bias = vec![-50f32; 8];
    bias[4] = 50.0;
    m.head.bias = Some(dancegen_nn::burn::module::Param::from_tensor(
        Tensor::from_data(TensorData::new(bias, [8]), &dev),
    ));
    let ids = m.sample(Tensor::zeros([2, 4], &dev), 10, &MaskedSampling::default());
    let ids: Vec<i64> = ids
        .into_data()
        .convert::<i64>()
        .try_into_vec::<i64>()
        .unwrap();
    assert!(ids.iter().all(|&i| i == 4), "{ids:?}");
}
