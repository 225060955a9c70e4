//! Every output format a dance can be written to, chosen by extension, and the staging that
//! makes a job's outputs appear all together or not at all.
//!
//! Motion files go through `dancegen_formats::dispatch::save_motion_file`, a holistic dance's
//! (body, fingers and face; `.csv` is its face) through the `holistic` module; previews are
//! drawn by `dancegen_render` (MP4 with the danced part of the song as its sound track). Every
//! file is first written into a hidden staging folder next to its destination and renamed into
//! place only after all of them are complete, so a failed or cancelled job leaves no file and
//! never replaces an existing one with half a dance.

use std::collections::HashSet;
use std::path::{Path, PathBuf};

use dancegen_character::{self as character, Character};
use dancegen_formats::dispatch::{ConvertOptions, LoadedMotion, save_motion_file};
use dancegen_formats::gltf::DancerAnimation;
use dancegen_motion::skeleton::Skeleton;
use dancegen_render::{RenderOptions, Scene, tracks_from_motion, write};

use crate::error::GenerateError;
use crate::progress::{Tracker, stage};
use crate::record::DanceRecord;
use crate::request::{DancerSelection, OutputRequest};
use crate::song::{AnalysedSong, FPS};
use crate::system::{Dance, GroupReport};

mod holistic;

/// Preview image size.
pub const PREVIEW_WIDTH: u32 = 640;
pub const PREVIEW_HEIGHT: u32 = 480;
/// GIF preview frame rate (half the motion's, to keep the file small).
pub const GIF_FPS: f32 = 15.0;

/// A file format, by extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OutputFormat {
    /// glTF binary: skinned skeletons with the animation (Blender, Unity, Unreal, three.js).
    Glb,
    /// FBX 7.4 binary: the same scene as `.glb` (Maya, MotionBuilder, Unity, Unreal, Blender).
    Fbx,
    Bvh,
    /// SMPL parameters (AMASS-style npz; SMPL-H `(T, 156)` for a holistic dance).
    Npz,
    /// World joints `(T, 24, 3)`, metres, Y-up, 30 fps (`(T, 52, 3)` SMPL-H for a holistic
    /// dance).
    Npy,
    /// Joint names, parents and world positions (and a holistic dance's face).
    Json,
    Gif,
    /// Preview with the song.
    Mp4,
    /// The face as Live Link Face CSV (52 ARKit weights per frame); holistic dances only.
    Csv,
}

impl OutputFormat {
    pub const ALL: [OutputFormat; 9] = [
        OutputFormat::Glb,
        OutputFormat::Fbx,
        OutputFormat::Bvh,
        OutputFormat::Npz,
        OutputFormat::Npy,
        OutputFormat::Json,
        OutputFormat::Gif,
        OutputFormat::Mp4,
        OutputFormat::Csv,
    ];

    pub fn extension(self) -> &'static str {
        match self {
            OutputFormat::Glb => "glb",
            OutputFormat::Fbx => "fbx",
            OutputFormat::Bvh => "bvh",
            OutputFormat::Npz => "npz",
            OutputFormat::Npy => "npy",
            OutputFormat::Json => "json",
            OutputFormat::Gif => "gif",
            OutputFormat::Mp4 => "mp4",
            OutputFormat::Csv => "csv",
        }
    }

    /// The format of `path`, or an error listing the formats.
    pub fn of(path: &Path) -> Result<Self, GenerateError> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(|e| e.to_ascii_lowercase())
            .unwrap_or_default();
        Self::ALL
            .into_iter()
            .find(|f| f.extension() == ext)
            .ok_or_else(|| GenerateError::Output {
                path: path.to_path_buf(),
                reason: format!(
                    "unknown output format '.{ext}' (use .glb, .fbx, .bvh, .npz, .npy, .json, \
                     .gif, .mp4 or, for a holistic dance's face, .csv)"
                ),
            })
    }

    /// Whether one file can hold several dancers (a couple, a group).
    pub fn holds_many_dancers(self) -> bool {
        matches!(
            self,
            OutputFormat::Glb
                | OutputFormat::Fbx
                | OutputFormat::Json
                | OutputFormat::Gif
                | OutputFormat::Mp4
        )
    }

    pub fn is_preview(self) -> bool {
        matches!(self, OutputFormat::Gif | OutputFormat::Mp4)
    }
}

/// An output request whose format and destination have been checked.
pub(crate) struct PlannedOutput {
    pub request: OutputRequest,
    pub format: OutputFormat,
}

/// Checks every output before any work is done: known format, an existing folder, no file
/// named twice, ffmpeg present for MP4, a face for `.csv` (`with_face`: the system makes one).
pub(crate) fn plan(
    outputs: &[OutputRequest],
    with_face: bool,
) -> Result<Vec<PlannedOutput>, GenerateError> {
    let mut seen = HashSet::new();
    let mut planned = Vec::with_capacity(outputs.len());
    for r in outputs {
        let format = OutputFormat::of(&r.path)?;
        if format == OutputFormat::Csv && !with_face {
            return Err(no_face(&r.path));
        }
        let dir = parent_dir(&r.path);
        if !dir.is_dir() {
            return Err(GenerateError::Output {
                path: r.path.clone(),
                reason: format!("the folder {} does not exist", dir.display()),
            });
        }
        if !seen.insert(r.path.clone()) {
            return Err(GenerateError::Output {
                path: r.path.clone(),
                reason: "named twice as an output".into(),
            });
        }
        planned.push(PlannedOutput {
            request: r.clone(),
            format,
        });
    }
    if planned.iter().any(|p| p.format == OutputFormat::Mp4) && !write::ffmpeg_available() {
        return Err(dancegen_render::RenderError::FfmpegMissing.into());
    }
    Ok(planned)
}

/// Rough seconds the writing takes, for the job's progress plan (a motion file takes tens of
/// milliseconds; a 45 s preview a few seconds on 2 cores). Only the proportion to the other
/// stages matters: the ETA is extrapolated from the real time spent.
pub(crate) fn estimated_seconds(planned: &[PlannedOutput]) -> f64 {
    planned
        .iter()
        .map(|p| if p.format.is_preview() { 4.0 } else { 0.1 })
        .sum()
}

/// A `.csv` asked of a dance without a face.
fn no_face(path: &Path) -> GenerateError {
    GenerateError::Output {
        path: path.to_path_buf(),
        reason: "a .csv holds the face (Live Link Face ARKit weights) of a holistic dance \
                 (--system holistic), and this dance has no face"
            .into(),
    }
}

/// Progress units of one motion file (a preview counts its frames).
const MOTION_FILE_UNITS: usize = 10;

fn parent_dir(path: &Path) -> &Path {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    }
}

/// The dancers `format` gets under `selection`, as one motion.
fn select(
    dance: &Dance,
    selection: DancerSelection,
    format: OutputFormat,
    path: &Path,
) -> Result<LoadedMotion, GenerateError> {
    let generated: Vec<_> = dance
        .dancers
        .iter()
        .filter(|d| d.role.generated())
        .collect();
    // A group's `.npy` is `(N, T, 24, 3)`: every dancer is generated, and external tools
    // read the whole group from it.
    let holds_many =
        format.holds_many_dancers() || (dance.group.is_some() && format == OutputFormat::Npy);
    let chosen: Vec<_> = match selection {
        DancerSelection::Given => dance
            .dancers
            .iter()
            .filter(|d| !d.role.generated())
            .collect(),
        DancerSelection::Auto if holds_many => dance.dancers.iter().collect(),
        _ => generated,
    };
    match chosen.as_slice() {
        [] => Err(GenerateError::Output {
            path: path.to_path_buf(),
            reason: if selection == DancerSelection::Given {
                "the dance has no given dancer (only a duet has a leader) to write".into()
            } else {
                "the dance has no generated dancer to write".into()
            },
        }),
        [one] => Ok(LoadedMotion::Smpl(one.motion.clone())),
        many if holds_many => Ok(LoadedMotion::Group(
            many.iter().map(|d| d.motion.clone()).collect(),
        )),
        many => Err(GenerateError::Output {
            path: path.to_path_buf(),
            reason: format!(
                "a .{} holds one dancer and this dance has {}; write .glb or .json for all of them",
                format.extension(),
                many.len()
            ),
        }),
    }
}

/// Hidden folders next to the destinations that hold the outputs until all are written.
#[derive(Default)]
struct Staging {
    dirs: Vec<tempfile::TempDir>,
    moves: Vec<(PathBuf, PathBuf)>,
}

impl Staging {
    /// Where to write `dest` for now.
    fn path_for(&mut self, dest: &Path) -> Result<PathBuf, GenerateError> {
        let dir = tempfile::Builder::new()
            .prefix(".dancegen-")
            .tempdir_in(parent_dir(dest))
            .map_err(|e| GenerateError::Output {
                path: dest.to_path_buf(),
                reason: format!("cannot create a staging folder next to it: {e}"),
            })?;
        let name = dest.file_name().ok_or_else(|| GenerateError::Output {
            path: dest.to_path_buf(),
            reason: "not a file name".into(),
        })?;
        let tmp = dir.path().join(name);
        self.dirs.push(dir);
        self.moves.push((tmp.clone(), dest.to_path_buf()));
        Ok(tmp)
    }

    /// Renames every staged file into place; the staging folders go when `self` drops.
    fn commit(self) -> Result<Vec<PathBuf>, GenerateError> {
        let mut written = Vec::with_capacity(self.moves.len());
        for (tmp, dest) in &self.moves {
            std::fs::rename(tmp, dest).map_err(|e| GenerateError::Output {
                path: dest.clone(),
                reason: e.to_string(),
            })?;
            written.push(dest.clone());
        }
        Ok(written)
    }
}

/// An error about the staging copy `tmp`, told about `dest`.
fn about_dest(e: impl std::fmt::Display, tmp: &Path, dest: &Path) -> GenerateError {
    let text = e
        .to_string()
        .replace(&tmp.display().to_string(), &dest.display().to_string());
    let prefix = format!("{}: ", dest.display());
    GenerateError::Output {
        path: dest.to_path_buf(),
        reason: text.strip_prefix(&prefix).unwrap_or(&text).to_string(),
    }
}

/// Writes every planned output of `dance`, reporting progress under `write_outputs` and
/// stopping (leaving nothing) when the job is cancelled. Returns the paths written.
pub(crate) fn write_all(
    planned: &[PlannedOutput],
    dance: &Dance,
    song: &AnalysedSong,
    record: &DanceRecord,
    tracker: &Tracker<'_>,
) -> Result<Vec<PathBuf>, GenerateError> {
    // Before any file is written: only a holistic dance has a face for `.csv`.
    if dance.holistic.is_none()
        && let Some(p) = planned.iter().find(|p| p.format == OutputFormat::Csv)
    {
        return Err(no_face(&p.request.path));
    }
    let fps = FPS as f32;
    let units: Vec<usize> = planned
        .iter()
        .map(|p| match p.format {
            OutputFormat::Gif => frame_count(dance, GIF_FPS),
            OutputFormat::Mp4 => frame_count(dance, fps),
            _ => MOTION_FILE_UNITS,
        })
        .collect();
    let total: usize = units.iter().sum();
    let mut done = 0usize;
    let mut staging = Staging::default();
    for (p, &n) in planned.iter().zip(&units) {
        tracker.check()?;
        let dest = &p.request.path;
        if dance.group.is_some() && matches!(p.format, OutputFormat::Bvh | OutputFormat::Npz) {
            // One file per dancer: `name_0.bvh`, `name_1.bvh`, …
            for (k, d) in dance.dancers.iter().enumerate() {
                let one = numbered(dest, k);
                let tmp = staging.path_for(&one)?;
                let record = DanceRecord {
                    dancer: k,
                    ..record.clone()
                };
                save_motion_file(
                    &tmp,
                    &LoadedMotion::Smpl(d.motion.clone()),
                    &convert_options(&p.request, &record),
                )
                .map_err(|e| about_dest(e, &tmp, &one))?;
            }
            done += n;
            tracker.advance(stage::WRITE_OUTPUTS, done, total);
            continue;
        }
        let tmp = staging.path_for(dest)?;
        if let (Some(g), OutputFormat::Json) = (&dance.group, p.format) {
            let motion = select(dance, p.request.dancers, p.format, dest)?;
            write_group_json(&tmp, &motion, g).map_err(|e| about_dest(e, &tmp, dest))?;
            done += n;
            tracker.advance(stage::WRITE_OUTPUTS, done, total);
            continue;
        }
        let motion = select(dance, p.request.dancers, p.format, dest)?;
        if let (OutputFormat::Glb, Some(character)) = (p.format, &p.request.character) {
            write_character(&tmp, dest, character, &motion)?;
            done += n;
            tracker.advance(stage::WRITE_OUTPUTS, done, total);
            continue;
        }
        if let Some(parts) = &dance.holistic
            && !p.format.is_preview()
        {
            holistic::write(&tmp, dest, p.format, p.request.rig, parts, &motion, record)?;
            done += n;
            tracker.advance(stage::WRITE_OUTPUTS, done, total);
            continue;
        }
        if p.format.is_preview() {
            let tracks = tracks_from_motion(dest, &motion)?;
            let (width, height) = match p.format {
                OutputFormat::Mp4 => p.request.video.pixels(),
                _ => (PREVIEW_WIDTH, PREVIEW_HEIGHT),
            };
            let scene = Scene::new(&tracks, &RenderOptions::new(width, height))?;
            let base = done;
            // Frames stop coming once the job is cancelled; the short file is then dropped
            // with the staging folder.
            let frames = |rate: f32| {
                scene.stream(rate).enumerate().map_while(move |(i, img)| {
                    tracker.advance_as(
                        stage::RENDER_VIDEO,
                        stage::WRITE_OUTPUTS,
                        base + i + 1,
                        total,
                    );
                    tracker.check().is_ok().then_some(img)
                })
            };
            let written = if p.format == OutputFormat::Gif {
                write::write_gif(&tmp, frames(GIF_FPS), GIF_FPS)
            } else {
                let song_file = crate::song::SongFile::of(&song.source)?;
                let clip = write::AudioClip {
                    path: song_file.path(),
                    start_s: dance.span.start_s,
                    seconds: Some(dance.span.end_s - dance.span.start_s),
                };
                write::write_mp4(&tmp, frames(fps), width, height, fps, Some(clip))
            };
            written.map_err(|e| about_dest(e, &tmp, dest))?;
        } else {
            let record = DanceRecord {
                dancer: written_dancer(dance, p.request.dancers),
                ..record.clone()
            };
            save_motion_file(&tmp, &motion, &convert_options(&p.request, &record))
                .map_err(|e| about_dest(e, &tmp, dest))?;
        }
        done += n;
        tracker.advance(stage::WRITE_OUTPUTS, done, total);
    }
    tracker.check()?;
    staging.commit()
}

/// The user's character dancing `motion` (one dancer), as a `.glb` at `tmp` (for `dest`).
fn write_character(
    tmp: &Path,
    dest: &Path,
    character: &Character,
    motion: &LoadedMotion,
) -> Result<(), GenerateError> {
    let LoadedMotion::Smpl(s) = motion else {
        let n = match motion {
            LoadedMotion::Group(g) => g.len(),
            _ => 0,
        };
        return Err(GenerateError::Output {
            path: dest.to_path_buf(),
            reason: format!(
                "--character puts one dancer on the character and this .glb would hold {n}; \
                 with a leader add --follower-only"
            ),
        });
    };
    let dancer = DancerAnimation {
        local_rotations_axis_angle: &s.poses,
        root_translation: &s.trans,
    };
    let animation = character::retarget(character, &Skeleton::smpl24(), &[dancer], s.fps)
        .map_err(|e| about_dest(e, tmp, dest))?;
    character::write_glb(tmp, character, &animation).map_err(|e| about_dest(e, tmp, dest))
}

/// How a motion file is written for `request`.
fn convert_options(request: &OutputRequest, record: &DanceRecord) -> ConvertOptions {
    ConvertOptions {
        rig: request.rig,
        npz_record: Some(record.to_json()),
        ..ConvertOptions::default()
    }
}

/// The dancer a single-dancer file of `dance` holds under `selection` (as [`select`] picks it).
fn written_dancer(dance: &Dance, selection: DancerSelection) -> usize {
    let pick = match selection {
        DancerSelection::Given => dance.dancers.iter().position(|d| !d.role.generated()),
        _ => dance.dancers.iter().position(|d| d.role.generated()),
    };
    pick.unwrap_or(0)
}

/// `dir/stem_k.ext` for `dir/stem.ext`.
pub fn numbered(path: &Path, k: usize) -> PathBuf {
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let name = match path.extension() {
        Some(e) => format!("{stem}_{k}.{}", e.to_string_lossy()),
        None => format!("{stem}_{k}"),
    };
    path.with_file_name(name)
}

/// A group dance's `.json`: the stage record ([`GroupReport`]: start and end order, every
/// dancer's root trajectory, the requested paths and how well they were followed) plus the
/// joints as every `.json` has them (`joint_names`, `parents`, `shape` `(N, T, 24, 3)`,
/// `positions`).
fn write_group_json(
    out: &Path,
    motion: &LoadedMotion,
    g: &GroupReport,
) -> Result<(), dancegen_formats::dispatch::FormatError> {
    let (shape, positions) = dancegen_formats::dispatch::joint_positions(out, motion)?;
    let s = Skeleton::smpl24();
    let v = serde_json::json!({
        "fps": FPS,
        "up": "y",
        "units": "metres",
        "stage": "[x, z]: x to the audience's right, +z towards the audience, origin at the stage centre",
        "dancers": shape.first().copied().unwrap_or(0),
        "start_order": g.start_order,
        "end_order": g.end_order,
        "trajectories": g.trajectories,
        "requested": g.requested,
        "trajectory_error_mean_m": g.trajectory_error_mean_m,
        "trajectory_error_final_m": g.trajectory_error_final_m,
        "joint_names": s.names(),
        "parents": s.parents(),
        "shape": shape,
        "positions": positions,
    });
    dancegen_io::write_atomic(out, |w| {
        serde_json::to_writer(&mut *w, &v).map_err(std::io::Error::other)
    })
    .map_err(|e| dancegen_formats::dispatch::FormatError {
        path: out.to_path_buf(),
        reason: e.to_string(),
    })
}

/// Preview frames of `dance` at `fps` (the render scene's count for the longest dancer).
fn frame_count(dance: &Dance, fps: f32) -> usize {
    let frames = dance
        .dancers
        .iter()
        .map(|d| d.motion.frames())
        .max()
        .unwrap_or(0);
    let seconds = frames.saturating_sub(1) as f32 / FPS as f32;
    (seconds * fps + 1e-3).floor() as usize + 1
}
