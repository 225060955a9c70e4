//! The PDDM denoise network (paper Fig. 5): `f_θ(d_t, d_p, c, t)` predicts the clean window x̂0
//! from the shifted-and-noised window `d_t`, the dance primitives `d_p` (with a mask saying
//! which frames hold a primitive) and the condition `c` = music + genre.
//!
//! EDGE's FiLM decoder (D.1) on `Linear([d_t; d_p; mask])` with rotary positions; the music is
//! encoded by a linear layer and `music_layers` transformer encoder layers and, with a genre
//! token, forms the cross-attention memory; the FiLM vector is timestep MLP + genre embedding +
//! pooled music. Classifier-free guidance replaces the music by a learned null token and the
//! genre by a null genre. After the main output comes the [`FootRefine`] block. With
//! `x0_skip` (not Lodge++) the main output is added to a noise-dependent share of the input
//! ([`X0Skip`]).

use dancegen_nn::attention::{AttnMasks, ProjectedKv};
use dancegen_nn::burn;
use dancegen_nn::diffusion::pddm::ResidualShift;
use dancegen_nn::diffusion::{Conditioning, Denoiser};
use dancegen_nn::loss::FkSkeleton;
use dancegen_nn::pos_encoding::{Rotary, sinusoidal};
use dancegen_nn::timestep::{TimestepMlp, TimestepMlpConfig};
use dancegen_nn::transformer::{
    DecoderContext, EncoderLayer, EncoderLayerConfig, FilmDecoderLayer, FilmDecoderLayerConfig,
};

use burn::module::{Module, Param};
use burn::nn::{Embedding, EmbeddingConfig, Linear, LinearConfig};
use burn::tensor::{Device, Int, Tensor, TensorData};

use crate::choreo_gpt::MUSIC_DIMS;
use crate::config::PddmConfig;
use crate::foot_refine::FootRefine;
use crate::kinematics::Denormalize;
use crate::layout::DIMS;

/// What the PDDM is conditioned on for one batch of windows.
#[derive(Clone, Debug)]
pub struct PddmCond {
    /// `[B, T, 35]`.
    pub music: Tensor<3>,
    /// Genre index per window.
    pub genre: Vec<usize>,
    /// The primitives `d_p` `[B, T, 151]` (normalised; zero away from primitives).
    pub primitives: Tensor<3>,
    /// `[B, T, 1]`: 1 on frames that hold a primitive.
    pub mask: Tensor<3>,
    /// The music already encoded by [`PddmDenoiser::encode_music`] (`[B, T, d]`): the music is
    /// the same at every denoising step, so samplers encode it once.
    pub music_encoded: Option<Tensor<3>>,
}

/// The network's two outputs.
pub struct PddmOutput {
    /// Main decoder's x̂0.
    pub main: Tensor<3>,
    /// x̂0 after the Foot Refine Block (equal to `main` without it).
    pub refined: Tensor<3>,
}

/// See the module documentation.
#[derive(Module, Debug)]
pub struct PddmDenoiser {
    pub input: Linear,
    pub time: TimestepMlp,
    pub time_cond: Linear,
    pub music_in: Linear,
    pub music_layers: Vec<EncoderLayer>,
    pub null_music: Param<Tensor<3>>,
    /// `genres + 1` rows: the last is the null genre.
    pub genre: Embedding,
    pub layers: Vec<FilmDecoderLayer>,
    pub output: Linear,
    pub refine: Option<FootRefine>,
    pub denorm: Denormalize,
    pub genres: usize,
    pub d_model: usize,
    /// Set by the config (`x0_skip`), never stored with the weights.
    #[module(skip)]
    pub skip: Option<X0Skip>,
}

/// The skip of EDM's preconditioning (Karras et al. 2022, eq. 7 with `c_out = 1`) on the
/// residual-shift process: `x̂0 = c_skip(t) · ỹ_t + F(d_t, …)`, where
/// `ỹ_t = (d_t − η_t d_p) / (1 − η_t)` is the clean window plus noise of standard deviation
/// `σ_t = κ √η_t / (1 − η_t)` (eq. 9 solved for `d0`) and `c_skip = 1 / (1 + σ_t²)` (the
/// data are normalised to unit variance). At the last steps (`σ_1` = 0.04) the window passes
/// through almost unchanged and the network learns the correction; at the first
/// (`c_skip` ≈ 2.5e-7) it predicts x̂0 alone, as without the skip.
#[derive(Clone, Debug)]
pub struct X0Skip {
    /// `η_t` and `c_skip(t)` for the 0-based timestep the network sees (`t − 1`).
    coefficients: Vec<(f32, f32)>,
}

impl X0Skip {
    pub fn new(schedule: &ResidualShift) -> Self {
        let coefficients = (1..=schedule.steps())
            .map(|t| {
                let eta = schedule.eta[t];
                let sigma = schedule.kappa * eta.sqrt() / (1.0 - eta);
                (eta as f32, (1.0 / (1.0 + sigma * sigma)) as f32)
            })
            .collect();
        X0Skip { coefficients }
    }

    /// `c_skip · ỹ_t` for windows `d_t` at 0-based timesteps `t` (one per window), with
    /// primitives `d_p`.
    pub fn apply(&self, d_t: Tensor<3>, d_p: Tensor<3>, t: &[f32]) -> Tensor<3> {
        let [b, _, _] = d_t.dims();
        assert_eq!(t.len(), b, "one timestep per window");
        let device = d_t.device();
        let (mut eta, mut input, mut prims) = (vec![], vec![], vec![]);
        for &t in t {
            let last = self.coefficients.len() - 1;
            let (e, c) = self.coefficients[(t.round().max(0.0) as usize).min(last)];
            eta.push(e);
            // c_skip · (d_t − η d_p) / (1 − η)
            input.push(c / (1.0 - e));
            prims.push(-c * e / (1.0 - e));
        }
        let col = |v: Vec<f32>| Tensor::<3>::from_data(TensorData::new(v, [b, 1, 1]), &device);
        d_t * col(input) + d_p * col(prims)
    }
}

impl PddmConfig {
    /// A fresh network for `genres` genres, the data's normaliser (`mean`, `std`) and the
    /// residual-shift `schedule` it is trained on (used by `x0_skip`).
    pub fn init(
        &self,
        genres: usize,
        mean: &[f64],
        std: &[f64],
        schedule: &ResidualShift,
        device: &Device,
    ) -> PddmDenoiser {
        let d = self.d_model;
        PddmDenoiser {
            input: LinearConfig::new(2 * DIMS + 1, d).init(device),
            time: TimestepMlpConfig::new(d).init(device),
            time_cond: LinearConfig::new(4 * d, d).init(device),
            music_in: LinearConfig::new(MUSIC_DIMS, d).init(device),
            music_layers: (0..self.music_layers)
                .map(|_| {
                    EncoderLayerConfig::new(d, self.n_heads, self.d_ff)
                        .with_dropout(self.dropout)
                        .init(device)
                })
                .collect(),
            null_music: Param::from_tensor(Tensor::zeros([1, 1, d], device)),
            genre: EmbeddingConfig::new(genres + 1, d).init(device),
            layers: (0..self.n_layers)
                .map(|_| {
                    FilmDecoderLayerConfig::new(d, self.n_heads, self.d_ff)
                        .with_dropout(self.dropout)
                        .init(device)
                })
                .collect(),
            output: LinearConfig::new(d, DIMS).init(device),
            refine: self
                .foot_refine
                .then(|| FootRefine::new(d, self.n_heads, self.d_ff, self.dropout, device)),
            denorm: Denormalize::from_mean_std(mean, std, device),
            genres,
            d_model: d,
            skip: self.x0_skip.then(|| X0Skip::new(schedule)),
        }
    }
}

/// Which batch elements see the condition.
enum Keep<'a> {
    All,
    None,
    Some(&'a [bool]),
}

impl PddmDenoiser {
    /// Encoded music `[B, T, d]`.
    pub fn encode_music(&self, music: Tensor<3>) -> Tensor<3> {
        let h = self.music_in.forward(music);
        let [_, t, d] = h.dims();
        let pos = sinusoidal(0, t, d, &h.device()).unsqueeze::<3>();
        let mut h = h + pos;
        let masks = AttnMasks::default();
        for l in &self.music_layers {
            h = l.forward(h, &masks, None);
        }
        h
    }

    /// x̂0 of `x_t` `[B, T, 151]` at 0-based timesteps `t`; `refine = false` skips the Foot
    /// Refine Block (ablation).
    pub fn forward(
        &self,
        x_t: Tensor<3>,
        t: &[f32],
        cond: Conditioning<'_, PddmCond>,
        refine: bool,
    ) -> PddmOutput {
        let [b, frames, _] = x_t.dims();
        let device = x_t.device();
        let d = self.d_model;
        let (c, keep) = match cond {
            Conditioning::Full(c) => (c, Keep::All),
            Conditioning::Null => panic!("the PDDM always needs its primitives: use Dropout"),
            Conditioning::Dropout { cond, keep } => (cond, Keep::Some(keep)),
        };
        self.forward_keep(x_t, t, c, keep, refine, b, frames, d, &device)
    }

    /// The unconditional branch of guidance: music and genre dropped, primitives kept.
    pub fn forward_null(
        &self,
        x_t: Tensor<3>,
        t: &[f32],
        c: &PddmCond,
        refine: bool,
    ) -> PddmOutput {
        let [b, frames, _] = x_t.dims();
        let device = x_t.device();
        self.forward_keep(
            x_t,
            t,
            c,
            Keep::None,
            refine,
            b,
            frames,
            self.d_model,
            &device,
        )
    }

    #[allow(clippy::too_many_arguments)]
    fn forward_keep(
        &self,
        x_t: Tensor<3>,
        t: &[f32],
        c: &PddmCond,
        keep: Keep<'_>,
        refine: bool,
        b: usize,
        frames: usize,
        d: usize,
        device: &Device,
    ) -> PddmOutput {
        let keep_vec: Vec<bool> = match keep {
            Keep::All => vec![true; b],
            Keep::None => vec![false; b],
            Keep::Some(k) => k.to_vec(),
        };
        let prepared = self.prepare_with(c, &keep_vec, frames, d, false, device);
        self.forward_prepared(x_t, t, &prepared, refine)
    }

    /// Everything of the condition that does not change between denoising steps, for
    /// [`Self::forward_prepared`]: the cross-attention memory (music or the null token, and
    /// the genre) with each decoder layer's key/value projections of it, and the step-free part
    /// of the FiLM vector. `keep[i]`: window `i` sees music and genre (false = the guidance's
    /// unconditional branch).
    pub fn prepare(&self, c: &PddmCond, keep: &[bool]) -> PreparedCond {
        let [b, frames, _] = c.primitives.dims();
        assert_eq!(keep.len(), b, "one keep flag per window");
        self.prepare_with(c, keep, frames, self.d_model, true, &c.primitives.device())
    }

    fn prepare_with(
        &self,
        c: &PddmCond,
        keep_vec: &[bool],
        frames: usize,
        d: usize,
        project: bool,
        device: &Device,
    ) -> PreparedCond {
        let b = keep_vec.len();
        let null = self.null_music.val().expand([b, frames, d]);
        let music = if keep_vec.iter().all(|&k| !k) {
            null
        } else {
            let enc = match &c.music_encoded {
                Some(e) => e.clone(),
                None => self.encode_music(c.music.clone()),
            };
            if keep_vec.iter().all(|&k| k) {
                enc
            } else {
                let k: Vec<f32> = keep_vec.iter().map(|&k| f32::from(u8::from(k))).collect();
                let k = Tensor::<1>::from_data(TensorData::new(k, [b]), device).reshape([b, 1, 1]);
                enc * k.clone() + null * (k.neg() + 1.0)
            }
        };
        let genre: Vec<i64> = c
            .genre
            .iter()
            .zip(keep_vec)
            .map(|(&g, &k)| if k { g as i64 } else { self.genres as i64 })
            .collect();
        let genre = self.genre.forward(Tensor::<2, Int>::from_data(
            TensorData::new(genre, [b, 1]),
            device,
        ));
        let memory = Tensor::cat(vec![music.clone(), genre.clone()], 1);
        let film_cond = genre.reshape([b, d]) + music.mean_dim(1).reshape([b, d]);
        let memory_kv = project.then(|| {
            self.layers
                .iter()
                .map(|l| l.cross_kv(memory.clone()))
                .collect()
        });
        PreparedCond {
            primitives: c.primitives.clone(),
            mask: c.mask.clone(),
            memory,
            memory_kv,
            film_cond,
        }
    }

    /// The network on a condition from [`Self::prepare`] (same output as [`Self::forward`]).
    pub fn forward_prepared(
        &self,
        x_t: Tensor<3>,
        t: &[f32],
        p: &PreparedCond,
        refine: bool,
    ) -> PddmOutput {
        let frames = x_t.dims()[1];
        let device = x_t.device();
        let film = self.time_cond.forward(self.time.forward(t, &device)) + p.film_cond.clone();
        let rotary = Rotary::new(self.d_model).tables(0, frames, &device);
        let none = AttnMasks::default();
        let ctx = DecoderContext {
            memory: p.memory.clone(),
            cond: film.clone().unsqueeze_dim(1),
            self_masks: &none,
            cross_masks: &none,
            rotary: Some(&rotary),
        };
        let skipped = self
            .skip
            .as_ref()
            .map(|s| s.apply(x_t.clone(), p.primitives.clone(), t));
        let x = Tensor::cat(vec![x_t, p.primitives.clone(), p.mask.clone()], 2);
        let mut h = self.input.forward(x);
        for (i, l) in self.layers.iter().enumerate() {
            h = l.forward_with_kv(h, &ctx, p.memory_kv.as_ref().map(|kv| &kv[i]));
        }
        let main = match skipped {
            Some(s) => s + self.output.forward(h.clone()),
            None => self.output.forward(h.clone()),
        };
        let refined = match (&self.refine, refine) {
            (Some(r), true) => {
                main.clone() + r.forward(h, main.clone(), film, &self.denorm, &FkSkeleton::smpl24())
            }
            _ => main.clone(),
        };
        PddmOutput { main, refined }
    }
}

/// The step-invariant part of a condition ([`PddmDenoiser::prepare`]).
#[derive(Clone, Debug)]
pub struct PreparedCond {
    /// `[B, T, 151]`.
    pub primitives: Tensor<3>,
    /// `[B, T, 1]`.
    pub mask: Tensor<3>,
    /// Cross-attention tokens `[B, T + 1, d]`.
    pub memory: Tensor<3>,
    /// Each decoder layer's key/value projections of `memory`.
    pub memory_kv: Option<Vec<ProjectedKv>>,
    /// Genre embedding + pooled music `[B, d]`.
    pub film_cond: Tensor<2>,
}

/// The denoiser as the shared samplers see it: its refined x̂0, with or without the refine
/// block.
pub struct PddmSampling<'a> {
    pub net: &'a PddmDenoiser,
    pub refine: bool,
}

impl Denoiser for PddmSampling<'_> {
    type Cond = PddmCond;

    fn predict_x0(
        &self,
        x_t: Tensor<3>,
        t: Tensor<1, Int>,
        cond: Conditioning<'_, PddmCond>,
    ) -> Tensor<3> {
        let t: Vec<f32> = t.into_data().convert::<f32>().try_to_vec::<f32>().unwrap();
        match cond {
            Conditioning::Null => panic!("PddmSampling needs the condition (primitives)"),
            c => self.net.forward(x_t, &t, c, self.refine).refined,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use dancegen_nn::diffusion::pddm::ResidualShiftConfig;

    fn host(x: Tensor<3>) -> Vec<f32> {
        x.into_data().convert::<f32>().try_to_vec::<f32>().unwrap()
    }

    #[test]
    fn the_skip_removes_the_primitive_shift_and_fades_with_noise() {
        let dev = dancegen_nn::device::inference();
        let schedule = ResidualShiftConfig::lodgepp().init();
        let skip = X0Skip::new(&schedule);
        let (b, t, d) = (2, 3, 4);
        let d0: Vec<f32> = (0..b * t * d).map(|i| (i as f32 * 0.37).sin()).collect();
        let dp: Vec<f32> = (0..b * t * d).map(|i| (i as f32 * 0.11).cos()).collect();
        let d0t = Tensor::<3>::from_data(TensorData::new(d0.clone(), [b, t, d]), &dev);
        let dpt = Tensor::<3>::from_data(TensorData::new(dp, [b, t, d]), &dev);
        // Without noise, ỹ_t is the clean window at every step: c_skip · d0.
        for step in [1usize, 25, 50] {
            let d_t = schedule.q_sample(
                d0t.clone(),
                dpt.clone(),
                &[step, step],
                Tensor::zeros([b, t, d], &dev),
            );
            let out = host(skip.apply(d_t, dpt.clone(), &[(step - 1) as f32; 2]));
            let eta = schedule.eta[step];
            let sigma = schedule.kappa * eta.sqrt() / (1.0 - eta);
            let c = 1.0 / (1.0 + sigma * sigma);
            for (o, x) in out.iter().zip(&d0) {
                assert!(
                    (f64::from(*o) - c * f64::from(*x)).abs() < 1e-4,
                    "step {step}: {o} against {}",
                    c * f64::from(*x)
                );
            }
        }
        // Nearly all of the input passes at the last step, nearly none at the first.
        let (_, c1) = skip.coefficients[0];
        let (_, c50) = skip.coefficients[49];
        assert!(c1 > 0.99, "c_skip at t = 1: {c1}");
        assert!(c50 < 1e-5, "c_skip at t = 50: {c50}");
    }
}
