//! The published data sets' own pairings (no warp).
//!
//! **AIST++** (anchors.md C.1), under a root directory:
//! - motions: `motions/*.pkl` (the annotation release; without keypoints the `.pkl` files may
//!   also sit directly in the root), SMPL at 60 fps, taken to 30 fps by keeping every 2nd frame
//!   (EDGE `data_stride`);
//! - music: `wav/<music id>.wav`, the music id being the 5th field of the sequence name
//!   (`gBR_sBM_cAll_d04_mBR2_ch08` → `mBR2`); other audio extensions are accepted too;
//! - `splits/crossmodal_test.txt` → held out, `ignore_list.txt` (root or `splits/`) → skipped;
//! - genre from the name's first field.
//!
//! **FineDance** (anchors.md C.3), under a root directory:
//! - `motion/*.npy` `(T, 315)` at 30 fps, `music_wav/<same stem>.wav`,
//!   `label_json/<same stem>.json` whose `style2` is the genre
//!   (`li-ronghui/LODGE:dld/data/FineDance_dataset.py`, `music2genre`);
//! - the 20-song test split → held out; LODGE's `ignor_list` → skipped.
//!
//! Both: clip = the first `min(motion, music)` frames of each, as EDGE and LODGE truncate.
//! `--hold-out` stems add to the held-out split; `--genre` overrides the data set's genres.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use rayon::prelude::*;

use crate::clips::{create_dirs, gather_clips, original_clip, write_clip};
use crate::error::DatasetError;
use crate::genre;
use crate::inputs::{analyse_songs, check_hold_out};
use crate::manifest::ClipEntry;
use crate::options::{BuildOptions, Pairing, Progress};
use crate::song::stem;
use crate::units::load_units;

/// FineDance's test split (`li-ronghui/LODGE:infer_lodge.py`; anchors.md C.3).
pub const FINEDANCE_TEST: [&str; 20] = [
    "063", "132", "143", "036", "098", "198", "130", "012", "211", "193", "179", "065", "137",
    "161", "092", "120", "037", "109", "204", "144",
];

/// Sequences LODGE's FineDance loader skips (`ignor_list` in
/// `li-ronghui/LODGE:dld/data/FineDance_dataset.py`).
pub const FINEDANCE_IGNORE: [&str; 9] = [
    "116", "117", "118", "119", "120", "121", "122", "123", "202",
];

const AUDIO_EXTENSIONS: [&str; 6] = ["wav", "ogg", "flac", "mp3", "m4a", "aiff"];

/// One motion file with its song, before loading.
#[derive(Clone, Debug)]
struct Pair {
    motion: PathBuf,
    song: PathBuf,
    genre: String,
    held_out: bool,
}

/// The AIST++ music id of a sequence name (`gBR_sBM_cAll_d04_mBR2_ch08` → `mBR2`).
pub fn aistpp_music_id(seq: &str) -> Option<&str> {
    seq.split('_').find(|f| {
        f.len() == 4 && f.starts_with('m') && f[1..3].chars().all(|c| c.is_ascii_uppercase())
    })
}

fn files_with_ext(dir: &Path, exts: &[&str]) -> Result<Vec<PathBuf>, DatasetError> {
    let rd = std::fs::read_dir(dir).map_err(|e| DatasetError::input(dir, e))?;
    let mut v: Vec<PathBuf> = rd
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.is_file()
                && p.extension()
                    .and_then(|e| e.to_str())
                    .is_some_and(|e| exts.contains(&e.to_ascii_lowercase().as_str()))
        })
        .collect();
    v.sort();
    Ok(v)
}

/// `dir/<name>.<audio ext>`, preferring `.wav`.
fn find_audio(dir: &Path, name: &str) -> Result<PathBuf, DatasetError> {
    for ext in AUDIO_EXTENSIONS {
        let p = dir.join(format!("{name}.{ext}"));
        if p.is_file() {
            return Ok(p);
        }
    }
    Err(DatasetError::input(
        dir.join(format!("{name}.wav")),
        "music file not found (also tried .ogg, .flac, .mp3, .m4a, .aiff)",
    ))
}

/// Names listed one per line (blank lines and surrounding space ignored); empty if absent.
fn read_list(path: &Path) -> Result<BTreeSet<String>, DatasetError> {
    if !path.exists() {
        return Ok(BTreeSet::new());
    }
    let text = std::fs::read_to_string(path).map_err(|e| DatasetError::input(path, e))?;
    Ok(text
        .lines()
        .map(|l| l.trim())
        .filter(|l| !l.is_empty())
        .map(|l| l.trim_end_matches(".pkl").to_string())
        .collect())
}

fn root_of(opts: &BuildOptions) -> Result<&Path, DatasetError> {
    let root = opts.root.as_deref().ok_or_else(|| {
        DatasetError::Options("--pairing aistpp/finedance needs --root DIR".into())
    })?;
    if !root.is_dir() {
        return Err(DatasetError::input(
            root,
            "data set root is not a directory",
        ));
    }
    if !opts.motions.is_empty() || !opts.music.is_empty() {
        return Err(DatasetError::Options(
            "--motion/--music are for --pairing pseudo; the layouts find their files under --root"
                .into(),
        ));
    }
    Ok(root)
}

fn aistpp_pairs(opts: &BuildOptions) -> Result<Vec<Pair>, DatasetError> {
    let root = root_of(opts)?;
    let motion_dir = if root.join("motions").is_dir() {
        root.join("motions")
    } else {
        root.to_path_buf()
    };
    let motions = files_with_ext(&motion_dir, &["pkl"])?;
    if motions.is_empty() {
        return Err(DatasetError::input(
            &motion_dir,
            "no AIST++ motion .pkl files",
        ));
    }
    let music_dir = ["wav", "music", "audio"]
        .iter()
        .map(|d| root.join(d))
        .find(|d| d.is_dir())
        .unwrap_or_else(|| root.to_path_buf());
    let test = read_list(&root.join("splits/crossmodal_test.txt"))?;
    let mut ignore = read_list(&root.join("ignore_list.txt"))?;
    ignore.extend(read_list(&root.join("splits/ignore_list.txt"))?);
    let mut pairs = Vec::new();
    for m in motions {
        let seq = stem(&m);
        if ignore.contains(&seq) {
            tracing::info!("{}: in the AIST++ ignore list, skipped", m.display());
            continue;
        }
        let id = aistpp_music_id(&seq).ok_or_else(|| {
            DatasetError::input(&m, "no AIST++ music id (mXX0) in the sequence name")
        })?;
        pairs.push(Pair {
            song: find_audio(&music_dir, id)?,
            genre: genre::genre_from_name(&seq),
            held_out: test.contains(&seq),
            motion: m,
        });
    }
    Ok(pairs)
}

/// The genre of a FineDance `label_json` file: `style2` (what LODGE reads), else `style1`,
/// `style` or `genre`.
pub fn finedance_label(path: &Path) -> Result<String, DatasetError> {
    let text = std::fs::read_to_string(path).map_err(|e| DatasetError::input(path, e))?;
    let v: serde_json::Value = serde_json::from_str(&text)
        .map_err(|e| DatasetError::input(path, format!("not JSON: {e}")))?;
    ["style2", "style1", "style", "genre"]
        .iter()
        .find_map(|k| v.get(k).and_then(|g| g.as_str()))
        .map(genre::finedance_genre)
        .ok_or_else(|| DatasetError::input(path, "no genre (style2) in the label"))
}

fn finedance_pairs(opts: &BuildOptions) -> Result<Vec<Pair>, DatasetError> {
    let root = root_of(opts)?;
    let motion_dir = root.join("motion");
    let motions = files_with_ext(&motion_dir, &["npy"])?;
    if motions.is_empty() {
        return Err(DatasetError::input(
            &motion_dir,
            "no FineDance motion .npy files",
        ));
    }
    let music_dir = root.join("music_wav");
    let mut pairs = Vec::new();
    for m in motions {
        let s = stem(&m);
        if FINEDANCE_IGNORE.contains(&s.as_str()) {
            tracing::info!("{}: in LODGE's FineDance ignore list, skipped", m.display());
            continue;
        }
        let label = root.join("label_json").join(format!("{s}.json"));
        let genre = if label.exists() {
            finedance_label(&label)?
        } else {
            tracing::warn!("{}: no label, genre unknown", label.display());
            "unknown".to_string()
        };
        pairs.push(Pair {
            song: find_audio(&music_dir, &s)?,
            genre,
            held_out: FINEDANCE_TEST.contains(&s.as_str()),
            motion: m,
        });
    }
    Ok(pairs)
}

/// Builds an AIST++ or FineDance data set (module docs).
pub(crate) fn build_layout(
    opts: &BuildOptions,
    progress: &dyn Progress,
) -> Result<Vec<ClipEntry>, DatasetError> {
    let mut pairs = match opts.pairing {
        Pairing::Aistpp => aistpp_pairs(opts)?,
        Pairing::FineDance => finedance_pairs(opts)?,
        Pairing::Pseudo | Pairing::Duet | Pairing::Dd100 | Pairing::Group => {
            unreachable!("build_layout is only called for the layouts")
        }
    };
    let known: BTreeSet<String> = pairs
        .iter()
        .flat_map(|p| [stem(&p.motion), stem(&p.song)])
        .collect();
    check_hold_out(&opts.hold_out, &known)?;
    for p in &mut pairs {
        if opts
            .hold_out
            .iter()
            .any(|h| *h == stem(&p.motion) || *h == stem(&p.song))
        {
            p.held_out = true;
        }
        if let Some(g) = &opts.genre {
            p.genre = genre::normalize(g);
        }
    }
    let song_paths: Vec<PathBuf> = pairs
        .iter()
        .map(|p| p.song.clone())
        .collect::<BTreeSet<_>>()
        .into_iter()
        .collect();
    let songs = analyse_songs(&song_paths, progress)?;
    let by_path: BTreeMap<&Path, usize> = songs
        .iter()
        .enumerate()
        .map(|(i, s)| (s.path.as_path(), i))
        .collect();
    create_dirs(&opts.out)?;
    progress.stage("pairing motions", pairs.len());
    let results: Vec<Result<Vec<ClipEntry>, DatasetError>> = pairs
        .par_iter()
        .map(|p| {
            let song = &songs[by_path[p.song.as_path()]];
            let mut out = Vec::new();
            for unit in load_units(&p.motion, &p.genre, &crate::rates::SourceRates::default())? {
                if let Some(c) = original_clip(&unit, song, p.held_out)? {
                    out.push(write_clip(&opts.out, &c)?);
                }
            }
            progress.step(&stem(&p.motion));
            Ok(out)
        })
        .collect();
    gather_clips(results)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn music_ids() {
        assert_eq!(aistpp_music_id("gBR_sBM_cAll_d04_mBR2_ch08"), Some("mBR2"));
        assert_eq!(aistpp_music_id("gJS_sFM_cAll_d02_mJS4_ch09"), Some("mJS4"));
        assert_eq!(aistpp_music_id("take_01"), None);
    }
}
