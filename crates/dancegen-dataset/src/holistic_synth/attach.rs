//! `dataset build --holistic`: gives every clip of a built data set its synthetic fingers and
//! face, from the clip's real body (as written, on the floor) and its music features.
//!
//! Each clip gets `[held_out/]holistic/<clip>.npz` (manifest field `holistic`) holding
//! - `hands` `(T, 30, 3)` float32: local axis-angle of SMPL-H joints 22–51 (left hand, then
//!   right hand; [`super::hand_poses`] gives the axes);
//! - `face` `(T, 52)` float32: ARKit weights in [0, 1], `dancegen_motion::face::ARKIT_NAMES`
//!   order;
//! - `hand_targets` `(T, 2)` int64: the vocabulary pose each hand is heading for;
//! - `valence` `()` float32: the clip's mood.
//!
//! Held-out clips get theirs too, so hand and face reconstruction can be measured on held-out
//! synthetic data. The seed of a clip is the build seed mixed with its name, so a rebuild is
//! identical and a mirror image gets its own hands.

use std::path::Path;

use dancegen_formats::dispatch::{LoadedMotion, load_motion_file};
use dancegen_io::NpyData;
use dancegen_motion::face::ARKIT_COUNT;
use dancegen_music::features::EDGE35_DIM;
use rayon::prelude::*;

use super::hand_poses::HAND_JOINTS;
use super::{FaceInputs, SynthInputs, synthesize_face, synthesize_hands};
use crate::error::DatasetError;
use crate::manifest::ClipEntry;

/// EDGE-35 columns: onset envelope, chroma_cens, beat one-hot.
const ONSET: usize = 0;
const CHROMA: std::ops::Range<usize> = 21..33;
const BEAT: usize = 34;

/// FNV-1a of a clip name, mixed into the build seed.
fn name_hash(name: &str) -> u64 {
    name.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| {
        (h ^ b as u64).wrapping_mul(0x0100_0000_01b3)
    })
}

/// Synthesises and writes the hands and face of every clip (see the module documentation).
pub fn attach(out: &Path, clips: &mut [ClipEntry], seed: u64) -> Result<(), DatasetError> {
    for d in ["holistic", "held_out/holistic"] {
        let p = out.join(d);
        std::fs::create_dir_all(&p)
            .map_err(|e| DatasetError::input(&p, format!("cannot create directory: {e}")))?;
    }
    let rels: Vec<Result<String, DatasetError>> = clips
        .par_iter()
        .map(|c| attach_one(out, c, seed ^ name_hash(&c.name)))
        .collect();
    for (c, r) in clips.iter_mut().zip(rels) {
        c.holistic = Some(r?);
    }
    Ok(())
}

fn attach_one(out: &Path, c: &ClipEntry, seed: u64) -> Result<String, DatasetError> {
    let motion_path = out.join(&c.motion);
    let body = match load_motion_file(&motion_path)? {
        LoadedMotion::Smpl(m) => m,
        other => {
            return Err(DatasetError::input(
                &motion_path,
                format!("a {} has no SMPL body to give hands to", other.kind()),
            ));
        }
    };
    let joints = body
        .joints_world()
        .map_err(|e| DatasetError::input(&motion_path, e))?;
    let music_path = out.join(&c.music);
    let music = dancegen_io::npy::read_npy(&music_path)
        .map_err(|e| DatasetError::input(&music_path, e.reason))?;
    let t = body.frames();
    if music.shape != [t, EDGE35_DIM] {
        return Err(DatasetError::input(
            &music_path,
            format!(
                "music shape {:?}, expected [{t}, {EDGE35_DIM}]",
                music.shape
            ),
        ));
    }
    let col = |k: usize| -> Vec<f32> {
        (0..t)
            .map(|r| music.data[r * EDGE35_DIM + k] as f32)
            .collect()
    };
    let onset = col(ONSET);
    let chroma: Vec<f32> = (0..t)
        .flat_map(|r| CHROMA.map(move |k| (r, k)))
        .map(|(r, k)| music.data[r * EDGE35_DIM + k] as f32)
        .collect();
    let beats: Vec<usize> = (0..t)
        .filter(|&r| music.data[r * EDGE35_DIM + BEAT] > 0.5)
        .collect();
    let fps = body.fps;
    let hands = synthesize_hands(&SynthInputs {
        fps,
        joints: &joints,
        onset: &onset,
        beats: &beats,
        seed,
    });
    let face = synthesize_face(&FaceInputs {
        fps,
        frames: t,
        onset: &onset,
        chroma: &chroma,
        beats: &beats,
        seed,
    });
    let targets: Vec<i64> = hands.targets.iter().map(|&p| p as i64).collect();
    let prefix = if c.motion.starts_with("held_out/") {
        "held_out/"
    } else {
        ""
    };
    let rel = format!("{prefix}holistic/{}.npz", c.name);
    dancegen_io::npz::write_npz(
        &out.join(&rel),
        &[
            (
                "hands",
                &[t, 2 * HAND_JOINTS, 3],
                NpyData::F32(&hands.axis_angles),
            ),
            ("face", &[t, ARKIT_COUNT], NpyData::F32(&face.weights)),
            ("hand_targets", &[t, 2], NpyData::I64(&targets)),
            ("valence", &[], NpyData::F32(&[face.valence])),
        ],
    )?;
    Ok(rel)
}
