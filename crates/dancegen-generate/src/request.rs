//! What a front end asks for: one [`Request`] per dance, whatever the system.

use std::path::PathBuf;
use std::sync::Arc;

pub use dancegen_character::Character;
pub use dancegen_formats::rig::Rig;

use crate::systems::duet::DuetOptions;
use crate::systems::group::GroupOptions;
use crate::systems::holistic::HolisticOptions;
use crate::systems::solo::SoloOptions;

/// Where the song comes from.
#[derive(Clone, Debug)]
pub enum Song {
    /// The bundled demo song (45 s of *Metal Madness*, compiled into the library).
    Demo,
    File(PathBuf),
    /// Bytes in memory (an upload); `name` is shown in messages and its extension is the
    /// format hint.
    Bytes {
        name: String,
        bytes: Arc<[u8]>,
    },
}

impl Song {
    /// The file, or the demo song when there is none (what every command does without a
    /// song argument).
    pub fn file_or_demo(path: Option<&std::path::Path>) -> Self {
        match path {
            Some(p) => Song::File(p.to_path_buf()),
            None => Song::Demo,
        }
    }
}

/// The system that dances, with its own options. Adding a system adds a variant here and
/// its module in [`crate::systems`]; the existing systems are not touched.
#[derive(Clone, Debug)]
pub enum SystemRequest {
    /// One dancer (Lodge++).
    Solo(SoloOptions),
    /// The partner of a given leader (ReactDance).
    Duet(DuetOptions),
    /// 2–5 dancers together (TCDiff++).
    Group(GroupOptions),
    /// One dancer with fingers and face (SoulNet).
    Holistic(HolisticOptions),
}

impl SystemRequest {
    /// Whether the system's dances have a face (a holistic dance), so a `.csv` output can be
    /// checked before any work is done.
    pub fn makes_face(&self) -> bool {
        match self {
            SystemRequest::Solo(_) | SystemRequest::Duet(_) | SystemRequest::Group(_) => false,
            SystemRequest::Holistic(_) => true,
        }
    }
}

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

/// Which dancers an output file holds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum DancerSelection {
    /// Every dancer where the format holds several (`.glb`, `.json`, previews), the generated
    /// dancer in single-dancer formats (`.bvh`, `.npz`, `.npy`).
    #[default]
    Auto,
    /// Only the generated dancers (a duet's follower without its given leader).
    Generated,
    /// Only the given dancers (a duet's leader, as the dance used it: the danced span at
    /// 30 fps), so a front end can hand out the leader's joints next to the follower's.
    Given,
}

/// One file to write; the format comes from the extension ([`crate::output::OutputFormat`]).
#[derive(Clone, Debug)]
pub struct OutputRequest {
    pub path: PathBuf,
    pub dancers: DancerSelection,
    /// Bone names of `.bvh`, `.fbx` and `.glb` (other formats keep SMPL's).
    pub rig: Rig,
    /// A `.glb` output becomes this character (the user's humanoid glTF/VRM) dancing the dance,
    /// retargeted onto its skeleton; other formats ignore it.
    pub character: Option<Arc<Character>>,
}

impl OutputRequest {
    pub fn new(path: impl Into<PathBuf>) -> Self {
        OutputRequest {
            path: path.into(),
            dancers: DancerSelection::Auto,
            rig: Rig::Smpl,
            character: None,
        }
    }
}

/// One dance to generate.
#[derive(Clone, Debug)]
pub struct Request {
    pub song: Song,
    pub system: SystemRequest,
    pub common: CommonOptions,
    /// A model directory; `None` finds the system's default model on the search path
    /// ([`crate::models::ModelLocator`]).
    pub model: Option<PathBuf>,
    /// Files to write (none: the dance is only returned).
    pub outputs: Vec<OutputRequest>,
}
