//! The build's options: how to pair, what to read and hold out, and the progress callbacks.

use std::path::PathBuf;

use crate::rates::SourceRates;
use crate::warp::WarpParams;

/// How motion and music are paired.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pairing {
    /// Beat-warp pseudo-pairing of `--motion` files with `--music` songs.
    Pseudo,
    /// Beat-warp pseudo-pairing of couples (`--motion` files of two partners each) with songs;
    /// see [`crate::duet`].
    Duet,
    /// DD100 (Duolando) duet layout under `root`; see [`crate::dd100`].
    Dd100,
    /// AIST++ layout under `root` (`motions/*.pkl`, `wav/<music id>.wav`, `splits/`).
    Aistpp,
    /// FineDance layout under `root` (`motion/*.npy`, `music_wav/*.wav`, `label_json/*.json`).
    FineDance,
    /// 2–5 dancers composed from `--motion` takes into formations and beat-warped onto
    /// `--music` songs; see [`crate::group`].
    Group,
}

/// Options of [`crate::build()`].
#[derive(Clone, Debug)]
pub struct BuildOptions {
    /// Output directory (created if missing).
    pub out: PathBuf,
    pub pairing: Pairing,
    /// Motion files (pseudo pairing; any format `load_motion_file` reads; directories are
    /// searched for motion files, non-recursively).
    pub motions: Vec<PathBuf>,
    /// Songs (pseudo pairing).
    pub music: Vec<PathBuf>,
    /// Data set root (aistpp / finedance).
    pub root: Option<PathBuf>,
    /// Genre of every input (default: from the file names).
    pub genre: Option<String>,
    /// Motion or song stems (file names without extension) kept out of training.
    pub hold_out: Vec<String>,
    /// Breaks exact ties between songs.
    pub seed: u64,
    pub warp: WarpParams,
    /// Also trains on each training motion's left–right mirror image (clip `<name>_mirror`,
    /// [`dancegen_motion::repr::motion::SmplMotion::mirror`], as EDGE and Lodge augment); held-out motions are never mirrored.
    /// Pseudo and duet pairing (a couple is mirrored as a whole, both partners in one world
    /// reflection, so it stays a couple).
    pub mirror: bool,
    /// Also give every clip **synthetic** fingers and an ARKit face made from its body and
    /// music ([`crate::holistic_synth::attach`]), for the holistic (SoulNet) system. Pseudo and AIST++
    /// pairing (bodies without real hands).
    pub holistic: bool,
    /// Training takes are paired with this many songs, best first (1: only the best; the
    /// further pairings are clips `<name>__<song>`); held-out takes always with one. Pseudo
    /// pairing only.
    pub songs_per_motion: usize,
    /// Genres relabelled after pairing, `(from, to)`: a genre with too few takes to learn on
    /// its own is folded into a related one (e.g. the single CMU "dance, whirl" take into
    /// `modern`). Applied to every pairing's manifest.
    pub merge_genres: Vec<(String, String)>,
    /// Group pairing only ([`crate::group`]).
    pub group: GroupOptions,
    /// The rate each `motions` input was captured at, where its header is wrong or missing
    /// ([`SourceRates`]); the others are read at their header's rate.
    pub source_fps: SourceRates,
}

impl BuildOptions {
    /// Pseudo pairing of `motions` with `music` into `out`, defaults otherwise.
    pub fn pseudo(out: impl Into<PathBuf>, motions: Vec<PathBuf>, music: Vec<PathBuf>) -> Self {
        BuildOptions {
            out: out.into(),
            pairing: Pairing::Pseudo,
            motions,
            music,
            root: None,
            genre: None,
            hold_out: Vec::new(),
            seed: 0,
            warp: WarpParams::default(),
            mirror: false,
            holistic: false,
            songs_per_motion: 1,
            merge_genres: Vec::new(),
            group: GroupOptions::default(),
            source_fps: SourceRates::default(),
        }
    }
}

/// Progress callbacks (the CLI draws a bar); every method has a no-op default.
pub trait Progress: Sync {
    /// A stage with `total` steps begins.
    fn stage(&self, _name: &str, _total: usize) {}
    /// One step of the current stage finished.
    fn step(&self, _item: &str) {}
}

impl Progress for () {}

/// Options of the group pairing.
#[derive(Clone, Debug, PartialEq)]
pub struct GroupOptions {
    /// Training samples to compose.
    pub samples: usize,
    /// Held-out samples (from held-out takes, songs and shapes); 0 for none.
    pub held_out_samples: usize,
    /// Length of a sample in seconds.
    pub clip_seconds: f64,
    /// Formation shapes only the held-out samples use (group.md §4 holds out circle and
    /// diamond).
    pub hold_out_shapes: Vec<String>,
}

impl Default for GroupOptions {
    fn default() -> Self {
        GroupOptions {
            samples: 200,
            held_out_samples: 24,
            clip_seconds: 10.0,
            hold_out_shapes: Vec::new(),
        }
    }
}
