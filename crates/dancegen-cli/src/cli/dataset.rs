//! `dancegen dataset`: building training sets from motion and music.

use std::path::PathBuf;

use clap::{Args, Subcommand, ValueEnum};

#[derive(Subcommand, Debug)]
pub enum DatasetCommand {
    /// Pair motion with music features into OUT/{motion,music}/ + OUT/manifest.json.
    Build(DatasetBuildArgs),
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum PairingArg {
    /// Time-warp each motion onto a song's beats (a pseudo-pairing, not ground truth).
    Pseudo,
    /// Couples (`<dancer>_<take>` file pairs, or two-dancer group files) time-warped by one
    /// warp per couple; one clip per role assignment, the partner under leader/.
    Duet,
    /// DD100 (Duolando) duets under --root: motion/rotmat/{train,test}/<take>_00.npy (follower)
    /// and _01.npy (leader), music/<any>/{train,test}/<take>.wav; test takes held out.
    Dd100,
    /// AIST++ layout under --root: motions/*.pkl, wav/<music id>.wav, splits/.
    Aistpp,
    /// FineDance layout under --root: motion/*.npy, music_wav/*.wav, label_json/*.json.
    Finedance,
    /// 2-5 dancers composed from the --motion takes into formations (CMU couples keep their
    /// real placement), beat-warped onto the --music songs; OUT/group/<clip>/dancer_<k>.npz.
    Group,
}

/// `FROM=TO` of `--merge-genre`.
fn parse_merge(s: &str) -> Result<(String, String), String> {
    match s.split_once('=') {
        Some((from, to)) if !from.trim().is_empty() && !to.trim().is_empty() => {
            Ok((from.trim().to_string(), to.trim().to_string()))
        }
        _ => Err(format!("{s:?}: expected FROM=TO, e.g. whirl=modern")),
    }
}

#[derive(Args, Debug)]
pub struct DatasetBuildArgs {
    /// Motion files or directories (.bvh, .pkl, .npz, .npy); BVH is retargeted to SMPL 24.
    #[arg(long, num_args = 1.., value_name = "PATH")]
    pub motion: Vec<PathBuf>,
    /// Songs to pair the motions with (pseudo pairing).
    #[arg(long, num_args = 1.., value_name = "SONG")]
    pub music: Vec<PathBuf>,
    /// Genre of every input (default: from the file names: AIST++ gXX codes; CMU subjects 05
    /// modern, 55 whirl, 60/61 salsa, 85 break).
    #[arg(long, value_name = "NAME")]
    pub genre: Option<String>,
    /// Also train on each training motion's left-right mirror image (clips `<name>_mirror`;
    /// held-out motions are not mirrored). Pseudo and duet pairing (a couple is mirrored as a
    /// whole).
    #[arg(long)]
    pub mirror: bool,
    /// Also give every clip SYNTHETIC fingers and an ARKit face made from its real body and its
    /// music (`holistic/<clip>.npz`), for the holistic system. Pseudo and aistpp pairing.
    #[arg(long)]
    pub holistic: bool,
    /// Pair each training motion with its N best songs (the further pairings are clips
    /// `<name>__<song>`; held-out motions get one). Pseudo pairing only.
    #[arg(long, value_name = "N", default_value_t = 1)]
    pub songs_per_motion: usize,
    /// Relabel a genre after pairing, FROM=TO (repeatable), e.g. `whirl=modern` to fold a genre
    /// with too few takes to learn into a related one.
    #[arg(long = "merge-genre", value_name = "FROM=TO", value_parser = parse_merge)]
    pub merge_genre: Vec<(String, String)>,
    /// Motion or song file names (without extension) to keep out of training.
    #[arg(long = "hold-out", num_args = 1.., value_name = "STEM")]
    pub hold_out: Vec<String>,
    /// The rate a --motion input was captured at, whatever its header says (repeatable):
    /// INPUT=FPS, INPUT a --motion directory or file or a file name without extension (the
    /// most specific entry wins), or FPS alone for every input; e.g.
    /// `--source-fps ../shared/data/cmu-salsa=60`. Inputs without one are read at their
    /// header's rate. Each take's rate, kinematic tempo and floor are printed and recorded in
    /// the manifest (`takes`), and a take outside the tempo of real dance is warned about.
    #[arg(long = "source-fps", value_name = "INPUT=FPS",
          value_parser = dancegen_dataset::takes::SourceRates::parse_entry)]
    pub source_fps: Vec<(Option<String>, f64)>,
    /// How motion and music are paired.
    #[arg(long, value_enum, default_value_t = PairingArg::Pseudo)]
    pub pairing: PairingArg,
    /// Data set root for --pairing aistpp / finedance.
    #[arg(long, value_name = "DIR")]
    pub root: Option<PathBuf>,
    /// Breaks exact ties between songs; seeds the group composition.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// --pairing group: training samples to compose.
    #[arg(long, value_name = "N", default_value_t = 200)]
    pub samples: usize,
    /// --pairing group: held-out samples (from held-out takes, songs and shapes).
    #[arg(long, value_name = "N", default_value_t = 24)]
    pub held_out_samples: usize,
    /// --pairing group: length of a sample in seconds.
    #[arg(long, value_name = "SECONDS", default_value_t = 10.0)]
    pub clip_seconds: f64,
    /// --pairing group: formation shapes only held-out samples use (line, column, v,
    /// inverted_v, triangle, diamond, circle, arc, two_rows, cluster).
    #[arg(long = "hold-out-shape", num_args = 1.., value_name = "SHAPE")]
    pub hold_out_shape: Vec<String>,
    /// Output directory.
    #[arg(short, long, value_name = "OUT_DIR")]
    pub output: PathBuf,
}
