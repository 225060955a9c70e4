//! Windowed motion (+ optional music features) for training.
//!
//! Every motion file is read with `dancegen_formats::dispatch::load_motion_file` (BVH retargeted
//! to SMPL 24, group files split per dancer), resampled to the configured frame rate and
//! encoded to the configured representation: one clip of `(T, dims)` per dancer. Windows of
//! `window` frames start every `stride` frames (EDGE: 150 / 15 at 30 fps, `data/slice.py`;
//! ReactDance's dense sliding windows: stride 1–4); clips shorter than a window are skipped.
//!
//! Order: window `i` of epoch `e` is `perm_e[i]`, with `perm_e` a Fisher–Yates shuffle driven by
//! SplitMix64 seeded from `(seed, e)`; the last partial batch of an epoch is dropped (EDGE's
//! `drop_last=True`). The data position is therefore `(epoch, cursor)` and nothing else.

use std::path::{Path, PathBuf};

use dancegen_formats::dispatch::{ConvertOptions, LoadedMotion, convert_motion, load_motion_file};
use dancegen_motion::repr::{
    DuetFollower, DuetLeader, Edge151, Holistic623, HumanMl263, Lodge139, MinMaxNormalizer,
    SmplMotion,
};
use dancegen_nn::burn::tensor::{Device, Tensor, TensorData};
use serde::{Deserialize, Serialize};

use crate::TrainError;
use crate::config::{DataConfig, NormalizerKind, Representation};

/// File extensions read from a directory in `[data] paths`.
pub const MOTION_EXTENSIONS: [&str; 4] = ["bvh", "pkl", "npz", "npy"];

/// One dancer's encoded motion.
#[derive(Clone, Debug)]
pub struct Clip {
    pub source: PathBuf,
    pub frames: usize,
    /// `(frames, dims)`, raw (not normalised).
    pub motion: Vec<f32>,
    /// `(frames, music dims)`.
    pub music: Option<Vec<f32>>,
    /// Index into the manifest's genre list.
    pub genre: Option<usize>,
    /// Group clips: the number of dancers (slots `0..n` of each frame).
    pub dancers: Option<usize>,
}

/// A batch on the training device.
#[derive(Clone, Debug)]
pub struct Batch {
    /// `[batch, window, dims]`, normalised.
    pub motion: Tensor<3>,
    /// `[batch, window, music dims]`.
    pub music: Option<Tensor<3>>,
    /// Genre index per batch element (when every window's clip has one).
    pub genre: Option<Vec<usize>>,
    /// Seed of the batch's own randomness (diffusion timesteps, masks, …): a function of the
    /// run seed and the data position, so a resumed run draws the same numbers.
    pub seed: u64,
    /// Group windows: the dancers of each batch element.
    pub dancers: Option<Vec<usize>>,
}

/// Per-dimension statistics saved with the model (`normalizer.json`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Normalizer {
    /// `(x − mean) / std`; std below [`MIN_STD`] is replaced by 1 (constant dims pass through).
    MeanStd {
        mean: Vec<f64>,
        std: Vec<f64>,
    },
    /// EDGE / LODGE MinMax(−1, 1) (`dancegen_motion::repr::MinMaxNormalizer`).
    MinMax(MinMaxNormalizer),
    None {
        dims: usize,
    },
}

/// Smallest standard deviation used as is (below, the dim is treated as constant).
pub const MIN_STD: f64 = 1e-6;

impl Normalizer {
    /// Fits on all frames of all clips (statistics in f64).
    pub fn fit(kind: NormalizerKind, clips: &[Clip], dims: usize) -> Result<Self, String> {
        Ok(match kind {
            NormalizerKind::None => Normalizer::None { dims },
            NormalizerKind::MinMax => Normalizer::MinMax(
                MinMaxNormalizer::fit_chunks(clips.iter().map(|c| c.motion.as_slice()), dims)
                    .map_err(|e| e.to_string())?,
            ),
            NormalizerKind::MeanStd => {
                let mut sum = vec![0f64; dims];
                let mut sq = vec![0f64; dims];
                let mut n = 0usize;
                for row in clips.iter().flat_map(|c| c.motion.chunks_exact(dims)) {
                    for (d, &v) in row.iter().enumerate() {
                        sum[d] += v as f64;
                        sq[d] += v as f64 * v as f64;
                    }
                    n += 1;
                }
                if n == 0 {
                    return Err("normalizer fitted on no frames".into());
                }
                let mean: Vec<f64> = sum.iter().map(|s| s / n as f64).collect();
                let std = sq
                    .iter()
                    .zip(&mean)
                    .map(|(s, m)| {
                        let sd = (s / n as f64 - m * m).max(0.0).sqrt();
                        if sd < MIN_STD { 1.0 } else { sd }
                    })
                    .collect();
                Normalizer::MeanStd { mean, std }
            }
        })
    }

    /// Same kind and dimensions, every statistic within `tol` (relative to its size, at
    /// least 1): a model trained with `other` reads this normaliser's units.
    pub fn approx_eq(&self, other: &Normalizer, tol: f64) -> bool {
        let close = |a: &[f64], b: &[f64]| {
            a.len() == b.len()
                && a.iter()
                    .zip(b)
                    .all(|(x, y)| (x - y).abs() <= tol * x.abs().max(y.abs()).max(1.0))
        };
        match (self, other) {
            (
                Normalizer::MeanStd { mean: m1, std: s1 },
                Normalizer::MeanStd { mean: m2, std: s2 },
            ) => close(m1, m2) && close(s1, s2),
            (Normalizer::MinMax(a), Normalizer::MinMax(b)) => {
                a.dims == b.dims && close(&a.min, &b.min) && close(&a.max, &b.max)
            }
            (Normalizer::None { dims: a }, Normalizer::None { dims: b }) => a == b,
            _ => false,
        }
    }

    pub fn dims(&self) -> usize {
        match self {
            Normalizer::MeanStd { mean, .. } => mean.len(),
            Normalizer::MinMax(m) => m.dims,
            Normalizer::None { dims } => *dims,
        }
    }

    /// Normalises `(N, dims)` rows in place.
    pub fn transform(&self, x: &mut [f32]) -> Result<(), String> {
        match self {
            Normalizer::MeanStd { mean, std } => {
                for row in x.chunks_exact_mut(mean.len()) {
                    for ((v, m), s) in row.iter_mut().zip(mean).zip(std) {
                        *v = ((*v as f64 - m) / s) as f32;
                    }
                }
                Ok(())
            }
            Normalizer::MinMax(m) => m.transform(x).map_err(|e| e.to_string()),
            Normalizer::None { .. } => Ok(()),
        }
    }

    /// Undoes [`Normalizer::transform`] in place.
    pub fn inverse(&self, x: &mut [f32]) -> Result<(), String> {
        match self {
            Normalizer::MeanStd { mean, std } => {
                for row in x.chunks_exact_mut(mean.len()) {
                    for ((v, m), s) in row.iter_mut().zip(mean).zip(std) {
                        *v = (*v as f64 * s + m) as f32;
                    }
                }
                Ok(())
            }
            Normalizer::MinMax(m) => m.inverse(x).map_err(|e| e.to_string()),
            Normalizer::None { .. } => Ok(()),
        }
    }

    /// Writes the JSON form atomically.
    pub fn save(&self, path: &Path) -> Result<(), TrainError> {
        let json = serde_json::to_vec_pretty(self).expect("normalizer serialises");
        dancegen_io::write_atomic(path, |w| w.write_all(&json)).map_err(|e| TrainError::io(path, e))
    }

    /// Reads the JSON form.
    pub fn load(path: &Path) -> Result<Self, TrainError> {
        let bytes = std::fs::read(path).map_err(|e| TrainError::io(path, e))?;
        let n: Normalizer = serde_json::from_slice(&bytes).map_err(|e| TrainError::io(path, e))?;
        let ok = match &n {
            Normalizer::MeanStd { mean, std } => mean.len() == std.len(),
            Normalizer::MinMax(m) => m.min.len() == m.dims && m.max.len() == m.dims,
            Normalizer::None { .. } => true,
        };
        if !ok {
            return Err(TrainError::io(path, "statistics of different lengths"));
        }
        Ok(n)
    }
}

/// Values per frame of a representation.
pub fn representation_dims(r: Representation) -> usize {
    match r {
        Representation::Edge151 => Edge151::DIMS,
        Representation::Lodge139 => Lodge139::DIMS,
        Representation::Humanml263 => 263,
        Representation::Duet => DuetFollower::DIMS + DuetLeader::DIMS,
        Representation::Group => GROUP_SLOTS * Edge151::DIMS,
        Representation::Holistic => HOLISTIC_DIMS,
    }
}

/// Values per frame of [`Representation::Holistic`]: body 263 + hands 360 + 52 ARKit weights.
pub const HOLISTIC_DIMS: usize =
    dancegen_motion::repr::holistic::split::BODY_HAND_DIMS + dancegen_motion::face::ARKIT_COUNT;

/// Dancer slots of a group frame (TCDiff++'s N_max; `dancegen_refine::formation` templates go
/// up to the same count).
pub const GROUP_SLOTS: usize = dancegen_refine::formation::shapes::MAX_DANCERS;

/// Per-channel mean and std of one dancer's EDGE-151 frames over the active slots of group
/// clips, roots relative to each clip's frame-0 centroid (group.md §5 P3: fitted once on the
/// training set, never per sample); no std below `std_floor` (`[data] std_floor`).
pub fn fit_group_normalizer(clips: &[Clip], std_floor: f64) -> Result<Normalizer, String> {
    let d = Edge151::DIMS;
    let mut per_dancer = Vec::new();
    for c in clips {
        let n = c.dancers.ok_or("a group normaliser needs group clips")?;
        let dims = GROUP_SLOTS * d;
        let (cx, cz) = group_centroid(&c.motion[..dims.min(c.motion.len())], n);
        for row in c.motion.chunks_exact(dims) {
            for s in 0..n {
                let mut v = row[s * d..(s + 1) * d].to_vec();
                v[ROOT_X] -= cx;
                v[ROOT_HORIZONTAL_2] -= cz;
                per_dancer.extend(v);
            }
        }
    }
    let one = Clip {
        source: PathBuf::new(),
        frames: per_dancer.len() / d,
        motion: per_dancer,
        music: None,
        genre: None,
        dancers: None,
    };
    let mut fitted = Normalizer::fit(NormalizerKind::MeanStd, std::slice::from_ref(&one), d)?;
    if let Normalizer::MeanStd { std, .. } = &mut fitted {
        for s in std.iter_mut() {
            *s = s.max(std_floor);
        }
    }
    Ok(fitted)
}

/// EDGE-151's Z-up root x and y channels (horizontal; `dancegen_nn::edge151::ROOT_HORIZONTAL`).
const ROOT_X: usize = 4;
const ROOT_HORIZONTAL_2: usize = 5;

/// Root centroid of the first `n` slots of one group frame.
fn group_centroid(frame: &[f32], n: usize) -> (f32, f32) {
    let d = Edge151::DIMS;
    let (mut x, mut z) = (0f32, 0f32);
    for s in 0..n {
        x += frame[s * d + ROOT_X];
        z += frame[s * d + ROOT_HORIZONTAL_2];
    }
    (x / n.max(1) as f32, z / n.max(1) as f32)
}

/// Reads one group clip directory: `dancer_0.npz`, `dancer_1.npz`, … at `c.fps`.
pub fn load_group_clip(dir: &Path, c: &DataConfig) -> Result<Clip, TrainError> {
    let data_err = |reason: String| TrainError::Data {
        path: dir.to_path_buf(),
        reason,
    };
    let mut dancers = Vec::new();
    for k in 0.. {
        let p = dir.join(format!("dancer_{k}.npz"));
        if !p.is_file() {
            break;
        }
        let mut d = load_dancers(&p, c)?;
        if d.len() != 1 {
            return Err(data_err(format!(
                "{}: {} dancers, expected one",
                p.display(),
                d.len()
            )));
        }
        dancers.push(d.pop().expect("one"));
    }
    let n = dancers.len();
    if !(2..=GROUP_SLOTS).contains(&n) {
        return Err(data_err(format!(
            "{n} dancer files (dancer_0.npz, …): a group clip has 2 to {GROUP_SLOTS}"
        )));
    }
    let enc: Vec<Vec<f32>> = dancers
        .iter()
        .map(Edge151::encode)
        .collect::<Result<_, _>>()
        .map_err(|e| data_err(e.to_string()))?;
    let d = Edge151::DIMS;
    let mut frames = enc.iter().map(|e| e.len() / d).min().unwrap_or(0);
    let music = match &c.music {
        Some(m) => {
            let (f, t) = load_music(dir, &m.dir, m.dims)?;
            frames = frames.min(t);
            Some(f[..frames * m.dims].to_vec())
        }
        None => None,
    };
    let mut motion = vec![0f32; frames * GROUP_SLOTS * d];
    for (k, e) in enc.iter().enumerate() {
        for f in 0..frames {
            motion[(f * GROUP_SLOTS + k) * d..(f * GROUP_SLOTS + k + 1) * d]
                .copy_from_slice(&e[f * d..(f + 1) * d]);
        }
    }
    Ok(Clip {
        source: dir.to_path_buf(),
        frames,
        motion,
        music,
        genre: None,
        dancers: Some(n),
    })
}

/// The clip directories under `paths` (each a directory of `dancer_<k>.npz`, sorted).
pub fn group_dirs(paths: &[PathBuf]) -> Result<Vec<PathBuf>, TrainError> {
    let mut out = Vec::new();
    for p in paths {
        let rd = std::fs::read_dir(p).map_err(|e| TrainError::io(p, e))?;
        let mut dirs: Vec<PathBuf> = rd
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|d| d.join("dancer_0.npz").is_file())
            .collect();
        dirs.sort();
        if dirs.is_empty() {
            return Err(TrainError::Data {
                path: p.clone(),
                reason: "no group clip directories (<clip>/dancer_0.npz …)".into(),
            });
        }
        out.extend(dirs);
    }
    Ok(out)
}

fn encode(r: Representation, m: &SmplMotion) -> Result<Vec<f32>, String> {
    match r {
        Representation::Edge151 => Edge151::encode(m),
        Representation::Lodge139 => Lodge139::encode(m),
        Representation::Humanml263 => HumanMl263::encode(m),
        Representation::Duet => unreachable!("duet clips are encoded in pairs (encode_duet)"),
        Representation::Group => unreachable!("group clips are read by load_group_clip"),
        Representation::Holistic => unreachable!("holistic clips are encoded by encode_holistic"),
    }
    .map_err(|e| e.to_string())
}

/// [`Representation::Holistic`] frames of an SMPL 24 body and its hands and face file: SMPL-H 52
/// = body joints 0–21 + the 30 finger joints, encoded as [`Holistic623`], permuted to SoulNet's
/// split layout, frame `t`'s face appended to row `t`.
fn encode_holistic(m: &SmplMotion, npz: &Path) -> Result<Vec<f32>, String> {
    use dancegen_motion::face::ARKIT_COUNT;
    use dancegen_motion::repr::holistic::{JOINTS, split};
    let members = dancegen_io::read_npz(npz).map_err(|e| e.to_string())?;
    let get = |name: &str, shape: &[usize]| -> Result<Vec<f32>, String> {
        let a = members
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, a)| a)
            .ok_or_else(|| format!("{}: no `{name}` array", npz.display()))?;
        if a.shape != shape {
            return Err(format!(
                "{}: `{name}` has shape {:?}, expected {shape:?} for a {}-frame body",
                npz.display(),
                a.shape,
                m.frames()
            ));
        }
        Ok(a.data.iter().map(|&v| v as f32).collect())
    };
    let t = m.frames();
    let hands = get("hands", &[t, JOINTS - 22, 3])?;
    let face = get("face", &[t, ARKIT_COUNT])?;
    let mut poses = Vec::with_capacity(t * JOINTS * 3);
    for f in 0..t {
        poses.extend_from_slice(&m.poses[f * 72..f * 72 + 22 * 3]);
        poses.extend_from_slice(&hands[f * 90..(f + 1) * 90]);
    }
    let inter = Holistic623::encode(&poses, &m.trans, m.fps).map_err(|e| e.to_string())?;
    let body_hands = split::to_split(&inter, 0).map_err(|e| e.to_string())?;
    let mut out = Vec::with_capacity((t - 1) * HOLISTIC_DIMS);
    for (f, row) in body_hands.chunks_exact(split::BODY_HAND_DIMS).enumerate() {
        out.extend_from_slice(row);
        out.extend_from_slice(&face[f * ARKIT_COUNT..(f + 1) * ARKIT_COUNT]);
    }
    Ok(out)
}

/// Duet frames `[follower 151 | leader 220]` of a follower and its leader (cut to the shorter).
fn encode_duet(follower: &SmplMotion, leader: &SmplMotion, sigma: f64) -> Result<Vec<f32>, String> {
    let t = follower.frames().min(leader.frames());
    let cut = |m: &SmplMotion| SmplMotion {
        fps: m.fps,
        poses: m.poses[..t * 72].to_vec(),
        trans: m.trans[..t * 3].to_vec(),
    };
    let (f, l) = (cut(follower), cut(leader));
    let fe = DuetFollower::encode(&f, &l, sigma).map_err(|e| e.to_string())?;
    let le = DuetLeader::encode(&l, sigma).map_err(|e| e.to_string())?;
    let mut out = Vec::with_capacity(t * (DuetFollower::DIMS + DuetLeader::DIMS));
    for (a, b) in fe
        .chunks_exact(DuetFollower::DIMS)
        .zip(le.chunks_exact(DuetLeader::DIMS))
    {
        out.extend_from_slice(a);
        out.extend_from_slice(b);
    }
    Ok(out)
}

/// One dancer of `path` at `c.fps` as SMPL 24 (BVH retargeted).
fn load_dancers(path: &Path, c: &DataConfig) -> Result<Vec<SmplMotion>, TrainError> {
    let data_err = |reason: String| TrainError::Data {
        path: path.to_path_buf(),
        reason,
    };
    let loaded = load_motion_file(path).map_err(|e| data_err(e.reason))?;
    let opts = ConvertOptions {
        fps: Some(c.fps),
        to_smpl24: matches!(loaded, LoadedMotion::Bvh(_)),
        ..Default::default()
    };
    match convert_motion(path, loaded, &opts).map_err(|e| data_err(e.reason))? {
        LoadedMotion::Smpl(m) => Ok(vec![m]),
        LoadedMotion::Group(g) => Ok(g),
        other => Err(data_err(format!(
            "{} has no joint rotations; {:?} needs SMPL rotations",
            other.kind(),
            c.representation
        ))),
    }
}

/// The motion files named by `paths` (directories expanded, sorted).
pub fn motion_files(paths: &[PathBuf]) -> Result<Vec<PathBuf>, TrainError> {
    let mut out = Vec::new();
    for p in paths {
        if p.is_dir() {
            let rd = std::fs::read_dir(p).map_err(|e| TrainError::io(p, e))?;
            let mut files: Vec<PathBuf> = rd
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|f| {
                    f.extension().and_then(|e| e.to_str()).is_some_and(|e| {
                        MOTION_EXTENSIONS.contains(&e.to_ascii_lowercase().as_str())
                    })
                })
                .collect();
            files.sort();
            if files.is_empty() {
                return Err(TrainError::Data {
                    path: p.clone(),
                    reason: format!("no motion files ({})", MOTION_EXTENSIONS.join(", ")),
                });
            }
            out.extend(files);
        } else {
            out.push(p.clone());
        }
    }
    Ok(out)
}

/// Reads and encodes one motion file: one clip per dancer.
pub fn load_clips(path: &Path, c: &DataConfig) -> Result<Vec<Clip>, TrainError> {
    let data_err = |reason: String| TrainError::Data {
        path: path.to_path_buf(),
        reason,
    };
    let dancers = load_dancers(path, c)?;
    let leader = match &c.leader {
        Some(dir) => {
            let stem = path.file_stem().unwrap_or_default();
            let lp = dir.join(stem).with_extension("npz");
            let mut l = load_dancers(&lp, c)?;
            if l.len() != 1 || dancers.len() != 1 {
                return Err(data_err(format!(
                    "a duet clip is one follower ({} dancers here) and one leader ({} in {})",
                    dancers.len(),
                    l.len(),
                    lp.display()
                )));
            }
            l.pop()
        }
        None => None,
    };
    let music = match &c.music {
        Some(m) => Some(load_music(path, &m.dir, m.dims)?),
        None => None,
    };
    let dims = representation_dims(c.representation);
    let mut clips = Vec::new();
    let holistic = match (c.representation, &c.holistic) {
        (Representation::Holistic, Some(dir)) => {
            let stem = path.file_stem().unwrap_or_default();
            Some(dir.join(stem).with_extension("npz"))
        }
        (Representation::Holistic, None) => {
            return Err(data_err(
                "representation \"holistic\" needs [data] holistic (the directory of the \
                 hands and faces, `dataset build --holistic`)"
                    .into(),
            ));
        }
        _ => None,
    };
    for m in &dancers {
        let mut motion = match (&leader, &holistic) {
            (Some(l), _) => encode_duet(m, l, c.heading_sigma),
            (None, Some(h)) => encode_holistic(m, h),
            (None, None) => encode(c.representation, m),
        }
        .map_err(data_err)?;
        let mut frames = motion.len() / dims;
        let music = music.as_ref().map(|(feat, t)| {
            frames = frames.min(*t);
            feat.clone()
        });
        motion.truncate(frames * dims);
        let music = music.map(|mut f| {
            f.truncate(frames * c.music.as_ref().map_or(0, |m| m.dims));
            f
        });
        clips.push(Clip {
            source: path.to_path_buf(),
            frames,
            motion,
            music,
            genre: None,
            dancers: None,
        });
    }
    Ok(clips)
}

/// `<dir>/<stem>.npy` as `(values, frames)`.
fn load_music(motion: &Path, dir: &Path, dims: usize) -> Result<(Vec<f32>, usize), TrainError> {
    let stem = motion.file_stem().unwrap_or_default();
    let path = dir.join(stem).with_extension("npy");
    let a = dancegen_io::read_npy(&path).map_err(|e| TrainError::Data {
        path: path.clone(),
        reason: format!("music features of {}: {e}", motion.display()),
    })?;
    match a.shape.as_slice() {
        [t, d] if *d == dims => Ok((a.data.iter().map(|&v| v as f32).collect(), *t)),
        shape => Err(TrainError::Data {
            path,
            reason: format!("music features of shape {shape:?}, expected (T, {dims})"),
        }),
    }
}

/// The data order's generator: the neural crate's one seeded RNG.
pub use dancegen_nn::rng::SplitMix64;

/// Seed of step-`step` randomness or of epoch `e`'s shuffle, derived from the run seed.
pub fn derive_seed(seed: u64, stream: u64, index: u64) -> u64 {
    let mut r = SplitMix64(seed ^ stream.wrapping_mul(0xD1B5_4A32_D192_ED03));
    r.0 ^= index.wrapping_mul(0x8CB9_2BA7_2F3D_8DD7);
    r.next_u64()
}

/// Where the data order stands: the next batch is `perm(epoch)[cursor..cursor + batch]`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct DataPosition {
    pub epoch: u64,
    pub cursor: usize,
}

/// All windows of all clips, normalised, with a seeded order.
pub struct WindowDataset {
    pub clips: Vec<Clip>,
    /// `(clip, start frame)` of every window.
    pub windows: Vec<(usize, usize)>,
    pub dims: usize,
    pub music_dims: usize,
    pub window: usize,
    pub batch_size: usize,
    pub seed: u64,
}

/// Stream ids of [`derive_seed`]: the shuffles and the batches' own seeds.
const SHUFFLE_STREAM: u64 = 1;
const BATCH_STREAM: u64 = 4;

/// The genres of a `dancegen dataset build` manifest (`manifest.json`: `genres` and per clip
/// `name` + `genre`).
#[derive(Clone, Debug)]
pub struct GenreManifest {
    pub genres: Vec<String>,
    by_name: std::collections::HashMap<String, usize>,
}

impl GenreManifest {
    pub fn load(path: &Path) -> Result<Self, TrainError> {
        #[derive(Deserialize)]
        struct ClipEntry {
            name: String,
            genre: String,
        }
        #[derive(Deserialize)]
        struct Manifest {
            genres: Vec<String>,
            clips: Vec<ClipEntry>,
        }
        let err = |reason: String| TrainError::Data {
            path: path.to_path_buf(),
            reason,
        };
        let text = std::fs::read_to_string(path).map_err(|e| TrainError::io(path, e))?;
        let m: Manifest =
            serde_json::from_str(&text).map_err(|e| err(format!("not a dataset manifest: {e}")))?;
        let mut by_name = std::collections::HashMap::new();
        for c in m.clips {
            let g = m.genres.iter().position(|g| *g == c.genre).ok_or_else(|| {
                err(format!(
                    "clip {}: genre {:?} is not in `genres`",
                    c.name, c.genre
                ))
            })?;
            by_name.insert(c.name, g);
        }
        Ok(Self {
            genres: m.genres,
            by_name,
        })
    }

    /// The genre of the clip stored in `motion_file` (matched by file stem).
    pub fn genre_of(&self, motion_file: &Path) -> Option<usize> {
        let stem = motion_file.file_stem()?.to_str()?;
        self.by_name.get(stem).copied()
    }
}

impl WindowDataset {
    /// Reads every file of `c.paths`; returns the raw clips (fit the normaliser on them, then
    /// call [`WindowDataset::new`]).
    pub fn read_clips(c: &DataConfig) -> Result<Vec<Clip>, TrainError> {
        let genres = match &c.manifest {
            Some(m) => Some(GenreManifest::load(m)?),
            None => None,
        };
        let mut clips = Vec::new();
        let files = if c.representation == Representation::Group {
            group_dirs(&c.paths)?
        } else {
            motion_files(&c.paths)?
        };
        for f in files {
            let mut loaded = if c.representation == Representation::Group {
                vec![load_group_clip(&f, c)?]
            } else {
                load_clips(&f, c)?
            };
            if let Some(g) = &genres {
                // Genre-conditioned models need every clip's genre: a clip missing from the
                // manifest is a data error here, not a panic in the middle of training.
                let genre = g.genre_of(&f).ok_or_else(|| TrainError::Data {
                    path: f.clone(),
                    reason: format!(
                        "not listed in the manifest {} (rebuild the data set, or drop [data] manifest)",
                        c.manifest.as_deref().unwrap_or(Path::new("?")).display()
                    ),
                })?;
                for clip in &mut loaded {
                    clip.genre = Some(genre);
                }
            }
            clips.extend(loaded);
        }
        Ok(clips)
    }

    /// Normalises `clips` and indexes their windows.
    pub fn new(
        mut clips: Vec<Clip>,
        c: &DataConfig,
        normalizer: &Normalizer,
        seed: u64,
    ) -> Result<Self, TrainError> {
        let dims = representation_dims(c.representation);
        if normalizer.dims() != dims {
            return Err(TrainError::Data {
                path: c.paths[0].clone(),
                reason: format!(
                    "the normaliser has {} dims, {:?} has {dims}",
                    normalizer.dims(),
                    c.representation
                ),
            });
        }
        let mut windows = Vec::new();
        for (i, clip) in clips.iter_mut().enumerate() {
            normalizer
                .transform(&mut clip.motion)
                .map_err(|reason| TrainError::Data {
                    path: clip.source.clone(),
                    reason,
                })?;
            if clip.frames < c.window {
                tracing::warn!(
                    "{}: {} frames, shorter than one {}-frame window; skipped",
                    clip.source.display(),
                    clip.frames,
                    c.window
                );
                continue;
            }
            windows.extend(
                (0..=clip.frames - c.window)
                    .step_by(c.stride)
                    .map(|s| (i, s)),
            );
        }
        if windows.len() < c.batch_size {
            return Err(TrainError::Data {
                path: c.paths[0].clone(),
                reason: format!(
                    "{} windows of {} frames, fewer than one batch of {}",
                    windows.len(),
                    c.window,
                    c.batch_size
                ),
            });
        }
        Ok(Self {
            clips,
            windows,
            dims,
            music_dims: c.music.as_ref().map_or(0, |m| m.dims),
            window: c.window,
            batch_size: c.batch_size,
            seed,
        })
    }

    /// The window order of `epoch`.
    pub fn permutation(&self, epoch: u64) -> Vec<usize> {
        let mut rng = SplitMix64(derive_seed(self.seed, SHUFFLE_STREAM, epoch));
        let mut p: Vec<usize> = (0..self.windows.len()).collect();
        for i in (1..p.len()).rev() {
            p.swap(i, rng.below(i + 1));
        }
        p
    }

    /// The window indices of the batch at `pos`, and the position after it.
    pub fn batch_indices(&self, pos: DataPosition) -> (Vec<usize>, DataPosition) {
        let mut pos = pos;
        if pos.cursor + self.batch_size > self.windows.len() {
            pos = DataPosition {
                epoch: pos.epoch + 1,
                cursor: 0,
            };
        }
        let perm = self.permutation(pos.epoch);
        let idx = perm[pos.cursor..pos.cursor + self.batch_size].to_vec();
        (
            idx,
            DataPosition {
                epoch: pos.epoch,
                cursor: pos.cursor + self.batch_size,
            },
        )
    }

    /// The batch at `pos` on `device`, and the position after it.
    pub fn batch(&self, pos: DataPosition, device: &Device) -> (Batch, DataPosition) {
        let (idx, next) = self.batch_indices(pos);
        let (b, w) = (idx.len(), self.window);
        let mut motion = Vec::with_capacity(b * w * self.dims);
        let mut music = Vec::with_capacity(b * w * self.music_dims);
        for &i in &idx {
            let (c, s) = self.windows[i];
            let clip = &self.clips[c];
            motion.extend_from_slice(&clip.motion[s * self.dims..(s + w) * self.dims]);
            if let Some(m) = &clip.music {
                music.extend_from_slice(&m[s * self.music_dims..(s + w) * self.music_dims]);
            }
        }
        let motion = Tensor::from_data(TensorData::new(motion, [b, w, self.dims]), device);
        let music = (self.music_dims > 0)
            .then(|| Tensor::from_data(TensorData::new(music, [b, w, self.music_dims]), device));
        let genre: Option<Vec<usize>> = idx
            .iter()
            .map(|&i| self.clips[self.windows[i].0].genre)
            .collect();
        let seed = derive_seed(
            self.seed,
            BATCH_STREAM,
            next.epoch.wrapping_mul(1 << 32) ^ next.cursor as u64,
        );
        let dancers: Option<Vec<usize>> = idx
            .iter()
            .map(|&i| self.clips[self.windows[i].0].dancers)
            .collect();
        (
            Batch {
                motion,
                music,
                genre,
                seed,
                dancers,
            },
            next,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two dancers over `frames` frames: channel 20 swings by ±1, channel 30 by ±1e-4.
    fn two_dancer_clip(frames: usize) -> Clip {
        let d = Edge151::DIMS;
        let mut motion = vec![0f32; frames * GROUP_SLOTS * d];
        for f in 0..frames {
            let sign = if f % 2 == 0 { 1.0 } else { -1.0 };
            for s in 0..2 {
                motion[(f * GROUP_SLOTS + s) * d + 20] = sign;
                motion[(f * GROUP_SLOTS + s) * d + 30] = 1.0 + sign * 1e-4;
            }
        }
        Clip {
            source: PathBuf::from("clip"),
            frames,
            motion,
            music: None,
            genre: None,
            dancers: Some(2),
        }
    }

    fn stds(n: &Normalizer) -> &[f64] {
        match n {
            Normalizer::MeanStd { std, .. } => std,
            _ => panic!("mean_std expected"),
        }
    }

    #[test]
    fn the_group_std_floor_lifts_only_the_channels_below_it() {
        let clips = [two_dancer_clip(10)];
        let plain = fit_group_normalizer(&clips, 0.0).unwrap();
        let floored = fit_group_normalizer(&clips, 0.05).unwrap();
        let (p, f) = (stds(&plain), stds(&floored));
        assert!((p[20] - 1.0).abs() < 1e-6 && (f[20] - 1.0).abs() < 1e-6);
        assert!((p[30] - 1e-4).abs() < 1e-5, "{}", p[30]);
        assert_eq!(f[30], 0.05);
        // Constant channels (std 0 → 1 by MIN_STD) stay at 1.
        assert_eq!(p[40], 1.0);
        assert_eq!(f[40], 1.0);
    }
}
