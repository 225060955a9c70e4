//! The HFSQ autoencoder (paper §"HFSQ", stage 1): the follower's three streams (upper body,
//! lower body + contacts, root relative to the leader; [`DuetFollower::STREAMS`]) each go
//! through their own temporal conv encoder, grouped residual FSQ ([`Hfsq`]) and conv decoder.
//!
//! The diffusion latent is the level outputs as **normalised codes** `v̂_r ∈ [−1, 1]`
//! (the level output divided by its scale `s_r`), laid out level-major —
//! `[level 0: upper | lower | root][level 1: …]…` — so one LDCFG guidance scale covers one
//! contiguous channel range, and every channel has the same range for the diffusion's x̂0 clamp.
//! Decoding sums `s_r·v̂_r` per stream: a continuous latent that need not sit on the grid.
//!
//! Loss (paper: `λ_kin·L_kinematic + λ_lat·L_latent`): L1 on the features, their velocity and
//! acceleration, plus a commitment term `‖z_e − sg(Σ_r s_r v̂_r)‖²` on the unmasked quantization.
//! Our addition, off by default: an L1 loss on the follower's foot velocities
//! ([`crate::follower_feet`]), and decoder-only fine-tuning ([`LossOptions`]).

use dancegen_motion::repr::DuetFollower;
use dancegen_nn::burn;
use dancegen_nn::conv::{ConvCodecConfig, ConvDecoder, ConvEncoder};
use dancegen_nn::loss::{self, Distance};
use dancegen_nn::quant::hfsq::{Hfsq, HfsqConfig};

use burn::module::Module;
use burn::tensor::{Device, Tensor};

use crate::config::HfsqAutoencoderConfig;
use crate::follower_feet::FollowerFeet;

/// One stream's encoder, quantizer and decoder.
#[derive(Module, Debug)]
pub struct StreamCodec {
    pub encoder: ConvEncoder,
    pub quantizer: Hfsq,
    pub decoder: ConvDecoder,
}

/// See the module documentation.
#[derive(Module, Debug)]
pub struct HfsqAutoencoder {
    pub streams: Vec<StreamCodec>,
    #[module(skip)]
    pub num_levels: usize,
    #[module(skip)]
    pub stream_dim: usize,
}

/// Training losses of the autoencoder.
pub struct AutoencoderLosses {
    pub total: Tensor<1>,
    pub position: Tensor<1>,
    pub velocity: Tensor<1>,
    pub acceleration: Tensor<1>,
    pub latent: Tensor<1>,
    /// The foot velocity loss, when [`LossOptions::feet`] is given and weighted.
    pub foot_velocity: Option<Tensor<1>>,
}

/// Training choices beyond the paper's loss.
#[derive(Clone, Debug)]
pub struct LossOptions {
    /// The follower's feet, for the foot velocity loss
    /// ([`HfsqAutoencoderConfig::foot_velocity_weight`]).
    pub feet: Option<FollowerFeet>,
    /// Frame rate of the features (the loss is in m/s).
    pub fps: f64,
    /// Train the decoders only: the levels come from this autoencoder's encoders and
    /// quantizers (on `dancegen_nn::device::inference()`), the model's own are not used, and the
    /// commitment term is left out (fine-tuning a shipped autoencoder under a trained latent
    /// model, whose latent must stay as it is).
    pub frozen_latent: Option<HfsqAutoencoder>,
}

impl Default for LossOptions {
    fn default() -> Self {
        Self {
            feet: None,
            fps: dancegen_motion::conventions::CANONICAL_FPS,
            frozen_latent: None,
        }
    }
}

impl HfsqAutoencoderConfig {
    pub fn init(&self, device: &Device) -> HfsqAutoencoder {
        let sd = self.stream_dim();
        let streams = DuetFollower::STREAMS
            .iter()
            .map(|r| {
                let codec = ConvCodecConfig::new(r.len(), r.len())
                    .with_width(self.width)
                    .with_depth(self.depth)
                    .with_down_t(self.down_t)
                    .with_stride_t(2)
                    .with_code_dim(sd);
                StreamCodec {
                    encoder: codec.init_encoder(device),
                    quantizer: HfsqConfig::new(sd, self.levels.clone())
                        .with_groups(self.groups)
                        .with_num_levels(self.num_levels)
                        .with_residual_mask_prob(self.residual_mask_prob)
                        .with_residual_noise_std(self.residual_noise_std)
                        .with_code_mask_prob(self.code_mask_prob)
                        .init(device),
                    decoder: codec.init_decoder(device),
                }
            })
            .collect();
        HfsqAutoencoder {
            streams,
            num_levels: self.num_levels,
            stream_dim: sd,
        }
    }
}

fn stream_input(x: &Tensor<3>, s: usize) -> Tensor<3> {
    let r = &DuetFollower::STREAMS[s];
    x.clone().narrow(2, r.start, r.len())
}

impl HfsqAutoencoder {
    /// Channels of the diffusion latent.
    pub fn latent_dim(&self) -> usize {
        self.num_levels * self.streams.len() * self.stream_dim
    }

    /// Reconstruction `[B, T, 151]` of normalised follower features (training: masked levels)
    /// and the losses against the input, with the paper's terms only.
    pub fn loss(
        &self,
        x: Tensor<3>,
        cfg: &HfsqAutoencoderConfig,
    ) -> (Tensor<3>, AutoencoderLosses) {
        self.loss_with(x, cfg, &LossOptions::default())
    }

    /// [`Self::loss`] with our additions ([`LossOptions`]).
    pub fn loss_with(
        &self,
        x: Tensor<3>,
        cfg: &HfsqAutoencoderConfig,
        opts: &LossOptions,
    ) -> (Tensor<3>, AutoencoderLosses) {
        let mut outs = Vec::with_capacity(self.streams.len());
        let mut latent = None::<Tensor<1>>;
        let device = x.device();
        for (s, codec) in self.streams.iter().enumerate() {
            let levels = match &opts.frozen_latent {
                Some(frozen) => {
                    // The levels of the frozen copy, computed off the graph: nothing of this
                    // model's encoder or quantizer is used, so nothing of it is differentiated
                    // (tracked encoder work whose outputs were detached stayed in the autodiff
                    // graph and grew the process by ~25 MB a step).
                    let f = &frozen.streams[s];
                    let xi = stream_input(&x, s)
                        .detach()
                        .to_device(&dancegen_nn::device::inference());
                    let (levels, _) = f.quantizer.residual_levels(f.encoder.forward(xi));
                    levels.into_iter().map(|l| l.to_device(&device)).collect()
                }
                None => {
                    let z = codec.encoder.forward(stream_input(&x, s));
                    let (levels, _) = codec.quantizer.residual_levels(z.clone());
                    let sum = levels
                        .iter()
                        .cloned()
                        .reduce(|a, b| a + b)
                        .expect("at least one level");
                    let commit = loss::commitment(z, sum);
                    latent = Some(match latent {
                        Some(l) => l + commit,
                        None => commit,
                    });
                    levels
                }
            };
            let masked = codec.quantizer.mask_levels(levels);
            let q = masked.into_iter().reduce(|a, b| a + b).expect("levels");
            outs.push(codec.decoder.forward(q));
        }
        let recon = Tensor::cat(outs, 2);
        let position = loss::reconstruction(recon.clone(), x.clone(), Distance::L1);
        let velocity = loss::velocity(recon.clone(), x.clone(), Distance::L1);
        let acceleration = loss::acceleration(recon.clone(), x.clone(), Distance::L1);
        let mut total = position.clone() * cfg.position_weight
            + velocity.clone() * cfg.velocity_weight
            + acceleration.clone() * cfg.acceleration_weight;
        // Frozen: no commitment term (the encoders are not trained); logged as 0.
        let latent = match latent {
            Some(l) => {
                total = total + l.clone() * cfg.latent_weight;
                l
            }
            None => Tensor::zeros([1], &device),
        };
        let foot_velocity = match &opts.feet {
            Some(feet) if cfg.foot_velocity_weight > 0.0 => {
                let l = feet.velocity_loss(recon.clone(), x, opts.fps);
                total = total + l.clone() * cfg.foot_velocity_weight;
                Some(l)
            }
            _ => None,
        };
        (
            recon,
            AutoencoderLosses {
                total,
                position,
                velocity,
                acceleration,
                latent,
                foot_velocity,
            },
        )
    }

    /// Normalised follower features `[B, T, 151]` → the diffusion latent `[B, T / 2^down_t, C]`
    /// (normalised codes, level-major; unmasked).
    pub fn encode(&self, x: Tensor<3>) -> Tensor<3> {
        let device = x.device();
        let mut per_level: Vec<Vec<Tensor<3>>> = vec![Vec::new(); self.num_levels];
        for (s, codec) in self.streams.iter().enumerate() {
            let z = codec.encoder.forward(stream_input(&x, s));
            let (levels, _) = codec.quantizer.residual_levels(z);
            for (r, l) in levels.into_iter().enumerate() {
                per_level[r].push(l / codec.quantizer.level_scale(r, &device));
            }
        }
        Tensor::cat(per_level.into_iter().flatten().collect(), 2)
    }

    /// The diffusion latent `[B, N, C]` → follower features `[B, N·2^down_t, 151]`. With
    /// `levels < R` only the first `levels` levels are used (the coarse motion alone).
    pub fn decode(&self, latent: Tensor<3>) -> Tensor<3> {
        self.decode_levels(latent, self.num_levels)
    }

    pub fn decode_levels(&self, latent: Tensor<3>, levels: usize) -> Tensor<3> {
        let device = latent.device();
        let sd = self.stream_dim;
        let ns = self.streams.len();
        let outs = self
            .streams
            .iter()
            .enumerate()
            .map(|(s, codec)| {
                let q = (0..levels.min(self.num_levels))
                    .map(|r| {
                        latent.clone().narrow(2, (r * ns + s) * sd, sd)
                            * codec.quantizer.level_scale(r, &device)
                    })
                    .reduce(|a, b| a + b)
                    .expect("at least one level");
                codec.decoder.forward(q)
            })
            .collect();
        Tensor::cat(outs, 2)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use dancegen_nn::device;

    #[test]
    fn latent_round_trip_matches_the_quantized_reconstruction() {
        let cfg = HfsqAutoencoderConfig {
            width: 16,
            depth: 1,
            ..Default::default()
        };
        let dev = device::inference();
        let ae = cfg.init(&dev);
        let x = Tensor::<3>::random(
            [2, 32, DuetFollower::DIMS],
            burn::tensor::Distribution::Normal(0.0, 1.0),
            &dev,
        );
        let z = ae.encode(x.clone());
        assert_eq!(z.dims(), [2, 8, cfg.latent_dim()]);
        // Normalised codes stay in [−1, 1].
        let max = z.clone().abs().max().into_scalar::<f32>();
        assert!(max <= 1.0 + 1e-5, "code magnitude {max}");
        let (recon, _) = ae.loss(x, &cfg);
        let dec = ae.decode(z);
        let diff = (dec - recon).abs().max().into_scalar::<f32>();
        assert!(
            diff < 1e-4,
            "decode(encode(x)) differs from the forward pass by {diff}"
        );
    }
}
