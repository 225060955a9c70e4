//! `genre`: does a dance look like the genre it was asked for? A nearest-centroid classifier
//! (`dancegen_metrics::genre`) is fit on the kinetic features of the `--gt` clips, labelled by the
//! `--gt-genres` manifest, and assigns each `--pred` dancer a genre. The share assigned to
//! `--want-genre` is reported next to what it should be read against: chance (uniform and
//! majority) and the leave-one-out accuracy on the real clips themselves. Beside it, FID_k of the
//! `--pred` set against each genre's real clips (what `fid_k` gives with `--gt` holding only that
//! genre's clips). Genres with fewer than `--genre-min-clips` real clips are left out of the
//! classifier and reported under `excluded` (`dancegen_metrics::genre::keep_genres_with_at_least`).

use std::collections::BTreeMap;
use std::path::Path;

use anyhow::{Context, Result, bail};
use dancegen_dataset::Manifest;
use dancegen_metrics::fid::EPS_BAILANDO;
use dancegen_metrics::genre::{
    GenreClassifier, count_predictions, keep_genres_with_at_least, leave_one_out_accuracy,
};
use dancegen_metrics::protocol::Protocol;
use dancegen_metrics::{frechet_distance, normalize_by_gt};
use serde_json::{Value, json};

use super::input::Clip;
use super::solo;

/// The `genre` summary object and each `--pred` clip's predicted genre per dancer.
pub struct GenreReport {
    pub summary: Value,
    pub per_clip: Vec<Vec<String>>,
}

/// Fits on `gt` (genres from the manifest at `manifest_path`; genres with fewer than
/// `min_clips` clips left out) and classifies `pred`. Kinetic features are those `fid_k` uses
/// under `protocol` (`solo::features`), one sample per dancer.
pub fn check(
    pred: &[Clip],
    gt: &[Clip],
    manifest_path: &Path,
    want: &str,
    min_clips: usize,
    protocol: &Protocol,
) -> Result<GenreReport> {
    let manifest = Manifest::read(manifest_path).context("--gt-genres")?;
    let by_name: BTreeMap<&str, &str> = manifest
        .clips
        .iter()
        .map(|c| (c.name.as_str(), c.genre.as_str()))
        .collect();
    let mut known: Vec<&str> = manifest.genres.iter().map(String::as_str).collect();
    known.extend(by_name.values());
    known.sort_unstable();
    known.dedup();
    if !known.contains(&want) {
        bail!(
            "--want-genre {want} is not a genre of {} (its genres: {})",
            manifest_path.display(),
            known.join(", ")
        );
    }

    let mut examples: Vec<(String, Vec<f64>)> = Vec::new();
    for c in gt {
        let stem = c.stem();
        let Some(genre) = by_name.get(stem.as_str()) else {
            bail!(
                "--gt clip {} has no entry in {} (no clip named {stem})",
                c.path.display(),
                manifest_path.display()
            );
        };
        for f in solo::features(std::slice::from_ref(c), "k", protocol)? {
            examples.push((genre.to_string(), f));
        }
    }
    let (examples, excluded) = keep_genres_with_at_least(examples, min_clips);
    if let Some(n) = excluded.get(want) {
        bail!(
            "--want-genre {want} has {n} real --gt clip(s), fewer than --genre-min-clips {min_clips}: \
             too few to tell whether a dance looks like it"
        );
    }
    for (g, n) in &excluded {
        tracing::warn!(
            "genre {g} has {n} real --gt clip(s), fewer than --genre-min-clips {min_clips}: left out of the classifier"
        );
    }
    let mut real: Vec<&str> = examples.iter().map(|(g, _)| g.as_str()).collect();
    real.sort_unstable();
    real.dedup();
    if !real.contains(&want) {
        bail!(
            "no --gt clip has genre {want}, so the classifier cannot recognise it (the --gt clips have: {})",
            real.join(", ")
        );
    }
    for g in known
        .iter()
        .filter(|g| !real.contains(*g) && !excluded.contains_key(**g))
    {
        tracing::warn!(
            "genre {g} of {} has no --gt clip; the classifier does not know it",
            manifest_path.display()
        );
    }

    let clf = GenreClassifier::fit(&examples)
        .with_context(|| format!("genre classifier on the --gt clips ({})", real.join(", ")))?;
    let loo = leave_one_out_accuracy(&examples)?;

    let mut per_clip = Vec::with_capacity(pred.len());
    let mut pred_features = Vec::new();
    for c in pred {
        let mut genres = Vec::with_capacity(c.dancers.len());
        for f in solo::features(std::slice::from_ref(c), "k", protocol)? {
            let g = clf
                .predict(&f)
                .with_context(|| format!("{}: genre", c.path.display()))?;
            genres.push(g.to_string());
            pred_features.push(f);
        }
        per_clip.push(genres);
    }
    // FID_k against each genre's real clips, normalised by that genre's statistics as `fid_k`
    // normalises by its --gt set; undefined (null) with fewer than two clips on either side.
    let mut fid_k = serde_json::Map::new();
    for g in &real {
        let of_genre: Vec<Vec<f64>> = examples
            .iter()
            .filter(|(e, _)| e == g)
            .map(|(_, f)| f.clone())
            .collect();
        let v = if of_genre.len() < 2 || pred_features.len() < 2 {
            Value::Null
        } else {
            let (g_n, p_n) = normalize_by_gt(&of_genre, &pred_features);
            super::num(frechet_distance(&p_n, &g_n, EPS_BAILANDO))
        };
        fid_k.insert(g.to_string(), v);
    }
    let counts = count_predictions(per_clip.iter().flatten().map(String::as_str));
    let samples: usize = counts.values().sum();
    let share = (samples > 0).then(|| *counts.get(want).unwrap_or(&0) as f64 / samples as f64);
    let classes: serde_json::Map<String, Value> = clf
        .classes()
        .into_iter()
        .map(|(g, n)| (g.to_string(), json!(n)))
        .collect();
    let summary = json!({
        "requested": want,
        "share_requested": share,
        "samples": samples,
        "chance_uniform": clf.chance_uniform(),
        "chance_majority": clf.chance_majority(),
        "loo_accuracy_real": loo.accuracy(),
        "counts": counts,
        "classes": classes,
        "excluded": excluded,
        "min_clips": min_clips,
        "fid_k": fid_k,
    });
    Ok(GenreReport { summary, per_clip })
}
