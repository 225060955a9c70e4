//! The model configuration (`[model]` of a training config, `model.toml` of a bundle).
//!
//! Paper values (TCDiff++ §5.1) are d = 512, M = 8 layers, 8 heads, a 3-layer ReLU fusion MLP,
//! W = 3 ConcatSquashLinear layers and the loss weights below. AIOZ-GDance has 16.7 h of group
//! motion; we have about 8 minutes of distinct real motion, so the defaults follow group.md §4
//! "Model size" (d = 128–192, 4 layers, 4 heads, N_max = 5 with masks, 150 frames, DDIM 20).
//! Every ablation of the paper's Table 4 is a switch here.

use dancegen_nn::diffusion::{Solver, Spacing};
use dancegen_refine::foot_lock::PlantedRule;
use serde::{Deserialize, Serialize};

use crate::prediction::Prediction;

/// Which mixer follows the self-attention in each Sequence Decoder layer.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SequenceMixer {
    /// EDGE's cross-attention to the memory (the released code's default, `--use_ssm False`).
    CrossAttention,
    /// The released `CrossMamba`: Mamba v1 plus a linear cross-attention to the memory (paper
    /// §4.1 "Sequence Decoder", group.md §1 row 4).
    Mamba,
}

/// The network.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct DenoiserConfig {
    pub d_model: usize,
    pub n_layers: usize,
    pub n_heads: usize,
    pub d_ff: usize,
    /// Transformer encoder layers over the music tokens (EDGE's condition encoder: 2).
    pub music_layers: usize,
    pub dropout: f64,
    pub mixer: SequenceMixer,
    /// Fusion Projection (paper §4.1); `false` is Table 4's "w/o FP".
    pub fusion_projection: bool,
    /// Hidden width of the fusion MLP; the released code uses `2 · d_model` (1024 for 512).
    pub fusion_hidden: Option<usize>,
    /// Our option, not the paper's: the fusion MLP as a residual branch, `h + FP(h)`. The
    /// released FP replaces the tokens (no residual), which at d = 512 keeps the noisy input:
    /// its 1024 hidden units exceed the N × 151 channels of x_t. At d = 128 the default 256
    /// units cannot carry five dancers' 755 channels, so without the residual the decoder
    /// never sees most of x_t (docs/group-eval.md, "Motion energy").
    pub fusion_residual: bool,
    /// Dancer positioning embedding (rank code per slot); `false` keeps only the temporal
    /// code of each frame ("w/o DPE").
    pub positioning: bool,
    /// Swap mode S as FiLM input and memory token ("w/o SM").
    pub swap_mode: bool,
    /// Footwork Adaptor ("w/o FA").
    pub footwork: bool,
    /// Hidden width of the footwork adaptor (released: 128).
    pub footwork_hidden: usize,
    /// Our option, not the paper's: the adaptor adds a correction to the decoder's lower-body
    /// rotations (`x + FA(x)`, its last layer starting at zero) instead of replacing them. The
    /// replacing adaptor of the small model learns one crossed-shin pose and holds it
    /// whatever the decoder says (docs/group-collapse.md, "The footwork adaptor").
    pub footwork_residual: bool,
    /// Our option, not the paper's: each dancer's root x/y is integrated from per-frame steps
    /// and placed at the window mean of the decoder's root output ([`crate::root_path`]), so
    /// the noise the decoder reads cannot make the root jump between frames
    /// (docs/group-collapse.md §11).
    pub root_integrated: bool,
    /// What the last layer predicts: x̂0 (the paper's), `v` (our option, the
    /// v-parameterisation with its skip from x_t) or `x0_skip` (our option, x̂0 plus a learned
    /// skip from x_t); [`crate::prediction`].
    pub prediction: Prediction,
    /// With `prediction = "x0_skip"`: the widths (Gaussian σ, frames) of the smoothings of x_t
    /// the learned skip mixes; 0 is x_t itself ([`crate::prediction::SkipGate`]).
    pub skip_smoothing: Vec<f64>,
    /// Whether those smoothings (σ > 0) carry the root rotation too (v12: yes; in fast turns
    /// under a formation the body tipped over, docs/group-collapse.md §20).
    pub skip_smooth_root_rotation: bool,
    /// Our option, not the paper's: each dancer's root rotation in x̂0 is split into a heading
    /// and the rest (the tilt); the heading is x̂0's own plus a learned turn integrated from
    /// per-frame turns ([`crate::heading_path`]). With `root_rotation_smoothing`, both are
    /// smoothed, the heading as an angle, so that neither the input's noise nor a smoothing of
    /// the 6D rows across a fast turn reaches them (docs/group-collapse.md §21).
    pub heading_integrated: bool,
    /// With `heading_integrated`: σ in frames of the root rotation's smoothing (0: none).
    pub root_rotation_smoothing: f64,
}

impl Default for DenoiserConfig {
    fn default() -> Self {
        Self {
            d_model: 128,
            n_layers: 4,
            n_heads: 4,
            d_ff: 512,
            music_layers: 2,
            dropout: 0.1,
            mixer: SequenceMixer::CrossAttention,
            fusion_projection: true,
            fusion_hidden: None,
            fusion_residual: false,
            positioning: true,
            swap_mode: true,
            footwork: true,
            footwork_hidden: 128,
            footwork_residual: false,
            root_integrated: false,
            prediction: Prediction::X0,
            skip_smoothing: vec![0.0],
            skip_smooth_root_rotation: true,
            heading_integrated: false,
            root_rotation_smoothing: 0.0,
        }
    }
}

/// Largest smoothing width of the learned skip, in frames: 33 s at 30 fps, far beyond any
/// window (150 frames), so only a typo or a wrong unit goes past it.
pub const MAX_SKIP_SMOOTHING: f64 = 1000.0;

impl DenoiserConfig {
    pub fn fusion_hidden(&self) -> usize {
        self.fusion_hidden.unwrap_or(2 * self.d_model)
    }

    /// What deserialising cannot check: `root_rotation_smoothing` and, with `prediction =
    /// "x0_skip"`, at least one smoothing width; each width a number of frames in
    /// `0..=MAX_SKIP_SMOOTHING`.
    pub fn check(&self) -> Result<(), String> {
        let width = |name: &str, s: f64| {
            if (0.0..=MAX_SKIP_SMOOTHING).contains(&s) {
                Ok(())
            } else {
                Err(format!(
                    "{name} {s}: a width must be 0 to {MAX_SKIP_SMOOTHING} frames"
                ))
            }
        };
        width("root_rotation_smoothing", self.root_rotation_smoothing)?;
        if self.prediction != Prediction::LearnedSkip {
            return Ok(());
        }
        if self.skip_smoothing.is_empty() {
            return Err(
                "skip_smoothing is empty: the learned skip needs at least one width \
                        (0 is the input itself)"
                    .into(),
            );
        }
        self.skip_smoothing
            .iter()
            .try_for_each(|&s| width("skip_smoothing", s))
    }
}

/// Loss weights (paper §5.1: λ_sim = λ_D = 0.636, λ_vel = 2.964, λ_FK = 0.646,
/// λ_con = 10.942; the first four are EDGE's).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LossWeights {
    pub simple: f64,
    pub velocity: f64,
    pub fk: f64,
    pub contact: f64,
    /// Distance-consistency loss (Eq. 16–17); 0 is Table 4's "w/o L_D".
    pub distance: f64,
    /// The released code's `dis_loss` (weight 100 there; not in the paper, so 0 by default):
    /// each dancer's frame-to-frame root x/y change in x̂0 against x0's, on the normalised
    /// channels. It is what keeps a predicted root from jumping between frames (issue 43).
    pub root_velocity: f64,
    /// Our option, 0 (off, the paper's uniform L_simple) by default: each window's L_simple
    /// weighted by `min(1 + SNR_t, cap)`. `1 + SNR` is the weight that turns the x0 error into
    /// the v error (Salimans & Ho 2022), so with [`Prediction::Velocity`] the low-noise steps,
    /// where the network must remove the last noise from its skip, are trained as a
    /// v-predictor's are; the cap (Hang et al. 2023, "Min-SNR") keeps them from drowning
    /// the rest.
    pub simple_snr_cap: f64,
    /// Our option, 0 (off) by default: [`dancegen_nn::loss::leg_crossing`] on x̂0's joints,
    /// averaged over the active dancers' frames. Every network that read its input crossed its
    /// shins in 5-24 % of frames where real dancers do in 0-2 % (docs/group-collapse.md §20).
    pub leg_crossing: f64,
}

impl Default for LossWeights {
    fn default() -> Self {
        Self {
            simple: 0.636,
            velocity: 2.964,
            fk: 0.646,
            contact: 10.942,
            distance: 0.636,
            root_velocity: 0.0,
            simple_snr_cap: 0.0,
            leg_crossing: 0.0,
        }
    }
}

/// Training-time randomisation.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TrainingConfig {
    /// Classifier-free music dropout (EDGE / TCDiff++: 0.25).
    pub cond_drop: f64,
    /// Share of windows trained without any clean root injection (issue #17: half), so one
    /// model makes free and controlled dances.
    pub control_drop: f64,
    /// Our option, 0 (the paper's training) by default: the share of windows whose first half,
    /// first frames, last frames or both ends are given clean in x_t, every channel of every
    /// dancer, as the window-by-window sampler gives a window its prefix and an edit its kept
    /// frames ([`crate::losses::draw_cued_frames`]). A network that reads its input never saw
    /// clean frames beside noisy ones otherwise, and did not continue them
    /// (docs/group-collapse.md §21).
    pub cued_frames: f64,
}

impl TrainingConfig {
    /// What deserialising cannot check: every share a probability in `0..=1`.
    pub fn check(&self) -> Result<(), String> {
        for (name, v) in [
            ("cond_drop", self.cond_drop),
            ("control_drop", self.control_drop),
            ("cued_frames", self.cued_frames),
        ] {
            if !(0.0..=1.0).contains(&v) {
                return Err(format!("{name} {v}: a share must be 0 to 1"));
            }
        }
        Ok(())
    }
}

impl Default for TrainingConfig {
    fn default() -> Self {
        Self {
            cond_drop: 0.25,
            control_drop: 0.5,
            cued_frames: 0.0,
        }
    }
}

/// How LGDS gives the previous window's tail to the next window.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PrefixMode {
    /// Released `lgds_ddim_sample`: the clean prefix after every step.
    Clean,
    /// EDGE's inpainting: the prefix noised to the step's level.
    Renoised,
}

/// Long-form sampler.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LongSampler {
    /// Paper §4.4, sequential windows (window 0 kept, unlike the released code).
    Lgds,
    /// All windows at once, EDGE's first-half overwrite and final stitching.
    Parallel,
}

/// Sampling defaults (a request may override steps, guidance and the sampler).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SamplingConfig {
    /// DDIM steps (released: 50; group.md §4: 20 on CPU; here 6, see [`SamplingConfig::default`]).
    pub steps: usize,
    /// DDIM eta (released: 1).
    pub eta: f64,
    /// Which timesteps the DDIM steps visit (released: EDGE's linear spacing).
    pub spacing: Spacing,
    /// The update at each step (released: DDIM). Absent in older bundles: DDIM.
    pub solver: Solver,
    /// Guidance weight (EDGE / TCDiff++: 2).
    pub guidance: f64,
    pub sampler: LongSampler,
    pub prefix: PrefixMode,
    /// When a dancer's foot counts as planted for the foot lock (post-processing, not part of
    /// TCDiff++; `dancegen_lodgepp::planted_feet`). Absent in older bundles: `either`, as they
    /// were tuned with.
    pub foot_lock_rule: PlantedRule,
    /// The foot lock's leg IK on planted feet; `false` keeps the root lock only (dancers with
    /// a requested path get no root lock, so nothing). Absent in older bundles: `true`.
    pub foot_ik: bool,
    /// The leg IK leaves alone a contact run whose foot strays more than this (metres) from
    /// the run's mean place (`dancegen_lodgepp::planted_feet::pin_planted_feet_within`).
    /// Absent in older bundles: no bound.
    pub foot_ik_max_travel_m: Option<f64>,
    /// [`SamplingConfig::foot_ik_max_travel_m`] for a dancer on a requested path (a
    /// formation): its root is dragged along the path while its legs do not walk it, so its
    /// planted feet travel further. Absent: the same bound as a free dancer's.
    pub foot_ik_max_travel_on_path_m: Option<f64>,
    /// For a dancer on a requested path: a contact run whose foot strays more than the travel
    /// bound is cut into plants joined by swings of this many frames
    /// (`dancegen_lodgepp::planted_feet::pin_planted_feet_stepping`), so its feet step along
    /// the path instead of sliding. Absent: such runs are left to slide.
    pub foot_ik_swing_frames_on_path: Option<usize>,
    /// Height (metres) of those swings' arc at its middle. Absent: 0.06 m.
    pub foot_ik_swing_lift_m: Option<f64>,
    /// Time constant (frames) of a leash on the root lock: a removed glide is given back over
    /// about this long, so a dancer keeps the place the network gives it in the group
    /// (`dancegen_lodgepp::planted_feet::lock_planted_feet_leashed`). Absent: no leash.
    pub foot_lock_leash_frames: Option<f64>,
}

impl SamplingConfig {
    /// The leg IK's travel bound for a dancer on a requested path (`on_path`) or free
    /// (metres; `f64::INFINITY`: none).
    pub fn foot_ik_travel_bound(&self, on_path: bool) -> f64 {
        let free = self.foot_ik_max_travel_m;
        let bound = if on_path {
            self.foot_ik_max_travel_on_path_m.or(free)
        } else {
            free
        };
        bound.unwrap_or(f64::INFINITY)
    }
}

impl Default for SamplingConfig {
    fn default() -> Self {
        Self {
            // Measured on the held-out group set (7 clips, 3 seeds, formation control;
            // models/tcdiffpp-small/MODEL_CARD.md "Steps"): 6 steps matched 20 on every
            // metric of docs/group-eval.md (collisions 0.32 % vs 0.73 %, FID_k 761 vs 766,
            // boundary jerk 1.00 vs 1.15) at 3.3 times fewer denoiser calls, which the 5 × 60 s
            // target of issue #17 needs on 2 cores. That network ignored its input; one that
            // reads it dances more with more steps (docs/group-collapse.md §23), and the
            // shipped bundle sets its own count.
            steps: 6,
            eta: 1.0,
            spacing: Spacing::Linear,
            solver: Solver::Ddim,
            guidance: 2.0,
            // docs/group-eval.md: on the held-out set LGDS's joins had a boundary jerk of 7.1
            // and root steps up to 0.7 m (free dances), the parallel sampler 1.2 and 0.17 m.
            sampler: LongSampler::Parallel,
            prefix: PrefixMode::Clean,
            foot_lock_rule: PlantedRule::Either,
            foot_ik: true,
            foot_ik_max_travel_m: None,
            foot_ik_max_travel_on_path_m: None,
            foot_lock_leash_frames: None,
            foot_ik_swing_frames_on_path: None,
            foot_ik_swing_lift_m: None,
        }
    }
}

impl SamplingConfig {
    /// What deserialising cannot check: the foot lock's travel bound and leash are positive
    /// lengths (metres, frames).
    pub fn check(&self) -> Result<(), String> {
        for (name, v) in [
            ("foot_ik_max_travel_m", self.foot_ik_max_travel_m),
            (
                "foot_ik_max_travel_on_path_m",
                self.foot_ik_max_travel_on_path_m,
            ),
            ("foot_lock_leash_frames", self.foot_lock_leash_frames),
            ("foot_ik_swing_lift_m", self.foot_ik_swing_lift_m),
        ] {
            if let Some(v) = v
                && !(v.is_finite() && v > 0.0)
            {
                return Err(format!("{name} {v}: must be a positive number"));
            }
        }
        if let Some(n) = self.foot_ik_swing_frames_on_path
            && !(1..=MAX_SWING_FRAMES).contains(&n)
        {
            return Err(format!(
                "foot_ik_swing_frames_on_path {n}: must be 1 to {MAX_SWING_FRAMES} frames"
            ));
        }
        if let Some(lift) = self.foot_ik_swing_lift_m
            && lift > MAX_SWING_LIFT_M
        {
            return Err(format!(
                "foot_ik_swing_lift_m {lift}: at most {MAX_SWING_LIFT_M} m"
            ));
        }
        Ok(())
    }

    /// The swing of a dancer on a requested path's steps, `(frames, lift metres)`; `None`:
    /// its travelling contact runs are left alone.
    pub fn swing_on_path(&self) -> Option<(usize, f64)> {
        self.foot_ik_swing_frames_on_path.map(|frames| {
            (
                frames,
                self.foot_ik_swing_lift_m.unwrap_or(DEFAULT_SWING_LIFT_M),
            )
        })
    }
}

/// The longest swing a bundle may ask for: 2 s at 30 fps, longer than any step (real salsa
/// steps at 1.9 per second); it also keeps the plant arithmetic far from overflow.
pub const MAX_SWING_FRAMES: usize = 60;

/// The highest swing a bundle may ask for: 0.5 m, a knee-high step; a larger lift sends the
/// IK target out of the leg's reach.
pub const MAX_SWING_LIFT_M: f64 = 0.5;

/// A swing's lift when the bundle names none: a foot lifted 6 cm at the middle of its swing
/// (ankle about 13 cm above the floor) is off the floor by the 8 cm ankle and 5 cm toe contact
/// heights of `dancegen_metrics::physical`, as a stepping foot is.
pub const DEFAULT_SWING_LIFT_M: f64 = 0.06;

/// `[model]`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct GroupModelConfig {
    /// Frames per window (released: 150 at 30 fps).
    pub window: Option<usize>,
    pub denoiser: DenoiserConfig,
    pub loss: LossWeights,
    pub training: TrainingConfig,
    pub sampling: SamplingConfig,
}

/// Released window length: 5 s at 30 fps (`TCDiff:data/data_preprocess/slice.py`).
pub const WINDOW_FRAMES: usize = 150;

impl GroupModelConfig {
    pub fn window(&self) -> usize {
        self.window.unwrap_or(WINDOW_FRAMES)
    }

    /// Parses a `[model]` table (or a whole `model.toml`).
    pub fn from_toml(text: &str) -> Result<Self, toml::de::Error> {
        toml::from_str(text)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn smoothing_widths_are_checked() {
        let skip = |widths: Vec<f64>| DenoiserConfig {
            prediction: Prediction::LearnedSkip,
            skip_smoothing: widths,
            ..DenoiserConfig::default()
        };
        assert!(skip(vec![0.0, 1.0, 4.0]).check().is_ok());
        for bad in [vec![], vec![-1.0], vec![f64::NAN], vec![1e30]] {
            let e = skip(bad.clone()).check().unwrap_err();
            assert!(e.contains("skip_smoothing"), "{bad:?}: {e}");
        }
        // Other predictions never read the widths.
        let x0 = DenoiserConfig {
            skip_smoothing: vec![],
            ..DenoiserConfig::default()
        };
        assert!(x0.check().is_ok());
        for bad in [-1.0, f64::NAN, 1e30] {
            let heading = DenoiserConfig {
                heading_integrated: true,
                root_rotation_smoothing: bad,
                ..DenoiserConfig::default()
            };
            let e = heading.check().unwrap_err();
            assert!(e.contains("root_rotation_smoothing"), "{bad}: {e}");
        }
    }

    #[test]
    fn foot_lock_lengths_are_checked() {
        assert!(SamplingConfig::default().check().is_ok());
        for (travel, leash) in [
            (Some(0.0), None),
            (None, Some(-3.0)),
            (Some(f64::NAN), None),
        ] {
            let s = SamplingConfig {
                foot_ik_max_travel_m: travel,
                foot_lock_leash_frames: leash,
                ..SamplingConfig::default()
            };
            let e = s.check().unwrap_err();
            let name = if travel.is_some() {
                "foot_ik_max_travel_m"
            } else {
                "foot_lock_leash_frames"
            };
            assert!(e.contains(name), "{e}");
        }
        let on_path = SamplingConfig {
            foot_ik_max_travel_on_path_m: Some(-1.0),
            ..SamplingConfig::default()
        };
        let e = on_path.check().unwrap_err();
        assert!(e.contains("foot_ik_max_travel_on_path_m"), "{e}");
        for frames in [0, MAX_SWING_FRAMES + 1, usize::MAX] {
            let swing = SamplingConfig {
                foot_ik_swing_frames_on_path: Some(frames),
                ..SamplingConfig::default()
            };
            let e = swing.check().unwrap_err();
            assert!(e.contains("foot_ik_swing_frames_on_path"), "{frames}: {e}");
        }
        for bad in [-0.1, f64::NAN, 0.51, 1e30] {
            let lift = SamplingConfig {
                foot_ik_swing_lift_m: Some(bad),
                ..SamplingConfig::default()
            };
            let e = lift.check().unwrap_err();
            assert!(e.contains("foot_ik_swing_lift_m"), "{bad}: {e}");
        }
        let ok = SamplingConfig {
            foot_ik_swing_frames_on_path: Some(MAX_SWING_FRAMES),
            foot_ik_swing_lift_m: Some(MAX_SWING_LIFT_M),
            ..SamplingConfig::default()
        };
        assert!(ok.check().is_ok());
        assert_eq!(SamplingConfig::default().swing_on_path(), None);
        let eight = SamplingConfig {
            foot_ik_swing_frames_on_path: Some(8),
            ..SamplingConfig::default()
        };
        assert_eq!(eight.swing_on_path(), Some((8, DEFAULT_SWING_LIFT_M)));
    }

    #[test]
    fn the_solver_is_read_by_name_and_defaults_to_ddim() {
        let read = |t: &str| GroupModelConfig::from_toml(&format!("[sampling]\n{t}"));
        assert_eq!(read("").unwrap().sampling.solver, Solver::Ddim);
        for (name, solver) in [
            ("ddim", Solver::Ddim),
            ("dpmpp_2m", Solver::DpmPp2m),
            ("dpmpp_2m_sde", Solver::DpmPp2mSde),
        ] {
            let c = read(&format!("solver = \"{name}\"")).unwrap();
            assert_eq!(c.sampling.solver, solver);
        }
        let e = read("solver = \"euler\"").unwrap_err().to_string();
        assert!(e.contains("euler") && e.contains("dpmpp_2m"), "{e}");
    }

    #[test]
    fn a_dancer_on_a_path_gets_its_own_travel_bound_or_the_free_one() {
        let mut s = SamplingConfig::default();
        assert_eq!(s.foot_ik_travel_bound(false), f64::INFINITY);
        assert_eq!(s.foot_ik_travel_bound(true), f64::INFINITY);
        s.foot_ik_max_travel_m = Some(0.1);
        assert_eq!(s.foot_ik_travel_bound(true), 0.1);
        s.foot_ik_max_travel_on_path_m = Some(0.2);
        assert_eq!(s.foot_ik_travel_bound(false), 0.1);
        assert_eq!(s.foot_ik_travel_bound(true), 0.2);
    }

    #[test]
    fn training_shares_are_checked() {
        assert!(TrainingConfig::default().check().is_ok());
        for bad in [-0.1, 1.5, f64::NAN] {
            let t = TrainingConfig {
                cued_frames: bad,
                ..TrainingConfig::default()
            };
            let e = t.check().unwrap_err();
            assert!(e.contains("cued_frames"), "{bad}: {e}");
        }
    }
}
