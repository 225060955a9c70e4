//! The one sampler: DDPM / strided DDIM with classifier-free guidance, inpainting cues and
//! EDGE's long-form window overwrite.
//!
//! Sources (anchors D.1, D.2, D.5; EDGE `model/diffusion.py`, Lodge `inpaint_soft_ddim`):
//! - DDIM (Song et al. 2021) on EDGE's strided steps: the pairs of
//!   `int(linspace(−1, T − 1, steps + 1))` reversed (999, 979, …, 19, −1 for 50 steps on
//!   T = 1000); the step into −1 outputs x̂0. `eta = 1` in EDGE.
//! - DDPM ancestral sampling over all T steps with the posterior q(x_{t−1} | x_t, x̂0).
//! - DPM-Solver++(2M) (Lu et al. 2022, arXiv:2211.01095), deterministic or its SDE variant:
//!   a second-order multistep solver on the same x̂0, for few steps.
//! - x̂0 is clamped to [−1, 1] (EDGE `clip_denoised`) before the noise is re-derived from it.
//! - Guidance `unc + w · (cond − unc)` (EDGE, w = 2); ReactDance's layer-decoupled CFG writes
//!   `(1 + s_r) · cond − s_r · unc` per quantisation layer r, i.e. `w_r = 1 + s_r`.

use std::ops::Range;

use burn::tensor::{Device, Tensor, TensorData};

use super::noise::SeededNoise;
use super::schedule::{Schedule, timestep_tensor};
use super::{Conditioning, Denoiser};
use crate::progress::{self, Cancelled, DENOISING, NoHook, StepHook};

/// EDGE's guidance weight (anchors D.1; Lodge and TCDiff++ use the same).
pub const EDGE_GUIDANCE: f64 = 2.0;
/// EDGE's number of DDIM steps and eta (anchors D.1).
pub const EDGE_DDIM_STEPS: usize = 50;
pub const EDGE_DDIM_ETA: f64 = 1.0;
/// EDGE's x̂0 clamp range (`clip_denoised`).
pub const EDGE_CLIP: (f64, f64) = (-1.0, 1.0);
/// EDGE's DDPM path caps w at 1 below this fraction of T (`p_mean_variance`).
pub const EDGE_DDPM_LOW_T_FRACTION: f64 = 0.1;

/// Ancestral DDPM, strided DDIM or DPM-Solver++(2M).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Method {
    /// All T steps, posterior mean + `exp(½ log σ²_t) · z` (no noise into t = −1).
    Ddpm,
    /// `steps` strided steps with stochasticity `eta` (0 = deterministic DDIM, 1 = EDGE),
    /// at the timesteps `spacing` picks.
    Ddim {
        steps: usize,
        eta: f64,
        spacing: Spacing,
    },
    /// DPM-Solver++(2M) on the timesteps `spacing` picks ([`dpmpp_2m_step`]). Why: with few
    /// steps the first-order DDIM lands far from what the same network gives with many (a
    /// group network's pose spread 5.5 cm at 6 steps, 8.9 at 50); the second-order update
    /// uses the previous step's x̂0 to follow x̂0's change over the step. `stochastic` is the
    /// SDE variant, whose first-order step is DDIM with eta = 1; otherwise the ODE variant,
    /// whose first-order step is DDIM with eta = 0.
    DpmSolverPp2m {
        steps: usize,
        spacing: Spacing,
        stochastic: bool,
    },
}

/// Which update a strided sampler makes at each step: a model config's `solver` key.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Solver {
    /// DDIM with stochasticity `eta`: EDGE's and the papers' sampler.
    #[default]
    #[serde(rename = "ddim")]
    Ddim,
    /// DPM-Solver++(2M), deterministic ([`Method::DpmSolverPp2m`]); `eta` is not read.
    #[serde(rename = "dpmpp_2m")]
    DpmPp2m,
    /// SDE-DPM-Solver++(2M) ([`Method::DpmSolverPp2m`]); `eta` is not read.
    #[serde(rename = "dpmpp_2m_sde")]
    DpmPp2mSde,
}

impl Solver {
    /// The [`Method`] of `steps` steps at the timesteps `spacing` picks.
    pub fn method(self, steps: usize, eta: f64, spacing: Spacing) -> Method {
        match self {
            Solver::Ddim => Method::Ddim {
                steps,
                eta,
                spacing,
            },
            Solver::DpmPp2m | Solver::DpmPp2mSde => Method::DpmSolverPp2m {
                steps,
                spacing,
                stochastic: self == Solver::DpmPp2mSde,
            },
        }
    }
}

/// Which timesteps a strided DDIM visits.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Spacing {
    /// EDGE's evenly spaced steps ([`ddim_timesteps`]).
    #[default]
    Linear,
    /// Steps spaced as `(i / steps)²` of the schedule (DDIM paper, Song et al. 2021, App.
    /// D.2), so the last x̂0 is predicted from a nearly clean input: with few steps the linear
    /// spacing predicts it from `t ≈ T / steps`, where a network that has not learned to
    /// remove all of that noise passes it to the output as frame-to-frame jitter.
    Quadratic,
}

/// The `(t, t_next)` pairs of a strided DDIM under `spacing`; the last pair goes to −1.
pub fn ddim_timesteps_spaced(
    timesteps: usize,
    steps: usize,
    spacing: Spacing,
) -> Vec<(usize, i64)> {
    match spacing {
        Spacing::Linear => ddim_timesteps(timesteps, steps),
        Spacing::Quadratic => {
            assert!(
                steps >= 1 && steps <= timesteps,
                "DDIM steps must be in 1..=T"
            );
            let last = timesteps as i64 - 1;
            let s2 = (steps * steps) as i64;
            // ⌊(T − 1) · i² / steps²⌋ in integers (no float truncation surprises), kept strictly
            // increasing: a step that would repeat its predecessor moves up by one.
            let mut times = vec![-1i64];
            for i in 1..=steps as i64 {
                let prev = *times.last().expect("starts with -1");
                times.push((last * i * i / s2).max(prev + 1).min(last));
            }
            times.reverse();
            times.windows(2).map(|w| (w[0] as usize, w[1])).collect()
        }
    }
}

/// The `(t, t_next)` pairs EDGE's `ddim_sample` visits: `int(linspace(−1, T − 1, steps + 1))`
/// reversed, truncated toward zero like `Tensor.int()`. The last pair goes to −1.
pub fn ddim_timesteps(timesteps: usize, steps: usize) -> Vec<(usize, i64)> {
    assert!(
        steps >= 1 && steps <= timesteps,
        "DDIM steps must be in 1..=T"
    );
    let (a, b) = (-1.0f64, timesteps as f64 - 1.0);
    let times: Vec<i64> = (0..=steps)
        .map(|i| (a + (b - a) * i as f64 / steps as f64).trunc() as i64)
        .rev()
        .collect();
    times.windows(2).map(|w| (w[0] as usize, w[1])).collect()
}

/// One DDIM step from `x_t` and the (guided, clamped) x̂0 to `t_next` (EDGE `ddim_sample`):
/// `ε̂ = (√(1/ᾱ_t) x_t − x̂0) / √(1/ᾱ_t − 1)`,
/// `σ = eta · √((1 − ᾱ_t/ᾱ_n)(1 − ᾱ_n)/(1 − ᾱ_t))`, `x_n = √ᾱ_n x̂0 + √(1 − ᾱ_n − σ²) ε̂ + σ z`.
/// `t_next < 0` returns x̂0.
pub fn ddim_step(
    schedule: &Schedule,
    x_t: Tensor<3>,
    x0: Tensor<3>,
    t: usize,
    t_next: i64,
    eta: f64,
    noise: Tensor<3>,
) -> Tensor<3> {
    if t_next < 0 {
        return x0;
    }
    let tn = t_next as usize;
    let (a, an) = (schedule.alphas_cumprod[t], schedule.alphas_cumprod[tn]);
    let eps = (x_t * schedule.sqrt_recip_alphas_cumprod[t] - x0.clone())
        / schedule.sqrt_recipm1_alphas_cumprod[t];
    let sigma = eta * ((1.0 - a / an) * (1.0 - an) / (1.0 - a)).sqrt();
    let c = (1.0 - an - sigma * sigma).max(0.0).sqrt();
    x0 * an.sqrt() + eps * c + noise * sigma
}

/// `λ_t = log(α_t / σ_t)` of DPM-Solver, `α_t = √ᾱ_t`, `σ_t = √(1 − ᾱ_t)`: half the log-SNR.
fn half_log_snr(schedule: &Schedule, t: usize) -> f64 {
    let a = schedule.alphas_cumprod[t];
    0.5 * (a / (1.0 - a)).ln()
}

/// The previous step of a DPM-Solver++(2M) run: its x̂0 and its `h = λ_next − λ_t`.
#[derive(Clone, Debug)]
pub struct DpmPrevious {
    pub x0: Tensor<3>,
    pub h: f64,
}

/// One DPM-Solver++(2M) step from `x_t` to `t_next` (Lu et al. 2022, arXiv:2211.01095,
/// Alg. 2 and the SDE-DPM-Solver++(2M) of its §5), with `h = λ_next − λ_t` and, when a
/// previous step is given, `D = x̂0 + (x̂0 − x̂0_prev) / (2r)`, `r = h_prev / h` (else
/// `D = x̂0`):
/// - ODE: `x_n = (σ_n/σ_t) x_t + α_n (1 − e^{−h}) D`;
/// - SDE: `x_n = (σ_n/σ_t) e^{−h} x_t + α_n (1 − e^{−2h}) D + σ_n √(1 − e^{−2h}) z`.
///
/// Without a previous step the ODE step is DDIM's with eta = 0 and the SDE step DDIM's with
/// eta = 1. `t_next < 0` returns x̂0, as DDIM does. Returns `x_n` and this step's `h`.
#[allow(clippy::too_many_arguments)]
pub fn dpmpp_2m_step(
    schedule: &Schedule,
    x_t: Tensor<3>,
    x0: Tensor<3>,
    previous: Option<&DpmPrevious>,
    t: usize,
    t_next: i64,
    stochastic: bool,
    noise: Tensor<3>,
) -> (Tensor<3>, f64) {
    if t_next < 0 {
        return (x0, f64::INFINITY);
    }
    let tn = t_next as usize;
    let sigma = |t: usize| (1.0 - schedule.alphas_cumprod[t]).sqrt();
    let (sigma_t, sigma_n) = (sigma(t), sigma(tn));
    let alpha_n = schedule.alphas_cumprod[tn].sqrt();
    let h = half_log_snr(schedule, tn) - half_log_snr(schedule, t);
    let d = match previous {
        Some(p) if p.h.is_finite() && p.h > 0.0 => {
            let k = 0.5 * h / p.h;
            x0.clone() * (1.0 + k) - p.x0.clone() * k
        }
        _ => x0,
    };
    let x_n = if stochastic {
        let e = (-h).exp();
        let keep = 1.0 - (-2.0 * h).exp();
        x_t * (sigma_n / sigma_t * e) + d * (alpha_n * keep) + noise * (sigma_n * keep.sqrt())
    } else {
        x_t * (sigma_n / sigma_t) + d * (alpha_n * (1.0 - (-h).exp()))
    };
    (x_n, h)
}

/// One DDPM ancestral step from `t` to `t − 1` (EDGE `p_sample`): the posterior mean
/// `coef1_t x̂0 + coef2_t x_t` plus `exp(½ log σ²_t) z`, no noise at `t = 0`.
pub fn ddpm_step(
    schedule: &Schedule,
    x_t: Tensor<3>,
    x0: Tensor<3>,
    t: usize,
    noise: Tensor<3>,
) -> Tensor<3> {
    let mean = x0 * schedule.posterior_mean_coef1[t] + x_t * schedule.posterior_mean_coef2[t];
    if t == 0 {
        mean
    } else {
        mean + noise * (0.5 * schedule.posterior_log_variance_clipped[t]).exp()
    }
}

/// A ReactDance LDCFG channel group: channels `range` guided with scale `s` (`w = 1 + s`).
#[derive(Clone, Debug, PartialEq)]
pub struct ChannelScale {
    pub range: Range<usize>,
    pub s: f64,
}

/// Classifier-free guidance.
#[derive(Clone, Debug, PartialEq)]
pub enum Guidance {
    /// The conditional prediction alone (one network call per step).
    Conditional,
    /// The unconditional prediction alone.
    Unconditional,
    /// EDGE: `unc + w · (cond − unc)`; `w = 1` is the conditional prediction, `w = 0` the
    /// unconditional one.
    Scale(f64),
    /// ReactDance layer-decoupled CFG (paper §3, "LDCFG"): `(1 + s_r) · cond − s_r · unc` on
    /// each group's channels, `(1 + default_s) · cond − default_s · unc` elsewhere. In EDGE's
    /// notation `w = 1 + s`.
    PerChannel {
        groups: Vec<ChannelScale>,
        default_s: f64,
    },
}

/// How the guidance weight changes over the sampling steps. Applied to `w` (EDGE form).
#[derive(Clone, Debug, PartialEq)]
pub enum WeightSchedule {
    Constant,
    /// EDGE long-form: step `i` of `n` uses `clip(linspace(0, 2w, n), max = w)[i]`
    /// = `w · min(2i/(n − 1), 1)` — unguided first, full weight from half way.
    EdgeRamp,
    /// EDGE's DDPM path: `w ← min(w, 1)` while `t < 0.1 · T`.
    EdgeDdpmLowT,
    /// An explicit factor per step multiplying `w`.
    Factors(Vec<f64>),
}

impl WeightSchedule {
    /// The factor / cap applied to a weight `w` at step `i` of `n`, timestep `t` of `big_t`.
    pub fn apply(&self, w: f64, i: usize, n: usize, t: usize, big_t: usize) -> f64 {
        match self {
            WeightSchedule::Constant => w,
            WeightSchedule::EdgeRamp => {
                if n <= 1 {
                    w
                } else {
                    (2.0 * w * i as f64 / (n - 1) as f64).min(w)
                }
            }
            WeightSchedule::EdgeDdpmLowT => {
                if (t as f64) < EDGE_DDPM_LOW_T_FRACTION * big_t as f64 {
                    w.min(1.0)
                } else {
                    w
                }
            }
            WeightSchedule::Factors(f) => w * f[i],
        }
    }
}

/// The combined prediction for a per-channel weight vector `w` `[C]`:
/// `unc + w ⊙ (cond − unc)`.
pub fn combine(cond: Tensor<3>, uncond: Tensor<3>, w: &[f64]) -> Tensor<3> {
    let dims = cond.dims();
    assert_eq!(w.len(), dims[2], "one guidance weight per channel");
    let device = cond.device();
    let wt: Vec<f32> = w.iter().map(|&v| v as f32).collect();
    let wt = Tensor::<3>::from_data(TensorData::new(wt, [1, 1, dims[2]]), &device).expand(dims);
    uncond.clone() + (cond - uncond) * wt
}

impl Guidance {
    /// Per-channel EDGE-form weights, or `None` for the single-branch modes.
    fn weights(&self, channels: usize) -> Option<Vec<f64>> {
        match self {
            Guidance::Conditional | Guidance::Unconditional => None,
            Guidance::Scale(w) => Some(vec![*w; channels]),
            Guidance::PerChannel { groups, default_s } => {
                let mut w = vec![1.0 + default_s; channels];
                for g in groups {
                    assert!(
                        g.range.end <= channels,
                        "LDCFG group {:?} beyond {channels} channels",
                        g.range
                    );
                    for c in g.range.clone() {
                        w[c] = 1.0 + g.s;
                    }
                }
                Some(w)
            }
        }
    }
}

/// When a [`Cue`] is enforced.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CueActivity {
    /// After every step (EDGE inpainting, Lodge's hard cues: first/last 4 frames).
    Hard,
    /// Lodge's soft cues with strength `soft ∈ [0, 1]`: enforced while the number of remaining
    /// steps `k` (n, n − 1, …, 1) satisfies `k > n · (1 − soft)`, so `soft = 1` acts at every
    /// step and `soft = 0.5` over the first half. (Lodge writes `t > 50 · (1 − soft)` with 50 steps.)
    Soft(f64),
}

/// An inpainting constraint: after a step into `t_next ≥ 0`,
/// `x = v · mask + x · (1 − mask)` with `v = q_sample(value, t_next)` when `noised` (EDGE
/// `inpaint_loop`) or `v = value` (Lodge `inpaint_soft_ddim`). After the final step
/// (`t_next = −1`) an active cue writes the clean `value`, so hard-masked entries of the result
/// equal the given values (EDGE instead leaves its last x̂0 there, one cause of the weak
/// constraints reported in Stanford-TML/EDGE#10).
#[derive(Clone, Debug)]
pub struct Cue {
    /// Known values `[B, T, C]`.
    pub value: Tensor<3>,
    /// 1 where the value is imposed, 0 elsewhere, `[B, T, C]` (see [`Cue::frames`] /
    /// [`Cue::channels`]).
    pub mask: Tensor<3>,
    pub noised: bool,
    pub activity: CueActivity,
}

impl Cue {
    /// A mask over frames `frames` (all channels) and channels `channels` (all frames set when
    /// `frames` is the full range): entries in both ranges are 1.
    pub fn mask(
        dims: [usize; 3],
        frames: Range<usize>,
        channels: Range<usize>,
        device: &Device,
    ) -> Tensor<3> {
        let [b, t, c] = dims;
        let mut m = vec![0f32; b * t * c];
        for bi in 0..b {
            for ti in frames.clone() {
                for ci in channels.clone() {
                    m[(bi * t + ti) * c + ci] = 1.0;
                }
            }
        }
        Tensor::from_data(TensorData::new(m, dims), device)
    }

    /// A mask over frames `frames`, every channel.
    pub fn frames(dims: [usize; 3], frames: Range<usize>, device: &Device) -> Tensor<3> {
        Self::mask(dims, frames, 0..dims[2], device)
    }

    /// A mask over channels `channels`, every frame.
    pub fn channels(dims: [usize; 3], channels: Range<usize>, device: &Device) -> Tensor<3> {
        Self::mask(dims, 0..dims[1], channels, device)
    }

    fn active(&self, remaining: usize, n: usize) -> bool {
        match self.activity {
            CueActivity::Hard => true,
            CueActivity::Soft(soft) => remaining as f64 > n as f64 * (1.0 - soft),
        }
    }
}

/// EDGE long-form constraint (`long_ddim_sample`): windows `[N, W, C]` of stride `W/2`; window
/// `i`'s first half is overwritten by window `i − 1`'s second half.
pub fn overwrite_first_halves(x: Tensor<3>) -> Tensor<3> {
    let [n, w, _] = x.dims();
    assert!(
        w.is_multiple_of(2),
        "long-form windows need an even length, got {w}"
    );
    if n < 2 {
        return x;
    }
    let half = w / 2;
    let rest = Tensor::cat(
        vec![
            x.clone().narrow(0, 0, n - 1).narrow(1, half, half),
            x.clone().narrow(0, 1, n - 1).narrow(1, half, half),
        ],
        1,
    );
    Tensor::cat(vec![x.narrow(0, 0, 1), rest], 0)
}

/// Everything about one sampling run except the model and its condition.
#[derive(Clone, Debug)]
pub struct SampleOptions {
    pub method: Method,
    /// Clamp x̂0 to this range (EDGE: [−1, 1]); `None` disables it.
    pub clip_x0: Option<(f64, f64)>,
    pub guidance: Guidance,
    pub weight_schedule: WeightSchedule,
    pub cues: Vec<Cue>,
    /// EDGE long-form: the batch is consecutive windows, overwritten after every step.
    pub long_form: bool,
    pub seed: u64,
    /// Starting `x_T` (default: seeded standard noise).
    pub init: Option<Tensor<3>>,
}

impl SampleOptions {
    /// EDGE's defaults: DDIM 50 steps, eta 1, x̂0 clamp [−1, 1], guidance w = 2.
    pub fn edge(seed: u64) -> Self {
        SampleOptions {
            method: Method::Ddim {
                steps: EDGE_DDIM_STEPS,
                eta: EDGE_DDIM_ETA,
                spacing: Spacing::Linear,
            },
            clip_x0: Some(EDGE_CLIP),
            guidance: Guidance::Scale(EDGE_GUIDANCE),
            weight_schedule: WeightSchedule::Constant,
            cues: Vec::new(),
            long_form: false,
            seed,
            init: None,
        }
    }

    /// EDGE's long-form sampler: [`SampleOptions::edge`] plus window overwrite and the ramp.
    pub fn edge_long_form(seed: u64) -> Self {
        SampleOptions {
            long_form: true,
            weight_schedule: WeightSchedule::EdgeRamp,
            ..Self::edge(seed)
        }
    }
}

/// The guided, clamped x̂0 at one step. `w` is `None` for the single-branch guidance modes.
#[allow(clippy::too_many_arguments)]
fn guided_x0<M: Denoiser>(
    model: &M,
    x: Tensor<3>,
    t: usize,
    cond: Option<&M::Cond>,
    guidance: &Guidance,
    w: Option<Vec<f64>>,
    clip: Option<(f64, f64)>,
    device: &Device,
) -> Tensor<3> {
    let b = x.dims()[0];
    let tt = || timestep_tensor(&vec![t; b], device);
    let pred = match (cond, guidance, w) {
        (None, _, _) | (_, Guidance::Unconditional, _) => {
            model.predict_x0(x, tt(), Conditioning::Null)
        }
        (Some(c), _, None) => model.predict_x0(x, tt(), Conditioning::Full(c)),
        (Some(c), _, Some(w)) => {
            let (pc, pu) = model.predict_x0_guided(x, tt(), c);
            combine(pc, pu, &w)
        }
    };
    match clip {
        Some((lo, hi)) => pred.clamp(lo, hi),
        None => pred,
    }
}

/// Samples `shape = [B, T, C]` from `model`. `cond = None` samples unconditionally whatever
/// the guidance. Deterministic given `opts.seed` (all noise comes from [`SeededNoise`]).
pub fn sample<M: Denoiser>(
    model: &M,
    schedule: &Schedule,
    shape: [usize; 3],
    cond: Option<&M::Cond>,
    opts: &SampleOptions,
    device: &Device,
) -> Tensor<3> {
    sample_hooked(model, schedule, shape, cond, opts, device, &NoHook)
        .expect("NoHook never cancels")
}

/// [`sample`], telling `hook` after every step (part [`DENOISING`], `done` of the run's steps)
/// and stopping with [`Cancelled`] when it answers `Break`. The same seed gives the same
/// result as [`sample`].
pub fn sample_hooked<M: Denoiser>(
    model: &M,
    schedule: &Schedule,
    shape: [usize; 3],
    cond: Option<&M::Cond>,
    opts: &SampleOptions,
    device: &Device,
    hook: &dyn StepHook,
) -> Result<Tensor<3>, Cancelled> {
    sample_with(model, schedule, shape, cond, opts, device, hook, &|x| x)
}

/// [`sample_hooked`] with a system's own constraint `between_steps`, applied to `x_t` after
/// every step but the last (after EDGE's long-form overwrite, before the cues): a window
/// overwrite that re-bases window-relative roots (TCDiff++'s groups, whose windows store roots
/// relative to their own frame-0 centroid), for instance.
#[allow(clippy::too_many_arguments)]
pub fn sample_with<M: Denoiser>(
    model: &M,
    schedule: &Schedule,
    shape: [usize; 3],
    cond: Option<&M::Cond>,
    opts: &SampleOptions,
    device: &Device,
    hook: &dyn StepHook,
    between_steps: &dyn Fn(Tensor<3>) -> Tensor<3>,
) -> Result<Tensor<3>, Cancelled> {
    let big_t = schedule.timesteps();
    let pairs: Vec<(usize, i64)> = match opts.method {
        Method::Ddpm => (0..big_t).rev().map(|t| (t, t as i64 - 1)).collect(),
        Method::Ddim { steps, spacing, .. } | Method::DpmSolverPp2m { steps, spacing, .. } => {
            ddim_timesteps_spaced(big_t, steps, spacing)
        }
    };
    let n = pairs.len();
    let mut rng = SeededNoise::new(opts.seed);
    let mut x = match &opts.init {
        Some(x) => x.clone(),
        None => rng.tensor(shape, device),
    };
    let base_w = opts.guidance.weights(shape[2]);
    let mut previous: Option<DpmPrevious> = None;
    for (i, &(t, t_next)) in pairs.iter().enumerate() {
        let w = base_w.as_ref().map(|w| {
            w.iter()
                .map(|&w| opts.weight_schedule.apply(w, i, n, t, big_t))
                .collect::<Vec<f64>>()
        });
        let x0 = guided_x0(
            model,
            x.clone(),
            t,
            cond,
            &opts.guidance,
            w,
            opts.clip_x0,
            device,
        );
        x = if t_next < 0 {
            x0
        } else {
            match opts.method {
                Method::Ddpm => ddpm_step(schedule, x, x0, t, rng.tensor(shape, device)),
                Method::Ddim { eta, .. } => {
                    ddim_step(schedule, x, x0, t, t_next, eta, rng.tensor(shape, device))
                }
                Method::DpmSolverPp2m { stochastic, .. } => {
                    // The ODE variant draws no noise.
                    let noise = if stochastic {
                        rng.tensor(shape, device)
                    } else {
                        Tensor::zeros(shape, device)
                    };
                    let (next, h) = dpmpp_2m_step(
                        schedule,
                        x,
                        x0.clone(),
                        previous.as_ref(),
                        t,
                        t_next,
                        stochastic,
                        noise,
                    );
                    previous = Some(DpmPrevious { x0, h });
                    next
                }
            }
        };
        if opts.long_form && t_next >= 0 {
            x = overwrite_first_halves(x);
        }
        if t_next >= 0 {
            x = between_steps(x);
        }
        let remaining = n - i;
        for cue in &opts.cues {
            if !cue.active(remaining, n) {
                continue;
            }
            let v = if cue.noised && t_next >= 0 {
                let tn = vec![t_next as usize; shape[0]];
                schedule.q_sample(cue.value.clone(), &tn, rng.tensor(shape, device))
            } else {
                cue.value.clone()
            };
            x = v * cue.mask.clone() + x * (cue.mask.clone().neg() + 1.0);
        }
        progress::step(hook, DENOISING, i + 1, n)?;
    }
    Ok(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quadratic_spacing_ends_near_zero_and_never_repeats() {
        // Six steps on T = 1000: ⌊999 · i² / 36⌋ for i = 6..1, then −1.
        let q: Vec<(usize, i64)> = ddim_timesteps_spaced(1000, 6, Spacing::Quadratic);
        assert_eq!(
            q,
            vec![
                (999, 693),
                (693, 444),
                (444, 249),
                (249, 111),
                (111, 27),
                (27, -1)
            ]
        );
        // EDGE's linear spacing predicts the output from t = 165 instead.
        assert_eq!(
            ddim_timesteps_spaced(1000, 6, Spacing::Linear).last(),
            Some(&(165, -1))
        );
        // As many steps as T: every timestep once, strictly decreasing.
        for steps in [1, 2, 50, 200, 1000] {
            let p = ddim_timesteps_spaced(1000, steps, Spacing::Quadratic);
            assert_eq!(p.len(), steps);
            assert_eq!(p[0].0, 999);
            assert_eq!(p.last().unwrap().1, -1);
            assert!(p.iter().all(|&(t, n)| (t as i64) > n), "{steps}: {p:?}");
            assert!(p.windows(2).all(|w| w[0].1 == w[1].0 as i64));
        }
    }
}
