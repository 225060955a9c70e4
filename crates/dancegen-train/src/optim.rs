//! Optimizers, the learning-rate schedule and global-norm gradient clipping.
//!
//! - [`EdgeAdan`]: Adan (Xie et al. 2022, arXiv 2208.06677, Algorithm 1) exactly as EDGE trains
//!   with it (`Stanford-TML/EDGE:model/adan.py`, anchors.md D.1), as a Burn [`Optimizer`] whose
//!   state lands in Burn's optimizer record. It differs from Burn's built-in `Adan` (a port of the
//!   paper authors' `sail-sg/Adan`), so both are offered: EDGE's first step only records the
//!   gradient (its moments start at zero, so the update is zero and only the weight decay
//!   applies), and its bias corrections count that step.
//! - [`lr_at`]: linear warm-up then constant / linear / cosine decay, a pure function of the step
//!   (so "the schedule's position" in a checkpoint is just the step).
//! - [`clip_global_norm`]: `torch.nn.utils.clip_grad_norm_` — one L2 norm over all gradients.
//!   Burn's `GradientClippingConfig::Norm` clips each tensor by its own norm, which is a different
//!   (and recipe-changing) operation.

use dancegen_nn::burn;

use burn::module::{Module, ModuleVisitor, Param};
use burn::optim::{
    AdamWConfig, AdanConfig, GradientsParams, LearningRate, ModuleOptimizer, Optimizer,
    RecordState, StateSink, StateSource,
};
use burn::tensor::{Device, Tensor, TensorData};

use crate::config::{Decay, OptimizerConfig, OptimizerKind, ScheduleConfig};

/// EDGE's Adan betas (paper convention: the weight of the new value), `EDGE.py`.
pub const EDGE_ADAN_BETAS: [f64; 3] = [0.02, 0.08, 0.01];
/// PyTorch's AdamW default betas.
pub const ADAMW_BETAS: [f64; 2] = [0.9, 0.999];

/// Builds the configured optimizer (without clipping: see [`clip_global_norm`]).
pub fn build_optimizer(c: &OptimizerConfig) -> ModuleOptimizer {
    match c.kind {
        OptimizerKind::Adamw => {
            let b = c.betas.clone().unwrap_or(ADAMW_BETAS.to_vec());
            AdamWConfig::new()
                .with_beta_1(b[0] as f32)
                .with_beta_2(b[1] as f32)
                .with_epsilon(c.eps as f32)
                .with_weight_decay(c.weight_decay as f32)
                .init()
        }
        OptimizerKind::Adan => {
            let b = c.betas.clone().unwrap_or(EDGE_ADAN_BETAS.to_vec());
            ModuleOptimizer::from(EdgeAdan {
                betas: [b[0], b[1], b[2]],
                eps: c.eps,
                weight_decay: c.weight_decay,
            })
        }
        OptimizerKind::AdanOfficial => {
            // Burn / sail-sg use the complementary convention (0.98, 0.92, 0.99).
            let b = c.betas.clone().unwrap_or(EDGE_ADAN_BETAS.to_vec());
            AdanConfig::new()
                .with_beta_1((1.0 - b[0]) as f32)
                .with_beta_2((1.0 - b[1]) as f32)
                .with_beta_3((1.0 - b[2]) as f32)
                .with_epsilon(c.eps as f32)
                .with_weight_decay(c.weight_decay as f32)
                .init()
        }
    }
}

/// Adan as in `Stanford-TML/EDGE:model/adan.py`, per parameter tensor, with `k` the step count
/// after increment and `β` in the paper's convention:
///
/// ```text
/// if k > 1:  m ← (1−β1)m + β1 g
///            v ← (1−β2)v + β2 (g − g_prev)
///            n ← (1−β3)n + β3 (g + (1−β2)(g − g_prev))²
/// c_i = 1 / (1 − (1−β_i)^k)
/// θ ← (θ − lr · (c1 m + (1−β2) c2 v) / (sqrt(c3 n) + ε)) / (1 + λ lr)
/// g_prev ← g
/// ```
///
/// (EDGE's `restart_cond` is never set and is not implemented.)
#[derive(Clone, Debug)]
pub struct EdgeAdan {
    pub betas: [f64; 3],
    pub eps: f64,
    pub weight_decay: f64,
}

/// Per-tensor state of [`EdgeAdan`].
#[derive(Clone)]
pub struct EdgeAdanState<const D: usize> {
    pub step: u64,
    pub m: Tensor<D>,
    pub v: Tensor<D>,
    pub n: Tensor<D>,
    pub prev_grad: Tensor<D>,
}

impl<const D: usize> RecordState for EdgeAdanState<D> {
    fn state_flatten(&self, prefix: &str, out: &mut StateSink) {
        // The step as a one-element i64 tensor: exact, and no burn-pack scalar API needed.
        out.push_tensor(prefix, "step", TensorData::from([self.step as i64]));
        out.push_tensor(prefix, "m", self.m.to_data());
        out.push_tensor(prefix, "v", self.v.to_data());
        out.push_tensor(prefix, "n", self.n.to_data());
        out.push_tensor(prefix, "prev_grad", self.prev_grad.to_data());
    }

    fn state_unflatten(prefix: &str, src: &mut StateSource, device: &Device) -> Option<Self> {
        let step = src.take_tensor(prefix, "step")?.try_to_vec::<i64>().ok()?;
        let mut t = |leaf: &str| {
            src.take_tensor(prefix, leaf)
                .map(|d| Tensor::<D>::from_data(d, device))
        };
        Some(Self {
            step: u64::try_from(*step.first()?).ok()?,
            m: t("m")?,
            v: t("v")?,
            n: t("n")?,
            prev_grad: t("prev_grad")?,
        })
    }
}

impl Optimizer for EdgeAdan {
    type State<const D: usize> = EdgeAdanState<D>;

    fn step<const D: usize>(
        &self,
        lr: LearningRate,
        tensor: Tensor<D>,
        grad: Tensor<D>,
        state: Option<Self::State<D>>,
    ) -> (Tensor<D>, Option<Self::State<D>>) {
        let [b1, b2, b3] = self.betas;
        let mut s = state.unwrap_or_else(|| EdgeAdanState {
            step: 0,
            m: grad.zeros_like(),
            v: grad.zeros_like(),
            n: grad.zeros_like(),
            prev_grad: grad.zeros_like(),
        });
        if s.step > 0 {
            let diff = grad.clone() - s.prev_grad;
            s.m = s.m.mul_scalar(1.0 - b1) + grad.clone().mul_scalar(b1);
            s.v = s.v.mul_scalar(1.0 - b2) + diff.clone().mul_scalar(b2);
            let next_n = (grad.clone() + diff.mul_scalar(1.0 - b2)).square();
            s.n = s.n.mul_scalar(1.0 - b3) + next_n.mul_scalar(b3);
        }
        s.step += 1;
        let k = s.step as i32;
        let correct = |b: f64| 1.0 / (1.0 - (1.0 - b).powi(k));
        let (c1, c2, c3) = (correct(b1), correct(b2), correct(b3));
        let denom = s.n.clone().mul_scalar(c3).sqrt().add_scalar(self.eps);
        let update = (s.m.clone().mul_scalar(c1) + s.v.clone().mul_scalar((1.0 - b2) * c2)) / denom;
        let tensor = (tensor - update.mul_scalar(lr)).div_scalar(1.0 + self.weight_decay * lr);
        s.prev_grad = grad;
        (tensor, Some(s))
    }

    fn to_device<const D: usize>(mut s: Self::State<D>, device: &Device) -> Self::State<D> {
        s.m = s.m.to_device(device);
        s.v = s.v.to_device(device);
        s.n = s.n.to_device(device);
        s.prev_grad = s.prev_grad.to_device(device);
        s
    }
}

/// Learning rate for the update of step `step` (0-based) out of `total`: linear warm-up from
/// `lr / warmup` to `lr` over the first `warmup` steps, then the decay to `min_lr` at the last
/// step.
pub fn lr_at(step: u64, total: u64, peak: f64, s: &ScheduleConfig) -> f64 {
    if step < s.warmup_steps {
        return peak * (step + 1) as f64 / s.warmup_steps as f64;
    }
    let span = total.saturating_sub(s.warmup_steps).saturating_sub(1);
    let t = if span == 0 {
        0.0
    } else {
        ((step - s.warmup_steps) as f64 / span as f64).min(1.0)
    };
    match s.decay {
        Decay::Constant => peak,
        Decay::Linear => peak + (s.min_lr - peak) * t,
        Decay::Cosine => {
            s.min_lr + (peak - s.min_lr) * 0.5 * (1.0 + (std::f64::consts::PI * t).cos())
        }
    }
}

/// Clips all gradients of `module` together to global L2 norm `max_norm`, as
/// `torch.nn.utils.clip_grad_norm_`: `total = ‖(‖g_1‖, …, ‖g_n‖)‖₂`, and when
/// `max_norm / (total + 1e-6) < 1` every gradient is multiplied by that factor. Returns the
/// norm before clipping.
pub fn clip_global_norm<M: Module>(module: &M, grads: &mut GradientsParams, max_norm: f64) -> f64 {
    let total = global_norm(module, grads);
    let coef = max_norm / (total + 1e-6);
    if coef < 1.0 {
        module.visit(&mut Scale { grads, coef });
    }
    total
}

/// The global L2 norm of the gradients of `module`'s parameters.
pub fn global_norm<M: Module>(module: &M, grads: &GradientsParams) -> f64 {
    let mut v = SquaredNorms { grads, sum: 0.0 };
    module.visit(&mut v);
    v.sum.sqrt()
}

struct SquaredNorms<'a> {
    grads: &'a GradientsParams,
    sum: f64,
}

impl ModuleVisitor for SquaredNorms<'_> {
    fn visit_float<const D: usize>(&mut self, param: &Param<Tensor<D>>) {
        if let Some(g) = self.grads.get::<D>(param.id) {
            // Each tensor's squared norm in f32 (as PyTorch's per-tensor norms), summed in f64.
            self.sum += g.square().sum().into_scalar::<f32>() as f64;
        }
    }
}

struct Scale<'a> {
    grads: &'a mut GradientsParams,
    coef: f64,
}

impl ModuleVisitor for Scale<'_> {
    fn visit_float<const D: usize>(&mut self, param: &Param<Tensor<D>>) {
        if let Some(g) = self.grads.remove::<D>(param.id) {
            self.grads.register(param.id, g.mul_scalar(self.coef));
        }
    }
}
