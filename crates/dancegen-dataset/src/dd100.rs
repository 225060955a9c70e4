//! DD100, the duet data set of Duolando (Siyao et al., ICLR 2024) that ReactDance trains on, in
//! the layout of Duolando's loader (`lisiyao21/Duolando`, `DD100lfAll`): under a root,
//!
//! ```text
//! motion/rotmat/{train,test}/<take>_00.npy   follower, (T, 3 + 55·9): root translation, then
//! motion/rotmat/{train,test}/<take>_01.npy   leader      55 SMPL-X rotation matrices (row-major)
//! music/<any>/{train,test}/<take>.<audio>    the take's song (wav, mp3, ogg, flac, ...)
//! ```
//!
//! at 30 fps, metres, Y-up. SMPL-X body joints 0–21 are SMPL's; SMPL's hand joints 22/23 have
//! no SMPL-X counterpart (SMPL-X has fingers there) and are left at rest. `test` takes are held
//! out. Each take gives one clip with the data set's own roles and no warp: the first
//! `min(motion, music)` frames (as EDGE and LODGE truncate).
//!
//! This reader follows the public loader; it has not been run on the real DD100 files (they are
//! not available here), so the layout assumptions above are stated rather than verified. Duolando
//! also ships `pos3d/` joint positions and its own music features; neither is read.

use std::path::{Path, PathBuf};

use dancegen_motion::repr::motion::{POSE_DIMS, SmplMotion};
use dancegen_motion::rotation::Mat3;
use rayon::prelude::*;

use crate::MIN_CLIP_FRAMES;
use crate::clips::{create_dirs, gather_clips, write_couple_clip};
use crate::error::DatasetError;
use crate::inputs::{analyse_songs, check_hold_out};
use crate::manifest::{ClipEntry, WarpReport};
use crate::options::{BuildOptions, Progress};
use crate::song::stem;
use crate::units::MotionUnit;

/// Values per frame of a rotmat file.
pub const ROTMAT_DIMS: usize = 3 + 55 * 9;
/// SMPL-X body joints shared with SMPL 24.
const BODY_JOINTS: usize = 22;
const AUDIO_EXTENSIONS: [&str; 6] = ["wav", "mp3", "ogg", "flac", "m4a", "aiff"];
const SPLITS: [&str; 2] = ["train", "test"];

/// One DD100 take.
struct Take {
    name: String,
    follower: PathBuf,
    leader: PathBuf,
    song: PathBuf,
    held_out: bool,
}

/// A rotmat file as SMPL 24 at 30 fps.
pub fn read_rotmat(path: &Path) -> Result<SmplMotion, DatasetError> {
    let a = dancegen_io::read_npy(path).map_err(|e| DatasetError::input(path, e))?;
    let t = match a.shape.as_slice() {
        [t, d] if *d == ROTMAT_DIMS => *t,
        s => {
            return Err(DatasetError::input(
                path,
                format!(
                    "shape {s:?}, expected (T, {ROTMAT_DIMS}) = translation + 55 rotation matrices"
                ),
            ));
        }
    };
    if a.data.iter().any(|v| !v.is_finite()) {
        return Err(DatasetError::input(path, "holds NaN or infinite values"));
    }
    let mut poses = vec![0f32; t * POSE_DIMS];
    let mut trans = Vec::with_capacity(t * 3);
    for (f, row) in a.data.chunks_exact(ROTMAT_DIMS).enumerate() {
        trans.extend(row[..3].iter().map(|&v| v as f32));
        for j in 0..BODY_JOINTS {
            let m = &row[3 + 9 * j..3 + 9 * j + 9];
            let r = Mat3([[m[0], m[1], m[2]], [m[3], m[4], m[5]], [m[6], m[7], m[8]]]);
            let aa = r.to_axis_angle();
            poses[f * POSE_DIMS + 3 * j..f * POSE_DIMS + 3 * j + 3]
                .copy_from_slice(&aa.map(|v| v as f32));
        }
    }
    SmplMotion::new(30.0, poses, trans).map_err(|e| DatasetError::input(path, e))
}

fn find_song(root: &Path, split: &str, take: &str) -> Option<PathBuf> {
    let music = root.join("music");
    let mut dirs: Vec<PathBuf> = std::fs::read_dir(&music)
        .ok()?
        .filter_map(|e| e.ok().map(|e| e.path().join(split)))
        .filter(|d| d.is_dir())
        .collect();
    dirs.sort();
    dirs.iter().find_map(|d| {
        AUDIO_EXTENSIONS
            .iter()
            .map(|ext| d.join(format!("{take}.{ext}")))
            .find(|p| p.is_file())
    })
}

fn takes(root: &Path) -> Result<Vec<Take>, DatasetError> {
    let mut out = Vec::new();
    for split in SPLITS {
        let dir = root.join("motion/rotmat").join(split);
        if !dir.is_dir() {
            continue;
        }
        let mut followers: Vec<PathBuf> = std::fs::read_dir(&dir)
            .map_err(|e| DatasetError::input(&dir, e))?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.to_string_lossy().ends_with("_00.npy"))
            .collect();
        followers.sort();
        for follower in followers {
            let s = stem(&follower);
            let take = s.trim_end_matches("_00").to_string();
            let leader = dir.join(format!("{take}_01.npy"));
            if !leader.is_file() {
                return Err(DatasetError::input(
                    &leader,
                    "the take's leader file is missing",
                ));
            }
            let song = find_song(root, split, &take).ok_or_else(|| {
                DatasetError::input(
                    root.join("music/<any>")
                        .join(split)
                        .join(format!("{take}.wav")),
                    "the take's music file is missing",
                )
            })?;
            out.push(Take {
                name: take,
                follower,
                leader,
                song,
                held_out: split == "test",
            });
        }
    }
    if out.is_empty() {
        return Err(DatasetError::input(
            root.join("motion/rotmat"),
            "no DD100 takes (<take>_00.npy / <take>_01.npy under train/ or test/)",
        ));
    }
    Ok(out)
}

/// Builds a duet data set from a DD100 root (module docs).
pub(crate) fn build_dd100(
    opts: &BuildOptions,
    progress: &dyn Progress,
) -> Result<Vec<ClipEntry>, DatasetError> {
    let root = opts
        .root
        .as_deref()
        .ok_or_else(|| DatasetError::Options("--pairing dd100 needs --root DIR".into()))?;
    let mut takes = takes(root)?;
    let known = takes.iter().map(|t| t.name.clone()).collect();
    check_hold_out(&opts.hold_out, &known)?;
    for t in &mut takes {
        t.held_out |= opts.hold_out.contains(&t.name);
    }
    let songs: Vec<PathBuf> = takes.iter().map(|t| t.song.clone()).collect();
    let analysed = analyse_songs(&songs, progress)?;
    create_dirs(&opts.out)?;
    for d in ["leader", "held_out/leader"] {
        let p = opts.out.join(d);
        std::fs::create_dir_all(&p).map_err(|e| DatasetError::input(&p, e))?;
    }
    let genre = opts.genre.clone().unwrap_or_else(|| "dd100".into());
    progress.stage("reading takes", takes.len());
    let results: Vec<Result<Option<ClipEntry>, DatasetError>> = takes
        .par_iter()
        .zip(&analysed)
        .map(|(t, song)| {
            let follower = read_rotmat(&t.follower)?;
            let leader = read_rotmat(&t.leader)?;
            let n = follower.frames().min(leader.frames()).min(song.frames());
            progress.step(&t.name);
            if n < MIN_CLIP_FRAMES {
                tracing::warn!("{}: only {n} paired frames, skipped", t.follower.display());
                return Ok(None);
            }
            let cut = |m: &SmplMotion| SmplMotion {
                fps: m.fps,
                poses: m.poses[..n * POSE_DIMS].to_vec(),
                trans: m.trans[..n * 3].to_vec(),
            };
            let unit = MotionUnit {
                name: t.name.clone(),
                stem: t.name.clone(),
                source: t.follower.clone(),
                genre: genre.clone(),
                motion: cut(&follower),
                source_fps: f64::from(follower.fps),
                rate_from: crate::takes::RateFrom::Header,
            };
            let no_warp = WarpReport {
                min_rate: 1.0,
                max_rate: 1.0,
                matched_beats: 0,
                motion_beats: 0,
                bas_before: None,
                bas_after: None,
            };
            write_couple_clip(
                &opts.out,
                &t.name,
                &unit,
                &t.song,
                0,
                &unit.motion,
                &cut(&leader),
                song.rows(0, n),
                no_warp,
                t.held_out,
            )
            .map(Some)
        })
        .collect();
    gather_clips(results)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rotmat_rows_become_smpl_axis_angle() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("take_00.npy");
        let t = 3;
        let mut v = vec![0f32; t * ROTMAT_DIMS];
        for f in 0..t {
            let row = &mut v[f * ROTMAT_DIMS..(f + 1) * ROTMAT_DIMS];
            row[..3].copy_from_slice(&[0.1, 0.9, f as f32]);
            for j in 0..55 {
                // 90° about +Y for the knees (4, 5), identity elsewhere.
                let m: [f32; 9] = if j == 4 || j == 5 {
                    [0.0, 0.0, 1.0, 0.0, 1.0, 0.0, -1.0, 0.0, 0.0]
                } else {
                    [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]
                };
                row[3 + 9 * j..3 + 9 * j + 9].copy_from_slice(&m);
            }
        }
        dancegen_io::write_npy_f32(&p, &[t, ROTMAT_DIMS], &v).unwrap();
        let m = read_rotmat(&p).unwrap();
        assert_eq!(m.frames(), 3);
        assert_eq!(&m.trans[6..9], &[0.1, 0.9, 2.0]);
        let knee = m.joint_aa(1, 4);
        assert!(
            (knee[1] - std::f32::consts::FRAC_PI_2).abs() < 1e-5,
            "{knee:?}"
        );
        assert_eq!(m.joint_aa(1, 22), [0.0; 3]);
        let bad = dir.path().join("bad_00.npy");
        dancegen_io::write_npy_f32(&bad, &[2, 10], &[0.0; 20]).unwrap();
        let e = read_rotmat(&bad).unwrap_err().to_string();
        assert!(e.contains("bad_00.npy") && e.contains("498"), "{e}");
    }
}
