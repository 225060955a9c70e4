//! Reverse PDDM process over a batch of windows (paper §3.4.1 and §3.4.6): start from the
//! primitives plus noise, `d_T = d_p + κ √η_T z`, and step down with the network's x̂0, with
//! classifier-free guidance on music + genre (both branches in one batched forward), optional
//! penetration guidance on x̂0, and hard cues (the shared boundary frames) written after every
//! step, as in training where those frames of `d_t` are the clean values.

use dancegen_nn::burn;
use dancegen_nn::diffusion::noise::SeededNoise;
use dancegen_nn::diffusion::pddm::ResidualShift;
use dancegen_nn::progress::{self, Cancelled, DENOISING, NoHook, StepHook};

use burn::tensor::{Device, Tensor};

use crate::denoiser::{PddmCond, PddmDenoiser, PddmOutput};
pub use crate::foot_refine::FootRefineScope;
use crate::penetration::{CapsulePairs, PenetrationGuidance, guide};

/// Frames and channels fixed to known values after every step.
#[derive(Clone, Debug)]
pub struct HardCues {
    /// `[B, T, 151]`.
    pub values: Tensor<3>,
    /// `[B, T, 151]`, 1 where fixed.
    pub mask: Tensor<3>,
}

impl HardCues {
    fn apply(&self, x: Tensor<3>) -> Tensor<3> {
        self.values.clone() * self.mask.clone() + x * (self.mask.clone().neg() + 1.0)
    }
}

/// How to run the reverse process.
#[derive(Clone, Debug)]
pub struct PddmSampleOptions {
    /// Denoising steps (evenly strided over the trained `T`; Lodge++: 50 = all).
    pub steps: usize,
    /// Classifier-free guidance weight `w` of `x̂0 = x̂0_null + w (x̂0_cond − x̂0_null)`
    /// (Lodge / EDGE: 2; 1 = conditional only, one forward per step).
    pub guidance: f64,
    /// Use the Foot Refine Block.
    pub refine: bool,
    /// Final denoising steps the Foot Refine Block acts on (`None`: every step, as Lodge++).
    /// Fewer steps leave the dance faster (the block slows the whole body), but on the training
    /// songs every N tried scored a worse FID_k than every step (docs/solo-data-v2.md, round
    /// eight), so no shipped model sets it.
    pub refine_last_steps: Option<usize>,
    /// Channels the refinement is added to.
    pub refine_scope: FootRefineScope,
    /// Penetration guidance and the number of final steps it acts on.
    pub penetration: Option<(PenetrationGuidance, usize)>,
    pub seed: u64,
}

/// Samples `[B, T, 151]` windows (normalised) with `cues` written after every step.
/// `grad_device` is the autodiff device used by the penetration guidance.
pub fn sample_windows(
    net: &PddmDenoiser,
    shift: &ResidualShift,
    cond: &PddmCond,
    cues: Option<&HardCues>,
    opts: &PddmSampleOptions,
    device: &Device,
    grad_device: &Device,
) -> Tensor<3> {
    sample_windows_hooked(net, shift, cond, cues, opts, device, grad_device, &NoHook)
        .expect("NoHook never cancels")
}

/// [`sample_windows`], telling `hook` after every step (part [`DENOISING`]) and stopping with
/// [`Cancelled`] when it answers `Break`.
#[allow(clippy::too_many_arguments)]
pub fn sample_windows_hooked(
    net: &PddmDenoiser,
    shift: &ResidualShift,
    cond: &PddmCond,
    cues: Option<&HardCues>,
    opts: &PddmSampleOptions,
    device: &Device,
    grad_device: &Device,
    hook: &dyn StepHook,
) -> Result<Tensor<3>, Cancelled> {
    sample_windows_with(
        net,
        shift,
        cond,
        opts,
        device,
        grad_device,
        |d, _| match cues {
            Some(c) => c.apply(d),
            None => d,
        },
        hook,
    )
}

/// [`sample_windows`] with any constraint `after_step(x, is_final)` applied to the initial state
/// and after every step (EDGE's long-form overwrite, hard cues); `is_final` marks the result of
/// the last step. `hook` hears of every step (part [`DENOISING`]).
#[allow(clippy::too_many_arguments)]
pub fn sample_windows_with(
    net: &PddmDenoiser,
    shift: &ResidualShift,
    cond: &PddmCond,
    opts: &PddmSampleOptions,
    device: &Device,
    grad_device: &Device,
    after_step: impl Fn(Tensor<3>, bool) -> Tensor<3>,
    hook: &dyn StepHook,
) -> Result<Tensor<3>, Cancelled> {
    let dims = cond.primitives.dims();
    let b = dims[0];
    let mut rng = SeededNoise::new(opts.seed);
    let big_t = shift.steps();
    let mut d = cond.primitives.clone()
        + rng.tensor(dims, device) * (shift.kappa * shift.eta[big_t].sqrt());
    d = after_step(d, false);
    let guided = (opts.guidance - 1.0).abs() > 1e-9;
    let encoded = cond
        .music_encoded
        .clone()
        .unwrap_or_else(|| net.encode_music(cond.music.clone()));
    let cond = &PddmCond {
        music_encoded: Some(encoded.clone()),
        ..cond.clone()
    };
    // Music, genre and their cross-attention projections are the same at every step.
    let prepared = if guided {
        let doubled = PddmCond {
            music: Tensor::cat(vec![cond.music.clone(), cond.music.clone()], 0),
            genre: [cond.genre.clone(), cond.genre.clone()].concat(),
            primitives: Tensor::cat(vec![cond.primitives.clone(), cond.primitives.clone()], 0),
            mask: Tensor::cat(vec![cond.mask.clone(), cond.mask.clone()], 0),
            music_encoded: Some(Tensor::cat(vec![encoded.clone(), encoded], 0)),
        };
        let keep: Vec<bool> = (0..2 * b).map(|i| i < b).collect();
        net.prepare(&doubled, &keep)
    } else {
        net.prepare(cond, &vec![true; b])
    };
    let pairs = opts.penetration.map(|_| CapsulePairs::new());
    let ts = shift.strided(opts.steps);
    let scope = opts.refine_scope.mask(device);
    // x̂0 of one forward: the refined output, or the main one plus the refinement on `scope`.
    let x0_of = |out: PddmOutput| match &scope {
        Some(m) => out.main.clone() + (out.refined - out.main) * m.clone(),
        None => out.refined,
    };
    for (i, &t) in ts.iter().enumerate() {
        let s = ts.get(i + 1).copied().unwrap_or(0);
        let refine = opts.refine && opts.refine_last_steps.is_none_or(|k| ts.len() - i <= k);
        let mut x0 = if guided {
            let tt = vec![(t - 1) as f32; 2 * b];
            let both = x0_of(net.forward_prepared(
                Tensor::cat(vec![d.clone(), d.clone()], 0),
                &tt,
                &prepared,
                refine,
            ));
            let c = both.clone().narrow(0, 0, b);
            let u = both.narrow(0, b, b);
            u.clone() + (c - u) * opts.guidance
        } else {
            let tt = vec![(t - 1) as f32; b];
            x0_of(net.forward_prepared(d.clone(), &tt, &prepared, refine))
        };
        if let (Some((g, last)), Some(p)) = (&opts.penetration, &pairs)
            && ts.len() - i <= *last
        {
            x0 = guide(x0, &net.denorm, p, g, grad_device);
        }
        d = after_step(shift.step_to(d, x0, t, s, rng.tensor(dims, device)), s == 0);
        progress::step(hook, DENOISING, i + 1, ts.len())?;
    }
    Ok(d)
}
