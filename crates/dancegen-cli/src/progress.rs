//! Progress on stderr: a spinner for the short commands, and for `generate` a bar or JSON
//! lines fed by the generation library's progress reports.

use std::io::Write;
use std::time::Duration;

use dancegen_generate::Progress;
use dancegen_generate::progress::stage;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use crate::cli::ProgressArg;

/// A spinner for steps that can take over a second (long songs), silent with `--quiet` or
/// when stderr is not a terminal.
pub fn spinner(msg: &str, quiet: bool) -> ProgressBar {
    let pb = ProgressBar::new_spinner();
    if quiet {
        pb.set_draw_target(ProgressDrawTarget::hidden());
    }
    pb.set_style(
        ProgressStyle::with_template("{spinner} {msg} [{elapsed}]")
            .unwrap_or_else(|_| ProgressStyle::default_spinner()),
    );
    pb.set_message(msg.to_string());
    // Only appears if the step is still running after the first tick (fast runs stay clean).
    pb.enable_steady_tick(Duration::from_millis(120));
    pb
}

/// Bar resolution: per mille.
const BAR_UNITS: u64 = 1000;

/// How a generation job's progress is shown.
pub enum JobProgress {
    Bar(ProgressBar),
    Json,
    None,
}

impl JobProgress {
    pub fn new(mode: ProgressArg) -> Self {
        match mode {
            ProgressArg::Bar => {
                let pb = ProgressBar::new(BAR_UNITS);
                pb.set_style(
                    ProgressStyle::with_template(
                        "{spinner} {msg:<22} [{bar:30}] {percent:>3}% {elapsed} (about {eta} left)",
                    )
                    .unwrap_or_else(|_| ProgressStyle::default_bar())
                    .progress_chars("=> "),
                );
                pb.enable_steady_tick(Duration::from_millis(120));
                JobProgress::Bar(pb)
            }
            ProgressArg::Json => JobProgress::Json,
            ProgressArg::None => JobProgress::None,
        }
    }

    pub fn report(&self, p: &Progress) {
        match self {
            JobProgress::Bar(pb) => {
                pb.set_message(label(p.stage));
                pb.set_position((p.fraction * BAR_UNITS as f64).round() as u64);
            }
            JobProgress::Json => {
                // One line per report; stderr is unbuffered, so each line is whole.
                if let Ok(line) = serde_json::to_string(p) {
                    let _ = writeln!(std::io::stderr().lock(), "{line}");
                }
            }
            JobProgress::None => {}
        }
    }

    pub fn finish(&self) {
        if let JobProgress::Bar(pb) = self {
            pb.finish_and_clear();
        }
    }
}

/// Words for a stage name.
fn label(stage: &str) -> &'static str {
    match stage {
        stage::LOAD_MODEL => "loading the model",
        stage::ANALYSE_SONG => "analysing the song",
        "choreography" => "choreographing",
        "denoising" => "dancing",
        stage::WRITE_OUTPUTS => "writing the outputs",
        stage::DONE => "done",
        _ => "working",
    }
}
