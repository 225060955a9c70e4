//! Training sets for the dance models: motion clips paired with per-frame music features.
//!
//! Output layout (everything written atomically, the manifest last):
//!
//! ```text
//! OUT/motion/<clip>.npz        SMPL 24 motion, 30 fps, Y-up, metres (AMASS-style npz,
//!                              read back by dancegen_formats::dispatch::load_motion_file)
//! OUT/music/<clip>.npy         (T, 35) float32 EDGE-35 features at 30 fps, T = motion frames
//! OUT/leader/<clip>.npz        duet data sets only: the partner the clip's dancer follows
//! OUT/held_out/{motion,music,leader}/ the same for held-out clips (evaluation only)
//! OUT/manifest.json            see [`manifest::Manifest`]
//! ```
//!
//! Six ways to pair ([`Pairing`]):
//! - **pseudo** ([`Pairing::Pseudo`]): no data set here pairs dance with music, so each motion
//!   is time-warped onto the beats of a song ([`warp`]). This is a documented *pseudo*-pairing,
//!   not ground truth: the dancer never heard that song.
//! - **duet** ([`Pairing::Duet`]): couples recorded together, one warp for both partners,
//!   one clip per role assignment ([`duet`]).
//! - **dd100**: Duolando's duet data set under `--root` ([`dd100`]), its own pairing.
//! - **aistpp** / **finedance**: the data sets' own pairing ([`layouts`]).
//! - **group**: 2–5 dancers composed from real takes into formations, beat-warped onto songs
//!   ([`group`]; `OUT/group/<clip>/dancer_<k>.npz` and `OUT/trajectories/<clip>.npy`).
//!
//! Music features are computed once per song over the whole song (as the reference repos do)
//! and the clip's frames are sliced from that matrix, so a clip's beat/onset columns are the
//! whole-song tracker's decisions.
//!
//! This crate has no deep-learning dependencies.

pub mod dd100;
pub mod duet;
pub mod error;
pub mod genre;
pub mod group;
pub mod holistic_synth;
pub mod layouts;
pub mod manifest;
pub mod takes;
/// The beat warp lives in the motion crate (the generation library aligns generated dances with
/// it too); re-exported under its old path.
pub use dancegen_refine::beat_warp as warp;

use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::ops::Range;
use std::path::{Path, PathBuf};

use dancegen_formats::dispatch::{
    ConvertOptions, LoadedMotion, NpzStyle, convert_motion, load_motion_file_with, save_motion_file,
};
use dancegen_metrics::FRAME_LEN;
use dancegen_metrics::bas::{Variant, beat_align_score, clip_music_beats, try_motion_beats};
use dancegen_motion::repr::motion::{POSE_DIMS, SmplMotion};
use dancegen_music::FrameMatrix;
use dancegen_music::decode::AudioSource;
use dancegen_music::features::{EDGE35_DIM, ExtractOptions, FeatureSet, extract};
use rayon::prelude::*;

pub use error::DatasetError;
pub use manifest::{ClipEntry, GroupLabels, MANIFEST_VERSION, Manifest, PairingKind, WarpReport};
use warp::{BeatMatch, WarpParams, match_beats, warp_motion};

/// Frame rate of every clip (motion and music), EDGE/Lodge's 30 fps.
pub const FPS: u32 = 30;

/// Clips shorter than this (1 s) are dropped: too short to train on.
pub const MIN_CLIP_FRAMES: usize = 30;

/// Fraction of a song a motion piece may fill at the slowest allowed playback speed before
/// the motion is split into several clips (leaves room for the start offset).
const SONG_FILL: f64 = 0.9;

/// How motion and music are paired.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pairing {
    /// Beat-warp pseudo-pairing of `--motion` files with `--music` songs.
    Pseudo,
    /// Beat-warp pseudo-pairing of couples (`--motion` files of two partners each) with songs;
    /// see [`duet`].
    Duet,
    /// DD100 (Duolando) duet layout under `root`; see [`dd100`].
    Dd100,
    /// AIST++ layout under `root` (`motions/*.pkl`, `wav/<music id>.wav`, `splits/`).
    Aistpp,
    /// FineDance layout under `root` (`motion/*.npy`, `music_wav/*.wav`, `label_json/*.json`).
    FineDance,
    /// 2–5 dancers composed from `--motion` takes into formations and beat-warped onto
    /// `--music` songs; see [`group`].
    Group,
}

/// Options of [`build`].
#[derive(Clone, Debug)]
pub struct BuildOptions {
    /// Output directory (created if missing).
    pub out: PathBuf,
    pub pairing: Pairing,
    /// Motion files (pseudo pairing; any format `load_motion_file` reads; directories are
    /// searched for motion files, non-recursively).
    pub motions: Vec<PathBuf>,
    /// Songs (pseudo pairing).
    pub music: Vec<PathBuf>,
    /// Data set root (aistpp / finedance).
    pub root: Option<PathBuf>,
    /// Genre of every input (default: from the file names).
    pub genre: Option<String>,
    /// Motion or song stems (file names without extension) kept out of training.
    pub hold_out: Vec<String>,
    /// Breaks exact ties between songs.
    pub seed: u64,
    pub warp: WarpParams,
    /// Also trains on each training motion's left–right mirror image (clip `<name>_mirror`,
    /// [`SmplMotion::mirror`], as EDGE and Lodge augment); held-out motions are never mirrored.
    /// Pseudo and duet pairing (a couple is mirrored as a whole, both partners in one world
    /// reflection, so it stays a couple).
    pub mirror: bool,
    /// Also give every clip **synthetic** fingers and an ARKit face made from its body and
    /// music ([`holistic_synth::attach`]), for the holistic (SoulNet) system. Pseudo and AIST++
    /// pairing (bodies without real hands).
    pub holistic: bool,
    /// Training takes are paired with this many songs, best first (1: only the best; the
    /// further pairings are clips `<name>__<song>`); held-out takes always with one. Pseudo
    /// pairing only.
    pub songs_per_motion: usize,
    /// Genres relabelled after pairing, `(from, to)`: a genre with too few takes to learn on
    /// its own is folded into a related one (e.g. the single CMU "dance, whirl" take into
    /// `modern`). Applied to every pairing's manifest.
    pub merge_genres: Vec<(String, String)>,
    /// Group pairing only ([`group`]).
    pub group: group::GroupOptions,
    /// The rate each `motions` input was captured at, where its header is wrong or missing
    /// ([`takes::SourceRates`]); the others are read at their header's rate.
    pub source_fps: takes::SourceRates,
}

impl BuildOptions {
    /// Pseudo pairing of `motions` with `music` into `out`, defaults otherwise.
    pub fn pseudo(out: impl Into<PathBuf>, motions: Vec<PathBuf>, music: Vec<PathBuf>) -> Self {
        BuildOptions {
            out: out.into(),
            pairing: Pairing::Pseudo,
            motions,
            music,
            root: None,
            genre: None,
            hold_out: Vec::new(),
            seed: 0,
            warp: WarpParams::default(),
            mirror: false,
            holistic: false,
            songs_per_motion: 1,
            merge_genres: Vec::new(),
            group: group::GroupOptions::default(),
            source_fps: takes::SourceRates::default(),
        }
    }
}

/// Progress callbacks (the CLI draws a bar); every method has a no-op default.
pub trait Progress: Sync {
    /// A stage with `total` steps begins.
    fn stage(&self, _name: &str, _total: usize) {}
    /// One step of the current stage finished.
    fn step(&self, _item: &str) {}
}

impl Progress for () {}

/// A song analysed once: its EDGE-35 features over the whole song and its beats.
#[derive(Clone, Debug)]
pub struct Song {
    /// File stem.
    pub name: String,
    pub path: PathBuf,
    /// `(frames, 35)` at [`FPS`].
    pub features: FrameMatrix,
    /// Beat frames of the librosa-exact tracker (the features' beat column).
    pub beat_frames: Vec<usize>,
    pub tempo_bpm: f64,
}

impl Song {
    /// EDGE-35 features at 30 fps of a whole song, exactly as `dancegen features` computes them.
    pub fn analyse(path: &Path) -> Result<Song, DatasetError> {
        let f = extract(
            &AudioSource::File(path.to_path_buf()),
            &ExtractOptions {
                fps: FPS,
                set: FeatureSet::Edge35,
                start_bpm: None,
            },
        )?;
        Ok(Song {
            name: stem(path),
            path: path.to_path_buf(),
            beat_frames: f.beat_frames,
            tempo_bpm: f.tempo_bpm,
            features: f.features,
        })
    }

    pub fn frames(&self) -> usize {
        self.features.rows
    }

    pub fn duration_s(&self) -> f64 {
        self.frames() as f64 / f64::from(FPS)
    }

    /// Beat times in seconds.
    pub fn beat_times(&self) -> Vec<f64> {
        self.beat_frames
            .iter()
            .map(|&b| b as f64 / f64::from(FPS))
            .collect()
    }

    /// Feature rows `start..start + n`, flattened.
    pub(crate) fn rows(&self, start: usize, n: usize) -> Vec<f32> {
        self.features.data[start * EDGE35_DIM..(start + n) * EDGE35_DIM].to_vec()
    }

    /// Beats in `start..start + n`, relative to `start`.
    pub(crate) fn beats_in(&self, start: usize, n: usize) -> Vec<usize> {
        self.beat_frames
            .iter()
            .filter(|&&b| b >= start && b < start + n)
            .map(|&b| b - start)
            .collect()
    }
}

/// File name without its extension.
pub fn stem(path: &Path) -> String {
    path.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// Kinematic beats of world joints `(T, 24, 3)`: frame indices into the `T − 1` velocity
/// samples of strict local minima of the mean joint speed smoothed by a Gaussian of σ = 5
/// frames — Bailando/FACT's "kinetic beat", computed by the metric crate's own BAS code, so the
/// warp aligns exactly the beats the BAS metric later measures. (σ = 2 and 3 were tried on the
/// salsa takes: more, noisier minima, more of them matched, but a smaller BAS gain.)
pub fn kinematic_beats(joints: &[f64]) -> Vec<usize> {
    try_motion_beats(joints, Variant::Bailando).unwrap_or_default()
}

/// Bailando's BAS of a clip's world joints against the clip's music beats (frames relative
/// to the clip start, cut as Bailando cuts them).
pub fn bas_bailando(joints: &[f64], music_beats: &[usize]) -> Option<f64> {
    let frames = joints.len() / FRAME_LEN;
    let motion = try_motion_beats(joints, Variant::Bailando).ok()?;
    let music = clip_music_beats(music_beats, frames, Variant::Bailando);
    beat_align_score(&music, &motion, Variant::Bailando)
}

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

pub(crate) fn world_joints(m: &SmplMotion, source: &Path) -> Result<Vec<f64>, DatasetError> {
    let j = m
        .joints_world()
        .map_err(|e| DatasetError::input(source, format!("forward kinematics failed: {e}")))?;
    Ok(j.into_iter().map(f64::from).collect())
}

/// One dancer's motion at 30 fps, ready to be paired.
#[derive(Clone, Debug)]
pub(crate) struct MotionUnit {
    /// Clip name (pieces get `_<k>` appended).
    pub name: String,
    /// Stem of the source file (what `--hold-out` names).
    pub stem: String,
    pub source: PathBuf,
    pub genre: String,
    pub motion: SmplMotion,
    /// The rate the source file was read at, and where it came from.
    pub source_fps: f64,
    pub rate_from: takes::RateFrom,
}

/// Loads a motion file as SMPL 24 at 30 fps: BVH retargeted, 60 fps strided (EDGE), each dancer
/// of a group file separately (`<stem>_d<k>`).
pub(crate) fn load_units(
    path: &Path,
    genre: &str,
    rates: &takes::SourceRates,
) -> Result<Vec<MotionUnit>, DatasetError> {
    let given = rates.rate_for(path);
    let read = dancegen_formats::dispatch::LoadOptions {
        source_fps: given,
        ..Default::default()
    };
    let loaded = load_motion_file_with(path, &read)?;
    let source_fps = f64::from(loaded.fps());
    let rate_from = if given.is_some() {
        takes::RateFrom::Given
    } else {
        takes::RateFrom::Header
    };
    let opts = ConvertOptions {
        to_smpl24: true,
        fps: Some(FPS as f32),
        ..Default::default()
    };
    let converted = convert_motion(path, loaded, &opts)?;
    let s = stem(path);
    let unit = |name: String, motion: SmplMotion| MotionUnit {
        name,
        stem: s.clone(),
        source: path.to_path_buf(),
        genre: genre.to_string(),
        motion,
        source_fps,
        rate_from,
    };
    match converted {
        LoadedMotion::Smpl(m) => Ok(vec![unit(s.clone(), m)]),
        LoadedMotion::Group(g) => Ok(g
            .into_iter()
            .enumerate()
            .map(|(k, m)| unit(format!("{s}_d{k}"), m))
            .collect()),
        other => Err(DatasetError::input(
            path,
            format!("a {} has no SMPL rotations to train on", other.kind()),
        )),
    }
}

/// The left–right mirror image of a unit, as its own clip (`<name>_mirror`); the stem stays,
/// so a `--hold-out` of the take covers both.
pub(crate) fn mirrored_unit(u: &MotionUnit) -> MotionUnit {
    MotionUnit {
        name: format!("{}_mirror", u.name),
        motion: u.motion.mirror(),
        ..u.clone()
    }
}

/// A finished clip before it is written.
pub(crate) struct ClipData {
    name: String,
    genre: String,
    source_motion: PathBuf,
    source_song: PathBuf,
    start_frame: usize,
    motion: SmplMotion,
    music: Vec<f32>,
    pairing: PairingKind,
    warp: Option<WarpReport>,
    held_out: bool,
}

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

pub(crate) fn create_dirs(out: &Path) -> Result<(), DatasetError> {
    for d in ["motion", "music", "held_out/motion", "held_out/music"] {
        let p = out.join(d);
        std::fs::create_dir_all(&p)
            .map_err(|e| DatasetError::input(&p, format!("cannot create directory: {e}")))?;
    }
    Ok(())
}

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

fn build_pseudo(
    opts: &BuildOptions,
    progress: &dyn Progress,
) -> Result<Vec<ClipEntry>, DatasetError> {
    if opts.motions.is_empty() {
        return Err(DatasetError::Options(
            "--pairing pseudo needs --motion FILES".into(),
        ));
    }
    if opts.music.is_empty() {
        return Err(DatasetError::Options(
            "--pairing pseudo needs --music SONGS".into(),
        ));
    }
    let motions = expand_motion_inputs(&opts.motions)?;
    let mut known = BTreeSet::new();
    let mut seen: HashMap<String, &Path> = HashMap::new();
    for p in motions.iter().chain(&opts.music) {
        let s = stem(p);
        if let Some(prev) = seen.insert(s.clone(), p) {
            return Err(DatasetError::input(
                p,
                format!(
                    "same file name as {} (clip and hold-out names come from file names)",
                    prev.display()
                ),
            ));
        }
        known.insert(s);
    }
    check_hold_out(&opts.hold_out, &known)?;
    let held = |s: &str| opts.hold_out.iter().any(|h| h == s);
    let any_train_motion = motions.iter().any(|m| !held(&stem(m)));
    if any_train_motion && opts.music.iter().all(|m| held(&stem(m))) {
        return Err(DatasetError::Options(
            "every song is held out: training motions need at least one song that is not".into(),
        ));
    }
    let songs = analyse_songs(&opts.music, progress)?;
    for s in &songs {
        tracing::info!(
            "{}: {:.1} s, tempo {:.1} BPM, {} beats",
            s.path.display(),
            s.duration_s(),
            s.tempo_bpm,
            s.beat_frames.len()
        );
    }
    let train_songs: Vec<usize> = (0..songs.len())
        .filter(|&i| !held(&songs[i].name))
        .collect();
    let held_songs: Vec<usize> = (0..songs.len()).filter(|&i| held(&songs[i].name)).collect();
    let any_held_motion = motions.iter().any(|m| held(&stem(m)));
    if !held_songs.is_empty() && !any_held_motion {
        tracing::warn!(
            "held-out songs are only paired with held-out motions, and no motion is held out: \
             {} unused",
            held_songs
                .iter()
                .map(|&i| songs[i].name.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    create_dirs(&opts.out)?;
    progress.stage("pairing motions", motions.len());
    let results: Vec<Result<Vec<ClipEntry>, DatasetError>> = motions
        .par_iter()
        .map(|path| {
            let s = stem(path);
            let genre = opts
                .genre
                .as_deref()
                .map(genre::normalize)
                .unwrap_or_else(|| genre::genre_from_name(&s));
            let motion_held = held(&s);
            // Training motions never see a held-out song; held-out motions are paired with the
            // held-out songs when there are any (unseen motion on unseen music), else any song.
            let candidates = if motion_held && !held_songs.is_empty() {
                &held_songs
            } else {
                &train_songs
            };
            let mut entries = Vec::new();
            let mut units = load_units(path, &genre, &opts.source_fps)?;
            if opts.mirror && !motion_held {
                let mirrored: Vec<MotionUnit> = units.iter().map(mirrored_unit).collect();
                units.extend(mirrored);
            }
            for unit in units {
                for clip in pair_unit(&unit, &songs, candidates, opts, held)? {
                    entries.push(write_clip(&opts.out, &clip)?);
                }
            }
            progress.step(&s);
            Ok(entries)
        })
        .collect();
    let clips = gather_clips(results)?;
    let mut names = BTreeSet::new();
    for c in &clips {
        if !names.insert(c.name.as_str()) {
            return Err(DatasetError::Options(format!(
                "two clips are named {} (rename one of the inputs)",
                c.name
            )));
        }
    }
    Ok(clips)
}

/// A motion piece and its matching against one song.
pub(crate) struct PiecePlan {
    pub(crate) frames: Range<usize>,
    pub(crate) motion_beats: usize,
    pub(crate) matched: BeatMatch,
}

/// Splits a motion of `frames` frames into pieces short enough for a song of `song_s` seconds
/// at the slowest playback speed the warp allows.
fn piece_ranges(frames: usize, song_s: f64, p: &WarpParams) -> Vec<Range<usize>> {
    let fps = f64::from(FPS);
    let capacity = (SONG_FILL * song_s / p.max_rate * fps).floor() as usize;
    if frames <= capacity || capacity < MIN_CLIP_FRAMES {
        return std::iter::once(0..frames).collect();
    }
    let k = frames.div_ceil(capacity);
    (0..k)
        .map(|i| i * frames / k..(i + 1) * frames / k)
        .collect()
}

pub(crate) fn plan_song(
    joints: &[f64],
    frames: usize,
    song: &Song,
    p: &WarpParams,
) -> Vec<PiecePlan> {
    let fps = f64::from(FPS);
    let music = song.beat_times();
    piece_ranges(frames, song.duration_s(), p)
        .into_iter()
        .map(|r| {
            let j = &joints[r.start * FRAME_LEN..r.end * FRAME_LEN];
            let beats: Vec<f64> = kinematic_beats(j).iter().map(|&b| b as f64 / fps).collect();
            let len = (r.len().saturating_sub(1)) as f64 / fps;
            let matched = match_beats(&beats, &music, len, song.duration_s(), p);
            PiecePlan {
                frames: r,
                motion_beats: beats.len(),
                matched,
            }
        })
        .collect()
}

/// The candidate song with the most matched beats per minute of motion, and its plan; exact ties
/// go to the first song in an order rotated by the seed. `None` without candidates.
pub(crate) fn best_song(
    joints: &[f64],
    frames: usize,
    songs: &[Song],
    candidates: &[usize],
    opts: &BuildOptions,
    name: &str,
) -> Option<(usize, Vec<PiecePlan>)> {
    ranked_songs(joints, frames, songs, candidates, opts, name)
        .into_iter()
        .next()
}

/// Every candidate song with its plan, best first: most matched beats per minute; exact ties
/// keep the order of the candidates rotated by `--seed`.
pub(crate) fn ranked_songs(
    joints: &[f64],
    frames: usize,
    songs: &[Song],
    candidates: &[usize],
    opts: &BuildOptions,
    name: &str,
) -> Vec<(usize, Vec<PiecePlan>)> {
    let minutes = frames as f64 / f64::from(FPS) / 60.0;
    let n = candidates.len();
    let mut ranked: Vec<(f64, usize, Vec<PiecePlan>)> = (0..n)
        .map(|k| {
            let si = candidates[(k + opts.seed as usize % n) % n];
            let plan = plan_song(joints, frames, &songs[si], &opts.warp);
            let matched: usize = plan.iter().map(|p| p.matched.pairs.len()).sum();
            let score = matched as f64 / minutes;
            tracing::debug!("{name} x {}: {score:.1} matched beats/min", songs[si].name);
            (score, si, plan)
        })
        .collect();
    // Stable: equal scores stay in the rotated order (the first one is what `best_song` took).
    ranked.sort_by(|a, b| b.0.total_cmp(&a.0));
    ranked.into_iter().map(|(_, si, plan)| (si, plan)).collect()
}

/// Picks the song and produces the warped clips of one dancer.
fn pair_unit(
    unit: &MotionUnit,
    songs: &[Song],
    candidates: &[usize],
    opts: &BuildOptions,
    held: impl Fn(&str) -> bool,
) -> Result<Vec<ClipData>, DatasetError> {
    let m = &unit.motion;
    let frames = m.frames();
    if frames < MIN_CLIP_FRAMES {
        tracing::warn!(
            "{}: only {frames} frames at 30 fps, skipped",
            unit.source.display()
        );
        return Ok(Vec::new());
    }
    let joints = world_joints(m, &unit.source)?;
    let ranked = ranked_songs(&joints, frames, songs, candidates, opts, &unit.name);
    if ranked.is_empty() {
        return Err(DatasetError::Options(format!(
            "{}: no song to pair with",
            unit.source.display()
        )));
    }
    // A held-out take is measured once, against its best song.
    let keep = if held(&unit.stem) {
        1
    } else {
        opts.songs_per_motion.max(1)
    };
    let mut clips = Vec::new();
    for (rank, (si, plan)) in ranked.into_iter().take(keep).enumerate() {
        let song = &songs[si];
        // The best song keeps the plain name; further pairings name their song.
        let base = if rank == 0 {
            unit.name.clone()
        } else {
            format!("{}__{}", unit.name, song.name)
        };
        clips.extend(warp_plan(unit, &joints, song, plan, &base, &held)?);
    }
    Ok(clips)
}

/// The warped clips of `unit` on `song` by `plan` (one per piece), named `base` or
/// `base_<k>`.
fn warp_plan(
    unit: &MotionUnit,
    joints: &[f64],
    song: &Song,
    plan: Vec<PiecePlan>,
    base: &str,
    held: &impl Fn(&str) -> bool,
) -> Result<Vec<ClipData>, DatasetError> {
    let m = &unit.motion;
    let pieces = plan.len();
    let mut clips = Vec::new();
    for (k, piece) in plan.into_iter().enumerate() {
        let r = piece.frames.clone();
        let src = SmplMotion {
            fps: m.fps,
            poses: m.poses[r.start * POSE_DIMS..r.end * POSE_DIMS].to_vec(),
            trans: m.trans[r.start * 3..r.end * 3].to_vec(),
        };
        let (start, warped) = warp_motion(&src, &piece.matched.map, song.frames());
        let n = warped.frames();
        let name = if pieces == 1 {
            base.to_string()
        } else {
            format!("{base}_{k}")
        };
        if n < MIN_CLIP_FRAMES {
            tracing::warn!("{name}: only {n} frames fit in {}, skipped", song.name);
            continue;
        }
        let after = bas_bailando(
            &world_joints(&warped, &unit.source)?,
            &song.beats_in(start, n),
        );
        // The same piece unwarped, placed at the same song start.
        let fps = f64::from(FPS);
        let p0 = (piece.matched.map.inverse(start as f64 / fps) * fps)
            .round()
            .clamp(0.0, (r.len() - 1) as f64) as usize;
        let len = (r.len() - p0).min(song.frames() - start);
        let a = (r.start + p0) * FRAME_LEN;
        let before = bas_bailando(&joints[a..a + len * FRAME_LEN], &song.beats_in(start, len));
        let rates = piece.matched.map.rates();
        let report = WarpReport {
            min_rate: rates.iter().copied().fold(f64::INFINITY, f64::min),
            max_rate: rates.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            matched_beats: piece.matched.pairs.len(),
            motion_beats: piece.motion_beats,
            bas_before: before,
            bas_after: after,
        };
        clips.push(ClipData {
            name,
            genre: unit.genre.clone(),
            source_motion: unit.source.clone(),
            source_song: song.path.clone(),
            start_frame: start,
            music: song.rows(start, n),
            motion: warped,
            pairing: PairingKind::PseudoBeatWarp,
            warp: Some(report),
            held_out: held(&unit.stem) || held(&song.name),
        });
    }
    Ok(clips)
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

/// A fixed-width summary table of the clips (name, song, frames, rates, beats, BAS).
pub fn summary_table(m: &Manifest) -> String {
    let mut s = format!(
        "{:<28} {:<24} {:>6} {:>8} {:>8} {:>9} {:>8} {:>8} {}\n",
        "clip", "song", "frames", "rate_min", "rate_max", "matched", "bas_pre", "bas_post", "split"
    );
    let f = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.3}"));
    for c in &m.clips {
        let song = stem(Path::new(&c.source_song));
        let split = if m.held_out.contains(&c.name) {
            "held_out"
        } else {
            "train"
        };
        match &c.warp {
            Some(w) => s.push_str(&format!(
                "{:<28} {:<24} {:>6} {:>8.3} {:>8.3} {:>4}/{:<4} {:>8} {:>8} {split}\n",
                c.name,
                song,
                c.frames,
                w.min_rate,
                w.max_rate,
                w.matched_beats,
                w.motion_beats,
                f(w.bas_before),
                f(w.bas_after)
            )),
            None => s.push_str(&format!(
                "{:<28} {:<24} {:>6} {:>8} {:>8} {:>9} {:>8} {:>8} {split}\n",
                c.name, song, c.frames, "-", "-", "-", "-", "-"
            )),
        }
    }
    let warped: Vec<&WarpReport> = m.clips.iter().filter_map(|c| c.warp.as_ref()).collect();
    if !warped.is_empty() {
        let mean = |g: &dyn Fn(&WarpReport) -> Option<f64>| {
            let v: Vec<f64> = warped.iter().filter_map(|w| g(w)).collect();
            v.iter().sum::<f64>() / v.len().max(1) as f64
        };
        s.push_str(&format!(
            "{} warped clips: mean BAS {:.3} -> {:.3}, rates {:.3}..{:.3}, {} / {} motion beats matched\n",
            warped.len(),
            mean(&|w| w.bas_before),
            mean(&|w| w.bas_after),
            warped.iter().map(|w| w.min_rate).fold(f64::INFINITY, f64::min),
            warped.iter().map(|w| w.max_rate).fold(f64::NEG_INFINITY, f64::max),
            warped.iter().map(|w| w.matched_beats).sum::<usize>(),
            warped.iter().map(|w| w.motion_beats).sum::<usize>(),
        ));
    }
    s
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

    #[test]
    fn long_motions_are_split_to_fit_the_song() {
        let p = WarpParams::default();
        // 60 s song: at most 0.9 * 60 * 0.85 = 45.9 s of motion per piece (1377 frames).
        assert_eq!(piece_ranges(1377, 60.0, &p), vec![0..1377]);
        let r = piece_ranges(3000, 60.0, &p);
        assert_eq!(r.len(), 3);
        assert_eq!(r.first().unwrap().start, 0);
        assert_eq!(r.last().unwrap().end, 3000);
        for w in r.windows(2) {
            assert_eq!(w[0].end, w[1].start);
        }
        assert!(r.iter().all(|x| x.len() <= 1377));
    }
}
