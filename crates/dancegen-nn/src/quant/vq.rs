//! VQ with an EMA codebook and dead-code reset: T2M-GPT `QuantizeEMAReset`
//! (`Mael-zys/T2M-GPT:models/quantize_cnn.py`; the same class in
//! `EricGuo5513/momask-codes:models/vq/quantizer.py`), Lodge++'s and SoulNet's quantizer
//! (anchors D.3, D.6).
//!
//! - Nearest code by L2: `argmin ‖x‖² − 2 x·c + ‖c‖²`.
//! - Output `x + (q − x).detach()` (straight-through), commitment `mse(x, q.detach())`.
//! - Training (autodiff input) only: on the first call the codebook is initialised from the
//!   inputs (`_tile`: repeated with `N(0, (0.01/√d)²)` noise when there are fewer inputs than
//!   codes, first `K` rows); then every call, with one-hot assignments `o` `[N, K]`,
//!   `sum ← μ·sum + (1−μ)·oᵀx`, `count ← μ·count + (1−μ)·Σo`, and each code becomes
//!   `sum/count` if `count ≥ 1`, else (a dead code) a row of `_tile(x)` — the first `K` rows in
//!   T2M-GPT, a random permutation's first `K` (MoMask) with
//!   [`EmaVqConfig::shuffle_reset`]. The output uses the codebook from **before** the update, as
//!   the reference does. Perplexity is of the batch's assignments.
//!
//! State: the codebook, EMA sums and counts and an "initialised" flag are
//! [`RunningState`] tensors — part of the module's record, so they are saved and loaded with
//! the weights (names `codebook`, `code_sum`, `code_count`, `initialised`), never trained by the
//! optimiser (no gradient) and updated in place by `forward(&self)`.

use burn::config::Config;
use burn::module::{Module, RunningState};
use burn::tensor::{Device, Distribution, Int, Tensor};

use super::{QuantOutput, is_training};

/// Configuration of [`EmaVq`].
#[derive(Config, Debug)]
pub struct EmaVqConfig {
    /// Codebook size `K`.
    pub nb_code: usize,
    /// Code width `d`.
    pub code_dim: usize,
    /// EMA decay μ.
    #[config(default = 0.99)]
    pub mu: f64,
    /// Replace codes whose EMA count falls below 1 (T2M-GPT always does).
    #[config(default = true)]
    pub reset_dead_codes: bool,
    /// Reset dead codes to a random permutation of the inputs (MoMask) instead of the first `K`
    /// (T2M-GPT).
    #[config(default = false)]
    pub shuffle_reset: bool,
}

/// See the module documentation.
#[derive(Module, Debug)]
pub struct EmaVq {
    /// `[K, d]`.
    pub codebook: RunningState<Tensor<2>>,
    /// EMA of the sum of inputs assigned to each code, `[K, d]`.
    pub code_sum: RunningState<Tensor<2>>,
    /// EMA of the assignment counts, `[K]`.
    pub code_count: RunningState<Tensor<1>>,
    /// `[1]`: 1 once the codebook was initialised from data.
    pub initialised: RunningState<Tensor<1>>,
    #[module(skip)]
    pub mu: f64,
    #[module(skip)]
    pub reset_dead_codes: bool,
    #[module(skip)]
    pub shuffle_reset: bool,
}

impl EmaVqConfig {
    pub fn init(&self, device: &Device) -> EmaVq {
        let (k, d) = (self.nb_code, self.code_dim);
        EmaVq {
            codebook: RunningState::new(Tensor::zeros([k, d], device)),
            code_sum: RunningState::new(Tensor::zeros([k, d], device)),
            code_count: RunningState::new(Tensor::ones([k], device)),
            initialised: RunningState::new(Tensor::zeros([1], device)),
            mu: self.mu,
            reset_dead_codes: self.reset_dead_codes,
            shuffle_reset: self.shuffle_reset,
        }
    }
}

/// `exp(−Σ p log(p + 1e−7))` of code counts `[K]`.
pub fn perplexity_of_counts(counts: Tensor<1>) -> Tensor<1> {
    let p = counts.clone() / counts.sum();
    (p.clone() * (p + 1e-7).log()).sum().neg().exp()
}

/// Replaces a state's value at once. `RunningState::update` only queues a per-thread value
/// (averaged over threads at the next sync) and a module's record reads the last synced value, so
/// without the sync a checkpoint saved right after a step would miss that step.
fn store<const D: usize>(state: &RunningState<Tensor<D>>, value: Tensor<D>) {
    state.update(value);
    let _ = state.value_sync();
}

impl EmaVq {
    pub fn nb_code(&self) -> usize {
        self.codebook.value().dims()[0]
    }

    pub fn code_dim(&self) -> usize {
        self.codebook.value().dims()[1]
    }

    /// Whether the codebook has been initialised from data (or loaded).
    pub fn is_initialised(&self) -> bool {
        self.initialised
            .value_sync()
            .into_data()
            .try_to_vec::<f32>()
            .expect("f32")[0]
            > 0.5
    }

    /// Sets the codebook (and resets the EMA state to it with unit counts), e.g. to load one.
    pub fn set_codebook(&self, codebook: Tensor<2>) {
        let codebook = codebook.detach();
        let k = codebook.dims()[0];
        let device = codebook.device();
        store(&self.code_sum, codebook.clone());
        store(&self.code_count, Tensor::ones([k], &device));
        store(&self.codebook, codebook);
        store(&self.initialised, Tensor::ones([1], &device));
    }

    /// T2M-GPT `_tile`: at least `K` rows from `x` `[N, d]`, then the first `K` (or a random
    /// `K` with `shuffle`).
    fn tile(&self, x: Tensor<2>, shuffle: bool) -> Tensor<2> {
        let [n, d] = x.dims();
        let k = self.nb_code();
        let device = x.device();
        let out = if n < k {
            let r = k.div_ceil(n);
            let std = 0.01 / (d as f64).sqrt();
            let rep = x.repeat_dim(0, r);
            let noise = Tensor::<2>::random([n * r, d], Distribution::Normal(0.0, std), &device);
            rep + noise
        } else {
            x
        };
        let out = if shuffle {
            let m = out.dims()[0];
            let perm =
                Tensor::<1>::random([m], Distribution::Uniform(0.0, 1.0), &device).argsort(0);
            out.select(0, perm)
        } else {
            out
        };
        out.narrow(0, 0, k)
    }

    /// Nearest code of each row of `x` `[N, d]`: `[N]`.
    pub fn nearest(&self, x: Tensor<2>) -> Tensor<1, Int> {
        let n = x.dims()[0];
        let c = self.codebook.value_sync();
        let dist = x.clone().powf_scalar(2.0).sum_dim(1) - x.matmul(c.clone().transpose()) * 2.0
            + c.powf_scalar(2.0).sum_dim(1).transpose();
        dist.argmin(1).reshape([n])
    }

    /// One EMA step with inputs `x` `[N, d]` (detached) assigned to `idx`; returns perplexity.
    fn update(&self, x: Tensor<2>, idx: Tensor<1, Int>) -> Tensor<1> {
        let k = self.nb_code();
        let [_, d] = x.dims();
        let onehot: Tensor<2> = idx.one_hot::<2>(k).float(); // [N, K]
        let batch_sum = onehot.clone().transpose().matmul(x.clone()); // [K, d]
        let batch_count = onehot.sum_dim(0).reshape([k]);
        let mu = self.mu;
        let sum = self.code_sum.value_sync() * mu + batch_sum * (1.0 - mu);
        let count = self.code_count.value_sync() * mu + batch_count.clone() * (1.0 - mu);
        let mean = sum.clone() / count.clone().reshape([k, 1]);
        let codebook = if self.reset_dead_codes {
            let rand = self.tile(x, self.shuffle_reset);
            let used = count
                .clone()
                .greater_equal_elem(1.0)
                .reshape([k, 1])
                .expand([k, d]);
            rand.mask_where(used, mean)
        } else {
            mean
        };
        store(&self.code_sum, sum.detach());
        store(&self.code_count, count.detach());
        store(&self.codebook, codebook.detach());
        perplexity_of_counts(batch_count)
    }

    /// `[B, T, d]` → quantized `[B, T, d]`, indices `[B, T, 1]`.
    pub fn forward(&self, x: Tensor<3>) -> QuantOutput {
        let [b, t, d] = x.dims();
        let training = is_training(&x);
        let flat = x.reshape([b * t, d]);
        if training && !self.is_initialised() {
            let init = self.tile(flat.clone().detach(), false);
            self.set_codebook(init);
        }
        let idx = self.nearest(flat.clone().detach());
        let q = self.codebook.value_sync().select(0, idx.clone());
        let perplexity = if training {
            self.update(flat.clone().detach(), idx.clone())
        } else {
            perplexity_of_counts(
                idx.clone()
                    .one_hot::<2>(self.nb_code())
                    .float()
                    .sum_dim(0)
                    .reshape([self.nb_code()]),
            )
        };
        let commit_loss = crate::loss::commitment(flat.clone(), q.clone());
        let st = flat.clone() + (q - flat).detach();
        let quantized = st.reshape([b, t, d]);
        QuantOutput {
            quantized: quantized.clone(),
            indices: idx.reshape([b, t, 1]),
            commit_loss,
            perplexity: Some(perplexity),
            levels: vec![quantized],
        }
    }

    /// Codes of indices `[B, T, 1]` (or `[B, T]` flattened as `[B, T, 1]`) → `[B, T, d]`.
    /// Negative indices (dropped levels) decode to zeros.
    pub fn decode_indices(&self, indices: Tensor<3, Int>) -> Tensor<3> {
        let [b, t, _] = indices.dims();
        let d = self.code_dim();
        let flat = indices.reshape([b * t]);
        let dropped = flat.clone().lower_elem(0);
        let safe = flat.clamp_min(0);
        let codes = self.codebook.value_sync().select(0, safe);
        let zero = dropped.reshape([b * t, 1]).expand([b * t, d]);
        codes.mask_fill(zero, 0.0).reshape([b, t, d])
    }
}
