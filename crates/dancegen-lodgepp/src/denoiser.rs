//! The PDDM denoise network (paper Fig. 5): `f_θ(d_t, d_p, c, t)` predicts the clean window x̂0
//! from the shifted-and-noised window `d_t`, the dance primitives `d_p` (with a mask saying
//! which frames hold a primitive) and the condition `c` = music + genre.
//!
//! EDGE's FiLM decoder (D.1) on `Linear([d_t; d_p; mask])` with rotary positions; the music is
//! encoded by a linear layer and `music_layers` transformer encoder layers and, with a genre
//! token, forms the cross-attention memory; the FiLM vector is timestep MLP + genre embedding +
//! pooled music. Classifier-free guidance replaces the music by a learned null token and the
//! genre by a null genre. After the main output comes the [`FootRefine`] block.

use dancegen_nn::attention::{AttnMasks, ProjectedKv};
use dancegen_nn::burn;
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
}

impl PddmConfig {
    /// A fresh network for `genres` genres and the data's normaliser (`mean`, `std`).
    pub fn init(&self, genres: usize, mean: &[f64], std: &[f64], device: &Device) -> PddmDenoiser {
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
        let x = Tensor::cat(vec![x_t, p.primitives.clone(), p.mask.clone()], 2);
        let mut h = self.input.forward(x);
        for (i, l) in self.layers.iter().enumerate() {
            h = l.forward_with_kv(h, &ctx, p.memory_kv.as_ref().map(|kv| &kv[i]));
        }
        let main = self.output.forward(h.clone());
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
