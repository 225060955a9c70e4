//! `dancegen batch`: the manifest, the output folder and the shard of it this process takes.

use std::path::PathBuf;

use clap::Args;

#[derive(Args, Debug)]
pub struct BatchArgs {
    /// The manifest: one JSON object per line, e.g. {"id": "song-1", "song": "songs/a.mp3",
    /// "system": "solo", "seed": 7, "outputs": ["dance.glb", "dance.npy"], "genre": "salsa"}.
    /// Keys are `generate`'s options (snake_case or kebab-case; true for a switch); the seed
    /// defaults to a hash of the id; relative paths are taken from the manifest's folder (or
    /// the current one).
    pub manifest: PathBuf,
    /// Output folder: DIR/<id>/<output>, DIR/<id>/done.json once a song is complete, and one
    /// line per song in DIR/results.jsonl ({"id", "line", "error", "skipped", "seconds"}).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Take only the lines whose 0-based index mod N is I (e.g. a Kubernetes Indexed Job's
    /// $JOB_COMPLETION_INDEX/N or a Slurm array's $SLURM_ARRAY_TASK_ID/N).
    #[arg(long, value_name = "I/N")]
    pub shard: Option<Shard>,
    /// Songs generated at once in this process (each already uses every core; more helps
    /// only to overlap song decoding and file writing).
    #[arg(long, default_value_t = 1, value_name = "K",
        value_parser = clap::value_parser!(u16).range(1..=64))]
    pub jobs: u16,
}

/// `I/N`: this process's share of the manifest.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    pub index: usize,
    pub count: usize,
}

impl std::str::FromStr for Shard {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let (i, n) = s
            .split_once('/')
            .ok_or_else(|| format!("'{s}' is not I/N (e.g. 0/4)"))?;
        let index: usize = i
            .trim()
            .parse()
            .map_err(|_| format!("'{i}' is not a shard index"))?;
        let count: usize = n
            .trim()
            .parse()
            .map_err(|_| format!("'{n}' is not a shard count"))?;
        if count == 0 || index >= count {
            return Err(format!("shard {index}/{count}: need 0 ≤ I < N"));
        }
        Ok(Shard { index, count })
    }
}
