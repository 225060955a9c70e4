//! `dancegen serve`: the web app (`dancegen_server`), started with the flags' settings.

use std::path::PathBuf;

use anyhow::{Context, Result, anyhow, bail};
use dancegen_generate::models::{data_models_dir, model_kind};
use dancegen_generate::systems;
use dancegen_server::{Limits, ServeConfig};

use crate::cli::ServeArgs;

pub fn run(args: &ServeArgs, quiet: bool) -> Result<()> {
    let data_dir = match &args.data_dir {
        Some(d) => d.clone(),
        None => data_models_dir()
            .and_then(|m| m.parent().map(|p| p.join("serve")))
            .ok_or_else(|| anyhow!("no data folder on this platform: give --data-dir DIR"))?,
    };
    if !(args.max_song_seconds.is_finite() && args.max_song_seconds > 0.0) {
        bail!(
            "--max-song-seconds {}: need a positive number",
            args.max_song_seconds
        );
    }
    if args.max_upload_mb == 0 || args.max_queue == 0 {
        bail!("--max-upload-mb and --max-queue must be at least 1");
    }
    let disk_bytes = match args.max_disk_gb {
        None => None,
        Some(gb) if gb.is_finite() && gb > 0.0 && gb <= 1e6 => Some((gb * 1e9) as u64),
        Some(gb) => bail!("--max-disk-gb {gb}: need a positive number of gigabytes"),
    };
    let mut models = Vec::new();
    for dir in &args.models {
        let kind = model_kind(dir)
            .with_context(|| format!("--model {}: no model.toml with a kind", dir.display()))?;
        let system = systems::by_model_kind(&kind).ok_or_else(|| {
            anyhow!(
                "--model {}: kind '{kind}' is no system's model",
                dir.display()
            )
        })?;
        models.push((system.name.to_string(), PathBuf::from(dir)));
    }
    let admin = match &args.admin_token_file {
        None => dancegen_server::owner::AdminKey::none(),
        Some(f) => {
            let token = std::fs::read_to_string(f)
                .with_context(|| format!("--admin-token-file {}: cannot read it", f.display()))?;
            dancegen_server::owner::AdminKey::from_token(&token)
                .map_err(|e| anyhow!("--admin-token-file {}: {e}", f.display()))?
        }
    };
    let config = ServeConfig {
        addr: args.addr,
        data_dir: data_dir.clone(),
        workers: usize::from(args.workers),
        limits: Limits {
            upload_bytes: args.max_upload_mb << 20,
            song_seconds: args.max_song_seconds,
            queue_length: args.max_queue,
            jobs_per_minute: args.max_jobs_per_minute as usize,
            streams_per_client: args.max_streams_per_client as usize,
            disk_bytes,
            ..Limits::default()
        },
        models,
        keep: args
            .keep_days
            .map(|d| std::time::Duration::from_secs(u64::from(d) * 86_400)),
        admin,
    };
    dancegen_server::run(config, |addr| {
        if !quiet {
            // The one line a user needs; stdout, so scripts can read the port when it is 0.
            println!(
                "dancegen is serving http://{addr}/ (jobs in {})",
                data_dir.display()
            );
        }
    })
    .map_err(|e| anyhow!(e))
}
