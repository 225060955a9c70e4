//! What a group request may ask for beyond the common options, and the dancer counts and
//! music the group model serves (shared by the plain group dance and its edit).

use std::path::Path;

use dancegen_tcdiffpp::config::LongSampler;
use dancegen_tcdiffpp::layout::{N_MAX, N_MIN};

use crate::error::GenerateError;
use crate::formation_file::FormationFile;

/// Dancer counts the group model serves (front ends check them before a job starts).
pub const MIN_DANCERS: usize = N_MIN;
pub const MAX_DANCERS: usize = N_MAX;

/// Shortest music a group dance is made for (one half window of the model, 2.5 s).
pub const MIN_GROUP_SECONDS: f64 = 2.5;

/// Group options beyond [`crate::system::CommonOptions`].
#[derive(Clone, Debug)]
pub struct GroupOptions {
    pub dancers: usize,
    pub formation: Option<FormationFile>,
    /// Every dancer dances the leftmost dancer's moves.
    pub unison: bool,
    /// `None`: the model's default.
    pub sampler: Option<LongSampler>,
    /// Move dancers out of each other's bodies.
    pub separation: bool,
    /// Planted-feet pass (leg IK, and the root lock for free dancers).
    pub foot_lock: bool,
    /// Time-warp each dancer so that its kinematic beats land on the song's
    /// ([`crate::beat_align`], as the solo's; post-processing, not part of TCDiff++).
    pub beat_align: bool,
}

impl GroupOptions {
    pub fn new(dancers: usize) -> Self {
        GroupOptions {
            dancers,
            formation: None,
            unison: false,
            sampler: None,
            separation: true,
            foot_lock: true,
            beat_align: true,
        }
    }

    /// Reads `path` as a formation file (checked later against the song).
    pub fn with_formation_file(mut self, path: &Path) -> Result<Self, GenerateError> {
        self.formation = Some(FormationFile::read(path, "the formation")?);
        Ok(self)
    }
}
