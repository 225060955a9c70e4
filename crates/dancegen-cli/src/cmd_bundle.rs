//! `dancegen bundle`: one model directory from its training runs (Lodge++: three; the duet
//! model: two; the group model: one; the holistic model: three).

use std::io::Write;

use anyhow::{Result, bail};
use dancegen_train::tasks::lodgepp::assemble_bundle;
use dancegen_train::tasks::reactdance::assemble_duet_bundle;
use dancegen_train::tasks::soulnet::assemble_holistic_bundle;
use dancegen_train::tasks::tcdiffpp::assemble_group_bundle;

use crate::cli::BundleArgs;
use crate::progress::spinner;

pub fn run(args: &BundleArgs, quiet: bool) -> Result<()> {
    if let (Some(vq), Some(mmr), Some(generator)) = (
        &args.holistic_vq,
        &args.holistic_mmr,
        &args.holistic_generator,
    ) {
        let name = args.name.as_deref().unwrap_or("soulnet-small");
        let pb = spinner("assembling the holistic model", quiet);
        assemble_holistic_bundle(vq, mmr, generator, &args.output, name)?;
        pb.finish_and_clear();
        if !quiet {
            writeln!(
                std::io::stdout().lock(),
                "{name} -> {}",
                args.output.display()
            )?;
        }
        return Ok(());
    }
    if let Some(run) = &args.group {
        let name = args.name.as_deref().unwrap_or("tcdiffpp-small");
        let pb = spinner("assembling the group model", quiet);
        assemble_group_bundle(run, &args.output, name)?;
        pb.finish_and_clear();
        if !quiet {
            writeln!(
                std::io::stdout().lock(),
                "{name} -> {}",
                args.output.display()
            )?;
        }
        return Ok(());
    }
    if let (Some(hfsq), Some(ldm)) = (&args.hfsq, &args.ldm) {
        let name = args.name.as_deref().unwrap_or("reactdance-small");
        let pb = spinner("assembling the duet model", quiet);
        assemble_duet_bundle(hfsq, ldm, &args.output, name)?;
        pb.finish_and_clear();
        if !quiet {
            writeln!(
                std::io::stdout().lock(),
                "{name} -> {}",
                args.output.display()
            )?;
        }
        return Ok(());
    }
    let (Some(vqvae), Some(gpt), Some(pddm)) = (&args.vqvae, &args.gpt, &args.pddm) else {
        bail!(
            "give --vqvae, --gpt and --pddm (solo model), --hfsq and --ldm (duet model), \
             --group (group model) or --holistic-vq, --holistic-mmr and --holistic-generator \
             (holistic model)"
        );
    };
    let name = args.name.as_deref().unwrap_or("lodgepp-small");
    let pb = spinner("assembling the model and its key-motion library", quiet);
    let clips = assemble_bundle(
        vqvae,
        gpt,
        pddm,
        &args.output,
        name,
        args.default_genre.as_deref(),
    )?;
    pb.finish_and_clear();
    if !quiet {
        writeln!(
            std::io::stdout().lock(),
            "{name} ({clips} key motions in the library) -> {}",
            args.output.display()
        )?;
    }
    Ok(())
}
