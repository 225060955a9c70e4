//! `dancegen eval`: the motions to measure, the metrics and the paper's protocol.

use std::path::PathBuf;

use clap::{Args, ValueEnum};

use dancegen_generate::flags::values::parse_source_fps;

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum ProtocolArg {
    /// Bailando / AIST++: 60 fps, first 1200 frames, zero-start root, frame time 1/60.
    AistppBailando,
    /// LODGE / FineDance: 30 fps, first 1024 frames, root-relative joints, 22 joints.
    FinedanceLodge,
    /// EDGE: 30 fps, 150-frame (5 s) clips, frame time 1/60.
    #[value(name = "edge-5s")]
    Edge5s,
    /// Positions as given, frame time 1/fps.
    None,
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum BasVariantArg {
    Bailando,
    Lodge,
    Fact,
    Gcd,
}

#[derive(Args, Debug)]
pub struct EvalArgs {
    /// Generated motion: files or directories (any format `convert` reads, joints .npy
    /// (T, 24, 3) in metres, Y-up, or group scenes (N, T, 24, 3)).
    #[arg(long, required = true, num_args = 1..)]
    pub pred: Vec<PathBuf>,
    /// Ground-truth motion (files or directories); needed by fid_*, mpjpe, gmr, genre and the
    /// *_gt values.
    #[arg(long, num_args = 1..)]
    pub gt: Vec<PathBuf>,
    /// Duets: the leader of each --pred (follower) clip, matched by file stem. Without it, a
    /// two-dancer clip (2, T, 24, 3) is read as [leader, follower] by the duet metrics.
    #[arg(long, num_args = 1..)]
    pub leader: Vec<PathBuf>,
    /// Duets: the leader of each --gt (follower) clip, matched by file stem.
    #[arg(long, num_args = 1..)]
    pub gt_leader: Vec<PathBuf>,
    /// Evaluation protocol (no resampling: the motion must already be at its frame rate).
    #[arg(long, value_enum, default_value_t = ProtocolArg::None)]
    pub protocol: ProtocolArg,
    /// Frame rate of .npy inputs (default: the protocol's).
    #[arg(long)]
    pub fps: Option<f64>,
    /// Read every input (--pred, --gt, --leader, --gt-leader) as sampled at this rate,
    /// whatever the files' headers say (the frames stay the same, their times change); for
    /// .npy inputs, the same as --fps.
    #[arg(long, value_name = "FPS", value_parser = parse_source_fps, conflicts_with = "fps")]
    pub source_fps: Option<f64>,
    /// Comma-separated metrics (default: all that the inputs allow; duet metrics by default only
    /// with --leader): fid_k,fid_g,div_k,div_g,bas,pfc,fsr,fsd,mpjpe,penetration,gmr,gmc,tif,
    /// collision,min_distance,fid_cd,div_cd,bed,ipr,contact_range,freeze,inverted,
    /// boundary_jerk,genre, and the physical figures floor_median,floor_p05,floor_p95,float,
    /// foot_slide,jerk,jerk_p99,max_step,spikes,leg_cross,lean,joint_speed,pelvis_speed,
    /// step_rate (world joints in metres, floor at y = 0). Groups: `physical` (those fourteen), `all`
    /// (every metric the inputs allow, the default).
    #[arg(long)]
    pub metrics: Option<String>,
    /// Genre check: the data set manifest (`dancegen dataset build`'s manifest.json) giving the
    /// genre of each --gt clip; a --gt file matches the clip whose name is its file stem.
    #[arg(long, value_name = "MANIFEST.json")]
    pub gt_genres: Option<PathBuf>,
    /// Genre check: the genre the --pred dances were asked for.
    #[arg(long, value_name = "NAME")]
    pub want_genre: Option<String>,
    /// Genre check: genres with fewer real --gt clips than this are left out of the classifier
    /// (and listed under `excluded`); 2 drops one-clip genres, whose one performance
    /// leave-one-out cannot test. The default, 1, keeps every genre.
    #[arg(long, value_name = "N", default_value_t = 1,
          value_parser = clap::value_parser!(u64).range(1..))]
    pub genre_min_clips: u64,
    /// Beat-align-score variant.
    #[arg(long, value_enum, default_value_t = BasVariantArg::Bailando)]
    pub bas_variant: BasVariantArg,
    /// Music beats: .npy of beat frame indices, or a (T, 35) feature file (beats = last column).
    #[arg(long, conflicts_with = "music")]
    pub beats: Option<PathBuf>,
    /// Song to compute the music beats from (at the motion's frame rate, 30 or 60).
    #[arg(long)]
    pub music: Option<PathBuf>,
    /// Frames between the window boundaries `boundary_jerk` looks at (the generator's window:
    /// 150 for EDGE's 5 s at 30 fps, 128 for dancegen's Lodge++).
    #[arg(long, default_value_t = 150, value_parser = clap::value_parser!(u64).range(2..))]
    pub window: u64,
    /// Write the results as JSON.
    #[arg(long, value_name = "OUT")]
    pub json: Option<PathBuf>,
}
