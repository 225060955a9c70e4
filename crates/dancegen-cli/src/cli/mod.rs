//! The command line: `dancegen` and its subcommands, one file per command's arguments. The
//! commands' code (`cmd_*.rs`, `batch/`, `eval/`) reads these types; nothing here reads theirs.

use clap::{Parser, Subcommand};

mod batch;
mod convert;
mod dataset;
mod eval;
mod generate;
mod models;
mod music;
mod render;
mod serve;
mod train;

pub use batch::{BatchArgs, Shard};
pub use convert::{ConvertArgs, NpzStyleArg, TargetSkeleton};
pub use dataset::{DatasetBuildArgs, DatasetCommand, PairingArg};
pub use eval::{BasVariantArg, EvalArgs, ProtocolArg};
pub use generate::{GenerateArgs, ProgressArg};
pub use models::{BundleArgs, ModelsArgs, ModelsCommand};
pub use music::{BeatsArgs, FeaturesArgs, SetArg};
pub use render::RenderArgs;
pub use serve::ServeArgs;
pub use train::TrainArgs;

#[derive(Parser, Debug)]
#[command(name = "dancegen", version, about = "Turn music into 3D dance", long_about = None)]
pub struct Cli {
    /// More log output (-v info, -vv debug, -vvv trace).
    #[arg(short, long, action = clap::ArgAction::Count, global = true)]
    pub verbose: u8,
    /// Only print errors; no progress bars.
    #[arg(short, long, global = true)]
    pub quiet: bool,
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Per-frame music features the dance models are conditioned on (librosa-compatible).
    Features(FeaturesArgs),
    /// Tempo and beat times of a song, optionally plotted.
    Beats(BeatsArgs),
    /// Convert motion between research formats and the formats animators use.
    Convert(ConvertArgs),
    /// Render a preview of one or more dancers: PNG (one frame), GIF or MP4 (with audio).
    Render(RenderArgs),
    /// Dance metrics (FID, diversity, BAS, PFC, foot skating, MPJPE, ...) under a paper's protocol.
    Eval(EvalArgs),
    /// Train a model from a TOML config (see examples/train/), or continue a run.
    Train(TrainArgs),
    /// Build training sets: motion + music pairs (beat-warp pseudo-pairing, AIST++, FineDance).
    #[command(subcommand)]
    Dataset(DatasetCommand),
    /// Generate a solo dance for a song (Lodge++), or with --leader the partner of a given
    /// leader (ReactDance); the installed default models (see `dancegen models`).
    #[command(after_long_help = dancegen_generate::systems::edits_table())]
    Generate(Box<GenerateArgs>),
    /// Generate many songs from a manifest (one JSON object per line: id, song, outputs and
    /// any `generate` option by name): one model load, resumable (songs with a done.json are
    /// skipped), shardable (--shard I/N) across processes and machines.
    Batch(BatchArgs),
    /// List the models found and where they were looked for, or install models.
    Models(ModelsArgs),
    /// Assemble a model directory from its finished training runs (solo: --vqvae --gpt --pddm;
    /// duet: --hfsq --ldm; group: --group; holistic: --holistic-vq --holistic-mmr
    /// --holistic-generator).
    Bundle(BundleArgs),
    /// The web app: upload a song, follow the progress, watch the dance in 3D in time with
    /// the music, download it (http://127.0.0.1:8080 by default).
    Serve(ServeArgs),
}
