//! `dancegen bundle`: one Lodge++ model directory from its three training runs.

use std::io::Write;

use anyhow::Result;
use dancegen_train::tasks::lodgepp::assemble_bundle;

use crate::cli::BundleArgs;
use crate::progress::spinner;

pub fn run(args: &BundleArgs, quiet: bool) -> Result<()> {
    let pb = spinner("assembling the model and its key-motion library", quiet);
    let clips = assemble_bundle(
        &args.vqvae,
        &args.gpt,
        &args.pddm,
        &args.output,
        &args.name,
        args.default_genre.as_deref(),
    )?;
    pb.finish_and_clear();
    if !quiet {
        writeln!(
            std::io::stdout().lock(),
            "{} ({clips} key motions in the library) -> {}",
            args.name,
            args.output.display()
        )?;
    }
    Ok(())
}
