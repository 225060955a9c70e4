//! What a front end asks for: one [`Request`] per dance, whatever the system.

use std::path::PathBuf;
use std::sync::Arc;

pub use dancegen_character::Character;
pub use dancegen_formats::rig::Rig;

// Defined where the systems read them; a front end finds them here, with the rest of a request.
pub use crate::song::Song;
pub use crate::system::CommonOptions;

use crate::systems::duet::DuetOptions;
use crate::systems::group::GroupOptions;
use crate::systems::holistic::HolisticOptions;
use crate::systems::solo::SoloOptions;

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

/// One file to write; the format comes from the extension (`output::OutputFormat`).
#[derive(Clone, Debug)]
pub struct OutputRequest {
    pub path: PathBuf,
    pub dancers: DancerSelection,
    /// Bone names of `.bvh`, `.fbx` and `.glb` (other formats keep SMPL's).
    pub rig: Rig,
    /// A `.glb` output becomes this character (the user's humanoid glTF/VRM) dancing the dance,
    /// retargeted onto its skeleton; other formats ignore it.
    pub character: Option<Arc<Character>>,
    /// The picture size of an `.mp4` (other formats ignore it).
    pub video: VideoSize,
}

/// The picture size of a video preview: 640 × 480, or 1280 × 720 for a sharper video that
/// takes about three times as long to render.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum VideoSize {
    #[default]
    Sd,
    Hd,
}

impl VideoSize {
    /// The choices, as users write them.
    pub const NAMES: [&'static str; 2] = ["640x480", "1280x720"];

    /// Width and height in pixels.
    pub fn pixels(self) -> (u32, u32) {
        match self {
            VideoSize::Sd => (640, 480),
            VideoSize::Hd => (1280, 720),
        }
    }

    /// `640x480` or `1280x720`; anything else is an error listing them.
    pub fn parse(text: &str) -> Result<Self, String> {
        match text.trim() {
            "640x480" => Ok(VideoSize::Sd),
            "1280x720" => Ok(VideoSize::Hd),
            other => Err(format!(
                "video size '{other}': choose {}",
                Self::NAMES.join(" or ")
            )),
        }
    }
}

impl OutputRequest {
    pub fn new(path: impl Into<PathBuf>) -> Self {
        OutputRequest {
            path: path.into(),
            dancers: DancerSelection::Auto,
            rig: Rig::Smpl,
            character: None,
            video: VideoSize::Sd,
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
