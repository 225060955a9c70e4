//! Finished clips written to the data set folder (motion, music, a partner), and the clips of parallel jobs gathered in job order.

use std::path::{Path, PathBuf};

use dancegen_formats::dispatch::{ConvertOptions, LoadedMotion, NpzStyle, save_motion_file};
use dancegen_motion::repr::motion::{POSE_DIMS, SmplMotion};
use dancegen_music::features::EDGE35_DIM;

use crate::error::DatasetError;
use crate::manifest::{ClipEntry, PairingKind, WarpReport};
use crate::song::Song;
use crate::units::{MotionUnit, world_joints};
use crate::{FPS, MIN_CLIP_FRAMES};

/// The clips of parallel jobs in job order, or the error of the first failing job in job order
/// (so the message does not depend on which thread finished first).
pub(crate) fn gather_clips<C: IntoIterator<Item = ClipEntry>>(
    results: Vec<Result<C, DatasetError>>,
) -> Result<Vec<ClipEntry>, DatasetError> {
    let mut clips = Vec::new();
    for r in results {
        clips.extend(r?);
    }
    Ok(clips)
}

/// A finished clip before it is written.
pub(crate) struct ClipData {
    pub(crate) name: String,
    pub(crate) genre: String,
    pub(crate) source_motion: PathBuf,
    pub(crate) source_song: PathBuf,
    pub(crate) start_frame: usize,
    pub(crate) motion: SmplMotion,
    pub(crate) music: Vec<f32>,
    pub(crate) pairing: PairingKind,
    pub(crate) warp: Option<WarpReport>,
    pub(crate) held_out: bool,
}

/// Writes one clip's motion and music and returns its manifest entry.
pub(crate) fn write_clip(out: &Path, c: &ClipData) -> Result<ClipEntry, DatasetError> {
    let frames = c.motion.frames();
    debug_assert_eq!(c.music.len(), frames * EDGE35_DIM);
    let prefix = if c.held_out { "held_out/" } else { "" };
    let motion_rel = format!("{prefix}motion/{}.npz", c.name);
    let music_rel = format!("{prefix}music/{}.npy", c.name);
    let motion_path = out.join(&motion_rel);
    let opts = ConvertOptions {
        npz_style: NpzStyle::Amass,
        ..Default::default()
    };
    // Every clip stands on the floor y = 0 (where its resting feet are), the convention the
    // solo model's foot features and contact thresholds assume.
    let mut motion = c.motion.clone();
    motion
        .put_feet_on_floor()
        .map_err(|e| DatasetError::input(&motion_path, e))?;
    save_motion_file(&motion_path, &LoadedMotion::Smpl(motion), &opts)?;
    dancegen_io::write_npy_f32(&out.join(&music_rel), &[frames, EDGE35_DIM], &c.music)?;
    let fps = f64::from(FPS);
    Ok(ClipEntry {
        name: c.name.clone(),
        motion: motion_rel,
        music: music_rel,
        genre: c.genre.clone(),
        source_motion: c.source_motion.display().to_string(),
        source_song: c.source_song.display().to_string(),
        song_start_s: c.start_frame as f64 / fps,
        song_end_s: (c.start_frame + frames) as f64 / fps,
        frames,
        pairing: c.pairing,
        warp: c.warp.clone(),
        leader: None,
        group: None,
        holistic: None,
    })
}

/// Writes one role assignment of a couple: `follower` as the clip's motion, `leader` under
/// `leader/`, both lowered by one shared floor height (the partners stand on the same floor).
#[allow(clippy::too_many_arguments)]
pub(crate) fn write_couple_clip(
    out: &Path,
    name: &str,
    unit: &MotionUnit,
    song: &Path,
    start_frame: usize,
    follower: &SmplMotion,
    leader: &SmplMotion,
    music: Vec<f32>,
    warp: WarpReport,
    held_out: bool,
) -> Result<ClipEntry, DatasetError> {
    use dancegen_motion::repr::motion::GroundMode;
    let frames = follower.frames();
    let prefix = if held_out { "held_out/" } else { "" };
    let motion_rel = format!("{prefix}motion/{name}.npz");
    let leader_rel = format!("{prefix}leader/{name}.npz");
    let music_rel = format!("{prefix}music/{name}.npy");
    let mut both = world_joints(follower, &unit.source)?;
    both.extend(world_joints(leader, &unit.source)?);
    let both: Vec<f32> = both.into_iter().map(|v| v as f32).collect();
    // One floor for both (they dance on the same one): where their resting feet are.
    let floor = dancegen_motion::repr::motion::planted_floor_height(&both, follower.fps)
        .unwrap_or_else(|| SmplMotion::ground_height(&both, GroundMode::SupportFeet));
    let lowered = |m: &SmplMotion| {
        let mut m = m.clone();
        for p in m.trans.chunks_exact_mut(3) {
            p[1] -= floor;
        }
        LoadedMotion::Smpl(m)
    };
    let opts = ConvertOptions {
        npz_style: NpzStyle::Amass,
        ..Default::default()
    };
    save_motion_file(&out.join(&motion_rel), &lowered(follower), &opts)?;
    save_motion_file(&out.join(&leader_rel), &lowered(leader), &opts)?;
    dancegen_io::write_npy_f32(&out.join(&music_rel), &[frames, EDGE35_DIM], &music)?;
    let fps = f64::from(FPS);
    Ok(ClipEntry {
        name: name.to_string(),
        motion: motion_rel,
        music: music_rel,
        genre: unit.genre.clone(),
        source_motion: unit.source.display().to_string(),
        source_song: song.display().to_string(),
        song_start_s: start_frame as f64 / fps,
        song_end_s: (start_frame + frames) as f64 / fps,
        frames,
        pairing: PairingKind::PseudoBeatWarp,
        warp: Some(warp),
        leader: Some(leader_rel),
        group: None,
        holistic: None,
    })
}

/// Creates the data set's folders under `out`.
pub(crate) fn create_dirs(out: &Path) -> Result<(), DatasetError> {
    for d in ["motion", "music", "held_out/motion", "held_out/music"] {
        let p = out.join(d);
        std::fs::create_dir_all(&p)
            .map_err(|e| DatasetError::input(&p, format!("cannot create directory: {e}")))?;
    }
    Ok(())
}

/// A clip of a data set's own pairing: the first `min(motion, song)` frames of both.
pub(crate) fn original_clip(
    unit: &MotionUnit,
    song: &Song,
    held_out: bool,
) -> Result<Option<ClipData>, DatasetError> {
    let n = unit.motion.frames().min(song.frames());
    if n < MIN_CLIP_FRAMES {
        tracing::warn!(
            "{}: only {n} paired frames with {}, skipped",
            unit.source.display(),
            song.path.display()
        );
        return Ok(None);
    }
    let m = &unit.motion;
    Ok(Some(ClipData {
        name: unit.name.clone(),
        genre: unit.genre.clone(),
        source_motion: unit.source.clone(),
        source_song: song.path.clone(),
        start_frame: 0,
        motion: SmplMotion {
            fps: m.fps,
            poses: m.poses[..n * POSE_DIMS].to_vec(),
            trans: m.trans[..n * 3].to_vec(),
        },
        music: song.rows(0, n),
        pairing: PairingKind::Original,
        warp: None,
        held_out,
    }))
}
