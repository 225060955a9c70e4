//! `dancegen train`: a config to start a run from, or a run to continue.

use std::path::PathBuf;

use clap::Args;

#[derive(Args, Debug)]
pub struct TrainArgs {
    /// Training configuration (TOML).
    #[arg(required_unless_present = "resume", conflicts_with = "resume")]
    pub config: Option<PathBuf>,
    /// Run directory (default: the config's `[run] dir`).
    #[arg(long, value_name = "DIR", conflicts_with = "resume")]
    pub run_dir: Option<PathBuf>,
    /// Continue the run in RUN_DIR from its latest checkpoint.
    #[arg(long, value_name = "RUN_DIR")]
    pub resume: Option<PathBuf>,
    /// Stop after this step, as if interrupted (a checkpoint is written there).
    #[arg(long, value_name = "STEP")]
    pub stop_at: Option<u64>,
}
