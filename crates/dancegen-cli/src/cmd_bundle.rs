//! `dancegen bundle`: one model directory from its training runs (Lodge++: three; the duet
//! model: two; the group model: one; the holistic model: three).

use std::io::Write;

use anyhow::{Result, bail};
use dancegen_train::tasks::lodgepp::assemble_bundle;
use dancegen_train::tasks::reactdance::assemble_duet_bundle;
use dancegen_train::tasks::soulnet::{
    Replacements, assemble_holistic_bundle, replace_in_holistic_model,
};
use dancegen_train::tasks::tcdiffpp::assemble_group_bundle;

use crate::cli::BundleArgs;
use crate::progress::spinner;

pub fn run(args: &BundleArgs, quiet: bool) -> Result<()> {
    if let (Some(vq), Some(mmr), Some(generator)) = (
        &args.holistic_vq,
        &args.holistic_mmr,
        &args.holistic_generator,
    ) {
        return assemble(args, quiet, "soulnet-small", "the holistic model", |name| {
            assemble_holistic_bundle(vq, mmr, generator, &args.output, name)?;
            Ok(String::new())
        });
    }
    if let Some(model) = &args.holistic_model {
        if args.holistic_vq.is_none() && args.holistic_generator.is_none() {
            bail!(
                "--holistic-model {}: give --holistic-vq and/or --holistic-generator (the runs \
                 that replace its networks)",
                model.display()
            );
        }
        let runs = Replacements {
            vq: args.holistic_vq.as_deref(),
            generator: args.holistic_generator.as_deref(),
        };
        return assemble(args, quiet, "soulnet-small", "the holistic model", |name| {
            replace_in_holistic_model(runs, model, &args.output, name)?;
            Ok(String::new())
        });
    }
    if args.holistic_vq.is_some() || args.holistic_generator.is_some() {
        bail!(
            "the holistic model needs --holistic-vq, --holistic-mmr and --holistic-generator \
             (three runs), or --holistic-model with --holistic-vq and/or --holistic-generator"
        );
    }
    if let Some(run) = &args.group {
        return assemble(args, quiet, "tcdiffpp-small", "the group model", |name| {
            assemble_group_bundle(run, &args.output, name)?;
            Ok(String::new())
        });
    }
    if let (Some(hfsq), Some(ldm)) = (&args.hfsq, &args.ldm) {
        return assemble(args, quiet, "reactdance-small", "the duet model", |name| {
            assemble_duet_bundle(hfsq, ldm, &args.output, name)?;
            Ok(String::new())
        });
    }
    let (Some(vqvae), Some(gpt), Some(pddm)) = (&args.vqvae, &args.gpt, &args.pddm) else {
        bail!(
            "give --vqvae, --gpt and --pddm (solo model), --hfsq and --ldm (duet model), \
             --group (group model) or --holistic-vq with --holistic-mmr and \
             --holistic-generator, or with --holistic-model (holistic model)"
        );
    };
    assemble(
        args,
        quiet,
        "lodgepp-small",
        "the model and its key-motion library",
        |name| {
            let clips = assemble_bundle(
                vqvae,
                gpt,
                pddm,
                &args.output,
                name,
                args.default_genre.as_deref(),
            )?;
            Ok(format!(" ({clips} key motions in the library)"))
        },
    )
}

/// One bundle: `build` writes the model named `--name` (or `default_name`) under a spinner and
/// returns extra words for the closing `NAME… -> DIR` line.
fn assemble(
    args: &BundleArgs,
    quiet: bool,
    default_name: &str,
    what: &str,
    build: impl FnOnce(&str) -> Result<String>,
) -> Result<()> {
    let name = args.name.as_deref().unwrap_or(default_name);
    let pb = spinner(&format!("assembling {what}"), quiet);
    let extra = build(name)?;
    pb.finish_and_clear();
    if !quiet {
        writeln!(
            std::io::stdout().lock(),
            "{name}{extra} -> {}",
            args.output.display()
        )?;
    }
    Ok(())
}
