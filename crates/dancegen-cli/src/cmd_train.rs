//! `dancegen train CONFIG.toml` / `dancegen train --resume RUN_DIR`: the training loop of
//! `dancegen-train` on a configuration file.

use anyhow::Result;
use dancegen_train::tasks::{resume_run, train_config};
use dancegen_train::{RunOptions, TrainConfig};

use crate::cli::TrainArgs;

pub fn run(args: &TrainArgs, quiet: bool) -> Result<()> {
    let opts = RunOptions {
        quiet,
        stop_at: args.stop_at,
    };
    let summary = match (&args.config, &args.resume) {
        (Some(path), None) => {
            let mut config = TrainConfig::load(path)?;
            if let Some(dir) = &args.run_dir {
                config.run.dir = std::path::absolute(dir)?;
            }
            train_config(&config, path, &opts)?
        }
        (None, Some(dir)) => resume_run(dir, &opts)?,
        // clap enforces exactly one of the two.
        _ => anyhow::bail!("give a CONFIG.toml or --resume RUN_DIR"),
    };
    if !quiet {
        let what = if summary.finished {
            format!("done; the model is in {}", summary.run_dir.display())
        } else {
            format!(
                "stopped at step {}; continue with `dancegen train --resume {}`",
                summary.step,
                summary.run_dir.display()
            )
        };
        eprintln!(
            "steps {}..{} at {:.2} steps/s, last loss {:.6}: {what}",
            summary.start_step, summary.step, summary.steps_per_s, summary.last_loss
        );
    }
    Ok(())
}
