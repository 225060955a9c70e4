//! `dancegen generate`: the flags become a request
//! ([`dancegen_generate::flags::request`]) and a progress bar goes around
//! `dancegen_generate::Generator` (which does the work for every system).

use std::io::Write;

use anyhow::Result;
use dancegen_generate::{CancelToken, Generator, ModelLocator, Progress};

use crate::cli::{GenerateArgs, ProgressArg};
use crate::progress::JobProgress;

pub fn run(args: &GenerateArgs, quiet: bool) -> Result<()> {
    let request = dancegen_generate::flags::request(&args.flags)?;
    let generator = Generator::new(ModelLocator::from_environment());
    let bar = JobProgress::new(match args.progress {
        ProgressArg::Bar if !quiet => ProgressArg::Bar,
        ProgressArg::Bar => ProgressArg::None,
        other => other,
    });
    let on_progress = |p: &Progress| bar.report(p);
    let done = generator.run(&request, &on_progress, &CancelToken::new());
    bar.finish();
    let done = done?;
    // Even with -q: a warning says the dance may not be what was wanted.
    for w in &done.warnings {
        eprintln!("warning: {w}");
    }
    if !quiet {
        let mut out = std::io::stdout().lock();
        let notes: String = done.notes.iter().map(|n| format!("; {n}")).collect();
        writeln!(
            out,
            "{}: {}; generated in {:.2} s ({}{:.2} s in total){notes}",
            done.song_label,
            done.summary,
            done.timings.generate_s,
            done.timing_breakdown,
            done.timings.total_s,
        )?;
        for p in &done.written {
            writeln!(out, "  -> {}", p.display())?;
        }
    }
    Ok(())
}
