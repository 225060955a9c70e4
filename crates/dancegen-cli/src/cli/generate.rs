//! `dancegen generate`: the options every front end shares
//! ([`dancegen_generate::flags::GenerateFlags`]) and how progress is shown.

use clap::{Args, ValueEnum};
use dancegen_generate::flags::GenerateFlags;

/// How `generate` reports progress on stderr.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum ProgressArg {
    /// A progress bar when stderr is a terminal (nothing with -q).
    #[default]
    Bar,
    /// One JSON object per line: {"stage": ..., "fraction": 0..1, "eta_s": ...}; the last
    /// one has fraction 1.
    Json,
    /// Nothing.
    None,
}

#[derive(Args, Debug)]
pub struct GenerateArgs {
    #[command(flatten)]
    pub flags: GenerateFlags,
    /// Progress on stderr.
    #[arg(long, value_enum, default_value_t = ProgressArg::Bar)]
    pub progress: ProgressArg,
}
