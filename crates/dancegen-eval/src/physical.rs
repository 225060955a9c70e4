//! `--metrics physical`: the plausibility figures of `dancegen_metrics::physical` on each
//! dancer's world joints (cut to the protocol's length, no root handling: the floor and the
//! pelvis path are what they measure).
//!
//! A clip's value is the mean over its dancers, except `max_step` (the largest of any dancer)
//! and `spikes` (summed); the set value likewise: the mean over clips, the largest `max_step`,
//! the total `spikes`.

use anyhow::{Context, Result};
use dancegen_metrics::physical::{KEYS, Physical, physical};

use super::input::Clip;

/// Every dancer's figures.
pub fn clip_figures(clip: &Clip) -> Result<Vec<Physical>> {
    clip.placed
        .iter()
        .map(|d| physical(d, clip.fps()))
        .collect::<Result<_, _>>()
        .with_context(|| format!("{}: physical", clip.path.display()))
}

/// Whether `m` is one of the physical figures.
pub fn is_physical(m: &str) -> bool {
    KEYS.contains(&m)
}

/// How the values of several dancers or clips combine into one for key `m`.
pub fn combine(m: &str, vals: &[f64]) -> Option<f64> {
    if vals.is_empty() {
        return None;
    }
    Some(match m {
        "max_step" => vals.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        "spikes" => vals.iter().sum(),
        _ => vals.iter().sum::<f64>() / vals.len() as f64,
    })
}

/// Value of key `m` for one clip.
pub fn value(figures: &[Physical], m: &str) -> Option<f64> {
    let vals: Vec<f64> = figures
        .iter()
        .filter_map(|f| {
            f.entries()
                .into_iter()
                .find(|(k, _)| *k == m)
                .and_then(|(_, v)| v)
        })
        .collect();
    combine(m, &vals)
}
