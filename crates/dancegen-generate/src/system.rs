//! The one trait a dance system implements to plug into the generator.

use std::path::Path;

use dancegen_motion::repr::SmplMotion;
use dancegen_nn::burn::tensor::Device;
use dancegen_nn::progress::StepHook;

use crate::error::GenerateError;
use crate::song::{AnalysedSong, Span};

/// Options every system understands; `None` means the model's default.
#[derive(Clone, Debug, Default)]
pub struct CommonOptions {
    pub seed: u64,
    /// Denoising steps.
    pub steps: Option<usize>,
    /// Classifier-free guidance weight `w` (1 = conditional only).
    pub guidance: Option<f64>,
    /// Dance genre (the model's list).
    pub genre: Option<String>,
    /// Start of the music to dance to (seconds).
    pub start: Option<f64>,
    /// End of the music to dance to (seconds).
    pub end: Option<f64>,
    /// What to keep of existing motion (an edit); empty for a plain generation.
    pub edit: crate::edit::Edit,
}

impl CommonOptions {
    /// `--guidance` non-negative and finite, `--steps` at least 1; `default` completes the
    /// guidance hint (e.g. "2 = Lodge's default").
    pub fn check_sampling(&self, default: &str) -> Result<(), crate::GenerateError> {
        if let Some(w) = self.guidance
            && !(w.is_finite() && w >= 0.0)
        {
            return Err(crate::GenerateError::Invalid(format!(
                "--guidance {w}: use a non-negative number (1 = no guidance, {default})"
            )));
        }
        if self.steps == Some(0) {
            return Err(crate::GenerateError::Invalid(
                "--steps must be at least 1".into(),
            ));
        }
        Ok(())
    }
}

/// What a dancer is in the dance.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Role {
    /// The one generated dancer of a solo.
    Solo,
    /// A duet's given leader (the input motion, not generated).
    Leader,
    /// A duet's generated partner.
    Follower,
    /// One generated dancer of a group.
    Member,
}

impl Role {
    /// Whether the system made this dancer (rather than being given it).
    pub fn generated(self) -> bool {
        !matches!(self, Role::Leader)
    }
}

/// One dancer: SMPL 24 motion (Y-up, metres, 30 fps) standing on the floor.
#[derive(Clone, Debug)]
pub struct Dancer {
    pub role: Role,
    pub motion: SmplMotion,
}

/// What a system returns: its dancers and what it did, in words for the front ends.
#[derive(Clone, Debug)]
pub struct Dance {
    pub dancers: Vec<Dancer>,
    /// The music danced to.
    pub span: Span,
    /// What was made, e.g. "300 frames (10.0 s at 30 fps), genre salsa, seed 3, ...".
    pub summary: String,
    /// Where the generation time went, e.g. "sampling 0.20 s, decoding 0.05 s; " (may be
    /// empty; it is printed before the total time).
    pub timing_breakdown: String,
    /// Post-processing remarks printed after the timings.
    pub notes: Vec<String>,
    /// Group dances: where the dancers went (written to `.json`).
    pub group: Option<GroupReport>,
    /// Holistic dances: the one dancer's fingers and face (its body is `dancers[0]`).
    pub holistic: Option<HolisticParts>,
}

/// The parts of a holistic dance beyond the SMPL 24 body: the same dancer as SMPL-H 52 (body
/// joints 0–21 equal to the SMPL body's, then 15 left-hand and 15 right-hand finger joints) and
/// the face as the 52 ARKit blendshape weights per frame.
#[derive(Clone, Debug)]
pub struct HolisticParts {
    /// `(T, 52, 3)` local axis-angle rotations in SMPL-H order (root = world orientation).
    pub poses: Vec<f32>,
    /// `(T, 3)` pelvis world position, metres, Y-up (the body's `trans`).
    pub trans: Vec<f32>,
    /// The skeleton the rotations pose (`Skeleton::smplh52_approx` unless the model says
    /// otherwise).
    pub skeleton: dancegen_motion::skeleton::Skeleton,
    /// `(T, 52)` ARKit weights in `[0, 1]`, Live Link order, at the motion's frame rate.
    pub face: dancegen_motion::face::FaceWeights,
    /// `(T, 103)` FLAME expression + jaw values of the face, when the user gave an ARKit → FLAME
    /// mapping (written to `.json` as `"flame"`).
    pub flame: Option<Vec<f32>>,
}

/// A group dance's stage record (stage frame of `dancegen_refine::formation`: `[x, z]`
/// metres, x to the audience's right, +z towards the audience).
#[derive(Clone, Debug, serde::Serialize)]
pub struct GroupReport {
    /// Dancer indices left to right as the audience sees them at the first frame.
    pub start_order: Vec<usize>,
    /// The same at the last frame.
    pub end_order: Vec<usize>,
    /// `[dancer][frame]` root (pelvis) `[x, z]`.
    pub trajectories: Vec<Vec<[f64; 2]>>,
    /// The requested paths (`[dancer][frame]`, `null` where free), when a formation was given.
    pub requested: Option<Vec<Vec<Option<[f64; 2]>>>>,
    /// Mean and final distance (metres) between the root and the requested path over the
    /// constrained frames, when a formation was given.
    pub trajectory_error_mean_m: Option<f64>,
    pub trajectory_error_final_m: Option<f64>,
}

/// Everything a system gets for one job.
pub struct DanceInput<'a, O> {
    pub song: &'a AnalysedSong,
    pub common: &'a CommonOptions,
    pub options: &'a O,
    pub device: &'a Device,
    /// Told of every sampler step; answers `Break` when the job is cancelled.
    pub hook: &'a dyn StepHook,
}

/// A dance system (Lodge++, ReactDance, ...): how its model loads and how it dances.
///
/// The generator does everything around it once for every system: finding and caching the
/// model, analysing the song, progress and cancellation, writing the outputs.
pub trait DanceSystem: 'static {
    /// The name users choose it by (`--system solo`).
    const NAME: &'static str;
    /// The `kind` in its models' `model.toml`.
    const MODEL_KIND: &'static str;
    /// The shipped model found on the search path when no `--model` is given.
    const DEFAULT_MODEL: &'static str;
    /// The parts the system reports progress under (its sampler's [`StepHook`] part names)
    /// with their rough share of its running time.
    const PARTS: &'static [(&'static str, f64)];
    /// The edit operations its sampler applies ([`crate::edit::Edit::operations`] names); a
    /// request with another is refused before any work, naming it.
    const EDITS: &'static [&'static str] = &[];
    /// The least music (seconds from start to end) it dances to; a shorter span is refused.
    const MIN_SECONDS: f64;
    /// Seconds its generation takes per second of danced music on the 2-core reference
    /// machine: the first job's time plan ([`crate::time_plan`]); later jobs use this
    /// machine's measured speed.
    const SECONDS_PER_DANCED_SECOND: f64;

    type Model: Send + Sync + 'static;
    type Options;

    fn load(dir: &Path, device: &Device) -> Result<Self::Model, GenerateError>;

    /// Checks the request against the model before the song is analysed (a wrong genre
    /// fails at once).
    fn check(
        model: &Self::Model,
        common: &CommonOptions,
        options: &Self::Options,
    ) -> Result<(), GenerateError>;

    fn dance(
        model: &Self::Model,
        input: DanceInput<'_, Self::Options>,
    ) -> Result<Dance, GenerateError>;
}
