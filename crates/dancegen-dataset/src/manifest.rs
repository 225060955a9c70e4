//! `OUT/manifest.json`: the index a training config reads.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::error::DatasetError;

/// Version of the manifest layout.
pub const MANIFEST_VERSION: u32 = 1;

/// How a clip's motion and music were put together.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PairingKind {
    /// Motion time-warped onto a song's beats ([`crate::warp`]): a documented pseudo-pairing,
    /// not ground truth.
    PseudoBeatWarp,
    /// The data set's own pairing (AIST++, FineDance).
    Original,
}

/// Per-clip statistics of the beat warp. Rates are `Δmusic / Δmotion` of the map's pieces
/// (playback speed = 1 / rate); BAS is Bailando's beat-align score of the unwarped motion
/// (same song start) and of the warped motion against the song's beats.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct WarpReport {
    pub min_rate: f64,
    pub max_rate: f64,
    pub matched_beats: usize,
    pub motion_beats: usize,
    pub bas_before: Option<f64>,
    pub bas_after: Option<f64>,
}

/// One clip of the manifest.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ClipEntry {
    pub name: String,
    /// Motion file, relative to the manifest's directory.
    pub motion: String,
    /// Music feature file, relative to the manifest's directory.
    pub music: String,
    pub genre: String,
    pub source_motion: String,
    pub source_song: String,
    pub song_start_s: f64,
    pub song_end_s: f64,
    pub frames: usize,
    pub pairing: PairingKind,
    pub warp: Option<WarpReport>,
    /// Duet data sets: the partner this clip's dancer follows (motion file, relative to the
    /// manifest's directory).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub leader: Option<String>,
    /// Group data sets: the composition's labels; `motion` is then a directory of
    /// `dancer_<k>.npz` files.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub group: Option<GroupLabels>,
    /// Holistic data sets (`--holistic`): the clip's **synthetic** fingers and face
    /// (`crate::holistic_synth::attach`), relative to the manifest's directory.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub holistic: Option<String>,
}

/// What a composed group sample is made of (`--pairing group`, [`crate::group`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GroupLabels {
    /// Number of dancers `N` (files `dancer_0.npz` … `dancer_{N-1}.npz`).
    pub dancers: usize,
    /// Dancer index pairs recorded together (a real couple); exempt from the collision rule.
    pub partners: Vec<[usize; 2]>,
    /// Dancer indices left to right as the audience sees them (ascending x) at the first frame.
    pub start_order: Vec<usize>,
    /// The same at the last frame.
    pub end_order: Vec<usize>,
    /// Formation shapes in the order they are held.
    pub shapes: Vec<String>,
    /// Transitions between them (`direct`, `lateral_swap`, `upstage_pass`).
    pub transitions: Vec<String>,
    /// `unison`, `canon` or `contrast`.
    pub timing: String,
    /// `(N, T, 2)` float32 root `[x, z]` per dancer and frame (metres), relative to the
    /// manifest's directory.
    pub trajectories: String,
    /// Per dancer: the source take's file stem (`_mirror` appended when mirrored).
    pub sources: Vec<String>,
}

/// `manifest.json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Manifest {
    pub version: u32,
    pub fps: u32,
    /// Sorted, unique genre names of the clips.
    pub genres: Vec<String>,
    pub clips: Vec<ClipEntry>,
    /// Names of the clips kept out of training (stored under `held_out/`).
    pub held_out: Vec<String>,
    /// Every `--motion` take as read: its rate (given or from its header), kinematic tempo
    /// and floor ([`crate::takes`]). Empty for data set layouts and older manifests.
    #[serde(default)]
    pub takes: Vec<crate::takes::TakeEntry>,
}

impl Manifest {
    /// Reads a manifest written by [`crate::build::build`].
    pub fn read(path: &Path) -> Result<Manifest, DatasetError> {
        let text = std::fs::read_to_string(path).map_err(|e| DatasetError::input(path, e))?;
        let m: Manifest = serde_json::from_str(&text)
            .map_err(|e| DatasetError::input(path, format!("not a dancegen manifest: {e}")))?;
        if m.version != MANIFEST_VERSION {
            return Err(DatasetError::input(
                path,
                format!(
                    "manifest version {} (this build reads {MANIFEST_VERSION})",
                    m.version
                ),
            ));
        }
        Ok(m)
    }

    /// Writes the manifest atomically.
    pub fn write(&self, path: &Path) -> Result<(), DatasetError> {
        dancegen_io::write_atomic(path, |w| {
            serde_json::to_writer_pretty(&mut *w, self).map_err(std::io::Error::other)?;
            w.write_all(b"\n")
        })?;
        Ok(())
    }
}
