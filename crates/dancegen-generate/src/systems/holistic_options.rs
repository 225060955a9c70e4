//! What a holistic request may ask for beyond the common options (shared by the plain
//! holistic dance and its edit).

use std::path::PathBuf;

/// Shortest music the model dances to.
pub const MIN_SONG_SECONDS: f64 = 2.0;

/// Holistic options beyond [`crate::system::CommonOptions`]; the defaults are the shipped system.
#[derive(Clone, Debug)]
pub struct HolisticOptions {
    /// Planted feet stay put: the solo system's root lock, and leg IK where the model's
    /// `[sampling] foot_ik` asks for it, on the body (`dancegen_lodgepp::planted_feet`;
    /// post-processing, not part of SoulNet). Without it the
    /// held-out dances skate in 82 % of frames against the real 18 % (docs/holistic-eval.md).
    pub foot_lock: bool,
    /// A user's `(52, 103)` ARKit → FLAME mapping (`.npy`): the dance's face is then also given
    /// as FLAME's 100 expression + 3 jaw values (`.json` key `"flame"`). FLAME and SoulNet's
    /// mapping are not redistributable, so none is shipped.
    pub flame_mapping: Option<PathBuf>,
}

impl Default for HolisticOptions {
    fn default() -> Self {
        HolisticOptions {
            foot_lock: true,
            flame_mapping: None,
        }
    }
}
