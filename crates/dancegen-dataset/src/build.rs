//! `build`: reads the inputs, runs the chosen pairing and writes the manifest last.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use rayon::prelude::*;

use crate::FPS;
use crate::error::DatasetError;
use crate::inputs::expand_motion_inputs;
use crate::manifest::{ClipEntry, MANIFEST_VERSION, Manifest};
use crate::options::{BuildOptions, Pairing, Progress};
use crate::pseudo::build_pseudo;
use crate::song::stem;
use crate::{dd100, duet, genre, group, holistic_synth, layouts, takes};

/// What [`build`] produced.
#[derive(Clone, Debug)]
pub struct BuildReport {
    pub manifest: Manifest,
    pub manifest_path: PathBuf,
}

/// Builds the data set described by `opts` (see the crate docs).
pub fn build(opts: &BuildOptions, progress: &dyn Progress) -> Result<BuildReport, DatasetError> {
    if let Some(g) = &opts.genre
        && g.trim().is_empty()
    {
        return Err(DatasetError::Options("--genre must not be empty".into()));
    }
    if opts.songs_per_motion == 0 {
        return Err(DatasetError::Options(
            "--songs-per-motion must be at least 1".into(),
        ));
    }
    if opts.songs_per_motion > 1 && opts.pairing != Pairing::Pseudo {
        return Err(DatasetError::Options(
            "--songs-per-motion works with --pairing pseudo only".into(),
        ));
    }
    if opts.mirror && !matches!(opts.pairing, Pairing::Pseudo | Pairing::Duet) {
        return Err(DatasetError::Options(
            "--mirror works with --pairing pseudo and duet only (a data set layout is not \
             mirrored)"
                .into(),
        ));
    }
    if opts.holistic && !matches!(opts.pairing, Pairing::Pseudo | Pairing::Aistpp) {
        return Err(DatasetError::Options(
            "--holistic works with --pairing pseudo and aistpp only (bodies without real hands)"
                .into(),
        ));
    }
    let merges = merge_table(&opts.merge_genres)?;
    let takes = survey_takes(opts, progress)?;
    let mut clips = match opts.pairing {
        Pairing::Pseudo => build_pseudo(opts, progress)?,
        Pairing::Duet => duet::build_duet(opts, progress)?,
        Pairing::Dd100 => dd100::build_dd100(opts, progress)?,
        Pairing::Aistpp | Pairing::FineDance => layouts::build_layout(opts, progress)?,
        Pairing::Group => group::build_group(opts, progress)?,
    };
    for c in &mut clips {
        if let Some(to) = merges.get(&c.genre) {
            c.genre = to.clone();
        }
    }
    if opts.holistic {
        progress.stage("synthesising hands and faces", 0);
        holistic_synth::attach::attach(&opts.out, &mut clips, opts.seed)?;
    }
    finish(&opts.out, clips, takes)
}

/// Every `--motion` take's rate, tempo and floor ([`takes`]), each take out of the range of
/// real dance warned about by name. Pairings from a data set root read their own layout and
/// are not surveyed.
fn survey_takes(
    opts: &BuildOptions,
    progress: &dyn Progress,
) -> Result<Vec<takes::TakeEntry>, DatasetError> {
    if !matches!(
        opts.pairing,
        Pairing::Pseudo | Pairing::Duet | Pairing::Group
    ) {
        if !opts.source_fps.is_empty() {
            return Err(DatasetError::Options(
                "--source-fps applies to --motion inputs (pseudo, duet and group pairing); a \
                 data set layout has its own rates"
                    .into(),
            ));
        }
        return Ok(Vec::new());
    }
    let files = expand_motion_inputs(&opts.motions)?;
    opts.source_fps.check_used(&files)?;
    progress.stage("measuring takes", files.len());
    let per_file: Vec<Result<Vec<takes::TakeEntry>, DatasetError>> = files
        .par_iter()
        .map(|path| {
            let g = opts
                .genre
                .as_deref()
                .map(genre::normalize)
                .unwrap_or_else(|| genre::genre_from_name(&stem(path)));
            let g = merge_table(&opts.merge_genres)?
                .get(&g)
                .cloned()
                .unwrap_or(g);
            let entries = takes::measure(path, &g, &opts.source_fps);
            progress.step(&stem(path));
            entries
        })
        .collect();
    let mut out = Vec::new();
    for r in per_file {
        out.extend(r?);
    }
    for t in &out {
        if let Some(w) = &t.warning {
            tracing::warn!(
                "take {} ({}, read at {} fps): {w}",
                t.name,
                t.source,
                t.source_fps
            );
        }
    }
    Ok(out)
}

/// `--merge-genre` pairs as a map, names normalised like `--genre`; a genre merged into one
/// that is itself merged away, or merged twice, is an error (the result would depend on order).
fn merge_table(pairs: &[(String, String)]) -> Result<BTreeMap<String, String>, DatasetError> {
    let mut map = BTreeMap::new();
    for (from, to) in pairs {
        let (from, to) = (genre::normalize(from), genre::normalize(to));
        if from.is_empty() || to.is_empty() || from == to {
            return Err(DatasetError::Options(format!(
                "--merge-genre {from:?}={to:?}: give two different, non-empty genre names"
            )));
        }
        if map.insert(from.clone(), to).is_some() {
            return Err(DatasetError::Options(format!(
                "--merge-genre: {from:?} is merged twice"
            )));
        }
    }
    if let Some(to) = map.values().find(|to| map.contains_key(*to)) {
        return Err(DatasetError::Options(format!(
            "--merge-genre: {to:?} is both merged into and merged away"
        )));
    }
    Ok(map)
}

fn finish(
    out: &Path,
    mut clips: Vec<ClipEntry>,
    takes: Vec<takes::TakeEntry>,
) -> Result<BuildReport, DatasetError> {
    clips.sort_by(|a, b| a.name.cmp(&b.name));
    let genres: BTreeSet<String> = clips.iter().map(|c| c.genre.clone()).collect();
    let held_out = clips
        .iter()
        .filter(|c| c.motion.starts_with("held_out/"))
        .map(|c| c.name.clone())
        .collect();
    let manifest = Manifest {
        version: MANIFEST_VERSION,
        fps: FPS,
        genres: genres.into_iter().collect(),
        clips,
        held_out,
        takes,
    };
    let manifest_path = out.join("manifest.json");
    manifest.write(&manifest_path)?;
    Ok(BuildReport {
        manifest,
        manifest_path,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn merge_genre_table_checks_its_pairs() {
        let pair = |a: &str, b: &str| (a.to_string(), b.to_string());
        let map = merge_table(&[pair("whirl", "modern"), pair("Popping", "break")]).unwrap();
        assert_eq!(map.get("whirl").map(String::as_str), Some("modern"));
        assert_eq!(map.get("popping").map(String::as_str), Some("break"));
        for bad in [
            vec![pair("whirl", "whirl")],
            vec![pair("whirl", "modern"), pair("whirl", "break")],
            vec![pair("whirl", "modern"), pair("modern", "break")],
        ] {
            let e = merge_table(&bad).unwrap_err().to_string();
            assert!(e.contains("--merge-genre"), "{e}");
        }
    }
}
