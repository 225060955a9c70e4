//! `dancegen models`: the models found and the folders searched; `models install` copies
//! models into the data folder.

use std::io::Write;

use anyhow::{Context, Result, bail};
use dancegen_generate::ModelLocator;
use dancegen_generate::models::{self, MODEL_DIR_ENV};
use dancegen_generate::systems;

use crate::cli::{ModelsArgs, ModelsCommand};

pub fn run(args: &ModelsArgs, quiet: bool) -> Result<()> {
    match &args.command {
        None => list(args.json),
        Some(ModelsCommand::List { json }) => list(*json || args.json),
        Some(ModelsCommand::Install { from, to }) => {
            let from = match from {
                Some(f) => f.clone(),
                None => models::checkout_models().context(
                    "give --from DIR (a folder of models, e.g. a checkout's models/): the \
                     checkout this binary was built from is gone",
                )?,
            };
            let to = match to {
                Some(t) => t.clone(),
                None => models::data_models_dir()
                    .context("no data folder is known on this platform: give --to DIR")?,
            };
            let done = models::install(&from, &to)?;
            if !quiet {
                let mut out = std::io::stdout().lock();
                for m in &done {
                    writeln!(
                        out,
                        "{} {} -> {}",
                        if m.replaced { "updated" } else { "installed" },
                        m.name,
                        m.dir.display()
                    )?;
                }
            }
            Ok(())
        }
    }
}

fn list(json: bool) -> Result<()> {
    let locator = ModelLocator::from_environment();
    let found = locator.list();
    let system_of = |kind: &Option<String>| {
        kind.as_deref()
            .and_then(systems::by_model_kind)
            .map(|s| s.name)
    };
    let mut out = std::io::stdout().lock();
    if json {
        let value = serde_json::json!({
            "search_path": locator.search_dirs().iter().map(|d| serde_json::json!({
                "dir": d.dir,
                "origin": d.origin.describe(),
                "exists": d.dir.is_dir(),
            })).collect::<Vec<_>>(),
            "models": found.iter().map(|m| serde_json::json!({
                "name": m.name,
                "kind": m.kind,
                "system": system_of(&m.kind),
                "dir": m.dir,
                "origin": m.origin.describe(),
                "shadowed": m.shadowed,
            })).collect::<Vec<_>>(),
            "defaults": systems::SYSTEMS.iter().filter(|s| s.available).map(|s| serde_json::json!({
                "system": s.name,
                "model": s.default_model,
                "dir": locator.find(s.default_model, s.name).ok(),
            })).collect::<Vec<_>>(),
        });
        writeln!(out, "{}", serde_json::to_string_pretty(&value)?)?;
        return Ok(());
    }
    writeln!(
        out,
        "Model search path (first match wins; {MODEL_DIR_ENV} adds folders first):"
    )?;
    for (i, d) in locator.search_dirs().iter().enumerate() {
        let state = if d.dir.is_dir() { "" } else { " [missing]" };
        writeln!(
            out,
            "  {}. {} ({}){state}",
            i + 1,
            d.dir.display(),
            d.origin.describe()
        )?;
    }
    writeln!(out, "Models:")?;
    if found.is_empty() {
        writeln!(out, "  none found")?;
    }
    for m in &found {
        writeln!(
            out,
            "  {:<20} {:<8} {}{}",
            m.name,
            system_of(&m.kind).unwrap_or("?"),
            m.dir.display(),
            if m.shadowed { " (shadowed)" } else { "" }
        )?;
    }
    let missing: Vec<_> = systems::SYSTEMS
        .iter()
        .filter(|s| s.available && locator.find(s.default_model, s.name).is_err())
        .collect();
    for s in &missing {
        writeln!(
            out,
            "The {} system's default model {} is not installed: `dancegen models install \
             --from CHECKOUT/models` or set {MODEL_DIR_ENV}.",
            s.name, s.default_model
        )?;
    }
    if !missing.is_empty() && found.is_empty() {
        bail!("no models found");
    }
    Ok(())
}
