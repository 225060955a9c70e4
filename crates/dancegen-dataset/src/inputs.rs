//! Reading the build's inputs: the motion files named on the command line, the hold-out
//! names checked against them, and every song analysed once.

use std::collections::BTreeSet;
use std::path::PathBuf;

use rayon::prelude::*;

use crate::error::DatasetError;
use crate::options::Progress;
use crate::song::{Song, stem};

/// Motion files named by `inputs` (directories: their motion files, sorted).
pub(crate) fn expand_motion_inputs(inputs: &[PathBuf]) -> Result<Vec<PathBuf>, DatasetError> {
    let mut out = Vec::new();
    for p in inputs {
        if p.is_dir() {
            let mut v: Vec<PathBuf> = std::fs::read_dir(p)
                .map_err(|e| DatasetError::input(p, e))?
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|f| {
                    f.extension()
                        .and_then(|e| e.to_str())
                        .is_some_and(|e| ["pkl", "bvh", "npz", "npy"].contains(&e))
                })
                .collect();
            v.sort();
            if v.is_empty() {
                return Err(DatasetError::input(p, "directory holds no motion files"));
            }
            out.extend(v);
        } else {
            out.push(p.clone());
        }
    }
    Ok(out)
}

/// Fails on hold-out names that match nothing: a typo would silently leak test data into
/// training.
pub(crate) fn check_hold_out(
    hold_out: &[String],
    known: &BTreeSet<String>,
) -> Result<(), DatasetError> {
    let unknown: Vec<&String> = hold_out.iter().filter(|h| !known.contains(*h)).collect();
    if unknown.is_empty() {
        Ok(())
    } else {
        Err(DatasetError::Options(format!(
            "--hold-out {} matches no input (give motion or song file names without extension)",
            unknown
                .iter()
                .map(|s| s.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        )))
    }
}

/// Analyses every song once (in parallel).
pub(crate) fn analyse_songs(
    paths: &[PathBuf],
    progress: &dyn Progress,
) -> Result<Vec<Song>, DatasetError> {
    progress.stage("analysing songs", paths.len());
    paths
        .par_iter()
        .map(|p| {
            let s = Song::analyse(p);
            progress.step(&stem(p));
            s
        })
        .collect()
}
