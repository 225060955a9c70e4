//! Reading `--pred` / `--gt` / `--leader` / `--gt-leader`: files and directories of motion, each
//! file one clip of one or more dancers, checked and cut by the protocol.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use dancegen_metrics::protocol::{Prepared, Protocol, RootHandling};

/// One input file: a solo clip (one dancer) or a group scene (`N ≥ 2` dancers, same length).
pub struct Clip {
    pub path: PathBuf,
    /// Each dancer after the protocol's root handling and cut (what the solo metrics see).
    pub dancers: Vec<Prepared>,
    /// Each dancer's world positions, only cut to the protocol's length: the group and duet
    /// references (GCD, Duolando) measure dancers relative to each other, so no root handling.
    pub placed: Vec<Vec<f64>>,
}

impl Clip {
    pub fn frames(&self) -> usize {
        self.dancers.first().map_or(0, |d| d.frames)
    }

    pub fn fps(&self) -> f64 {
        self.dancers.first().map_or(0.0, |d| d.fps)
    }

    pub fn is_group(&self) -> bool {
        self.dancers.len() > 1
    }

    pub fn placed_refs(&self) -> Vec<&[f64]> {
        self.placed.iter().map(Vec::as_slice).collect()
    }

    pub fn stem(&self) -> String {
        stem(&self.path)
    }
}

pub fn stem(p: &Path) -> String {
    p.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// One `--pred` / `--gt` / … input: a file or folder, or a clip already in memory (the
/// Python package's arrays), read as a `.npy` of the same shape would be.
#[derive(Clone, Debug)]
pub enum Input {
    Path(PathBuf),
    Array(ClipArray),
}

impl From<PathBuf> for Input {
    fn from(p: PathBuf) -> Self {
        Input::Path(p)
    }
}

/// Joint positions in memory: `(T, J, 3)` for one dancer or `(N, T, J, 3)` for a scene, in
/// C order. `name` stands for the file stem: clips pair by it (`mpjpe`, duet leaders) and it
/// names the clip in `per_clip` and in errors.
#[derive(Clone, Debug)]
pub struct ClipArray {
    pub name: String,
    pub shape: Vec<usize>,
    pub data: Vec<f64>,
}

/// Motion files of the inputs: files as given, directories expanded (sorted); arrays as
/// given.
fn collect_files(inputs: &[Input]) -> Result<Vec<Input>> {
    const EXT: [&str; 4] = ["npy", "pkl", "npz", "bvh"];
    let mut out = Vec::new();
    for input in inputs {
        let input = match input {
            Input::Array(a) => {
                out.push(Input::Array(a.clone()));
                continue;
            }
            Input::Path(p) => p,
        };
        if input.is_dir() {
            let mut found: Vec<PathBuf> = std::fs::read_dir(input)
                .with_context(|| format!("reading {}", input.display()))?
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| {
                    p.is_file()
                        && p.extension()
                            .and_then(|e| e.to_str())
                            .is_some_and(|e| EXT.contains(&e.to_ascii_lowercase().as_str()))
                })
                .collect();
            if found.is_empty() {
                bail!(
                    "{}: directory holds no motion files (.npy, .pkl, .npz, .bvh)",
                    input.display()
                );
            }
            found.sort();
            out.extend(found.into_iter().map(Input::Path));
        } else if input.is_file() {
            out.push(Input::Path(input.clone()));
        } else {
            bail!("{}: no such file or directory", input.display());
        }
    }
    Ok(out)
}

/// Every clip of `inputs`. `fps`: the rate of `.npy` inputs (`--fps`); `source_fps`: the rate
/// every input was sampled at, whatever its header says (`--source-fps`).
pub fn load_set(
    inputs: &[Input],
    protocol: &Protocol,
    fps: Option<f64>,
    source_fps: Option<f64>,
) -> Result<Vec<Clip>> {
    collect_files(inputs)?
        .into_iter()
        .map(|input| match input {
            Input::Path(path) => load_clip(&path, protocol, fps, source_fps)
                .with_context(|| format!("{}", path.display())),
            Input::Array(a) => {
                let name = a.name.clone();
                let raw = raw_of_array(a)?;
                clip_of(PathBuf::from(&name), raw, protocol, fps, source_fps)
                    .with_context(|| format!("array {name}"))
            }
        })
        .collect()
}

/// The dancers of an array, as [`read_raw`] reads a `.npy` of that shape.
fn raw_of_array(a: ClipArray) -> Result<Raw> {
    let ClipArray { name, shape, data } = a;
    let (dancers, j) = match shape.as_slice() {
        [t, j, 3] if *t > 0 && *j > 0 => (1, *j),
        [n, t, j, 3] if *n > 0 && *t > 0 && *j > 0 => (*n, *j),
        s => bail!("array {name}: expected joints (T, J, 3) or (N, T, J, 3), got shape {s:?}"),
    };
    if data.len() != shape.iter().product::<usize>() {
        bail!("array {name}: {} values for shape {shape:?}", data.len());
    }
    let per = data.len() / dancers;
    Ok((
        data.chunks_exact(per).map(<[f64]>::to_vec).collect(),
        j,
        None,
    ))
}

/// Raw joints of a file: `(dancers, joints per dancer, frame rate stored in the file)`.
type Raw = (Vec<Vec<f64>>, usize, Option<f64>);

fn read_raw(path: &Path, source_fps: Option<f64>) -> Result<Raw> {
    let is_npy = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("npy"));
    if is_npy {
        let a = dancegen_io::read_npy(path)?;
        match a.shape.as_slice() {
            [_, j, 3] => return Ok((vec![a.data], *j, None)),
            [n, t, j, 3] => {
                if *n == 0 || *t == 0 || *j == 0 {
                    bail!("empty group array of shape {:?}", a.shape);
                }
                let per = t * j * 3;
                let dancers = a.data.chunks_exact(per).map(<[f64]>::to_vec);
                return Ok((dancers.collect(), *j, None));
            }
            // Other layouts (FineDance (T, 315), EDGE (T, 151)) go through the motion library.
            _ => {}
        }
    }
    let read = dancegen_formats::dispatch::LoadOptions {
        source_fps,
        ..Default::default()
    };
    let m = dancegen_formats::dispatch::load_motion_file_with(path, &read)?;
    let fps = f64::from(m.fps());
    let (shape, p) = dancegen_formats::dispatch::joint_positions(path, &m)?;
    let p: Vec<f64> = p.into_iter().map(f64::from).collect();
    // A raw-joints .npy stores no frame rate even when the library reads it.
    let file_fps = (!is_npy).then_some(fps);
    match shape.as_slice() {
        [_, j, 3] => Ok((vec![p], *j, file_fps)),
        [n, t, j, 3] if *n > 0 && *t > 0 && *j > 0 => Ok((
            p.chunks_exact(t * j * 3).map(<[f64]>::to_vec).collect(),
            *j,
            file_fps,
        )),
        s => bail!("expected (T, J, 3) or (N, T, J, 3) joints, got shape {s:?}"),
    }
}

/// Reads one clip (Y-up joints, one or more dancers) and applies the protocol to each dancer.
fn load_clip(
    path: &Path,
    protocol: &Protocol,
    fps_arg: Option<f64>,
    source_fps: Option<f64>,
) -> Result<Clip> {
    let raw = read_raw(path, source_fps)?;
    clip_of(path.to_path_buf(), raw, protocol, fps_arg, source_fps)
}

/// A clip of raw dancers read from `path` (or named so), the protocol applied to each.
fn clip_of(
    path: PathBuf,
    (raw, joints, file_fps): Raw,
    protocol: &Protocol,
    fps_arg: Option<f64>,
    source_fps: Option<f64>,
) -> Result<Clip> {
    // A raw-joints .npy has no header: --source-fps is its rate.
    let fps_arg = fps_arg.or(source_fps);
    let fps = match (file_fps, fps_arg, protocol.fps) {
        (Some(f), Some(a), _) if (f - a).abs() > 1e-3 => {
            bail!(
                "the file is at {f} fps but --fps {a} was given; resample with `dancegen convert --fps`"
            )
        }
        (Some(f), _, _) => f,
        (None, Some(a), _) => a,
        (None, None, Some(p)) => p,
        (None, None, None) => bail!("a .npy stores no frame rate: give --fps"),
    };
    // One body per dancer, within the bounds every motion reader applies (the .npy joints and
    // arrays read here do not pass through the motion library).
    for (i, d) in raw.iter().enumerate() {
        dancegen_formats::body_check::joint_array(d, joints).map_err(|e| {
            if raw.len() > 1 {
                anyhow::anyhow!("dancer {i}, {e}")
            } else {
                anyhow::anyhow!("{e}")
            }
        })?;
    }
    let as_given = Protocol {
        root: RootHandling::AsGiven,
        ..*protocol
    };
    let mut dancers = Vec::with_capacity(raw.len());
    let mut placed = Vec::with_capacity(raw.len());
    for (i, d) in raw.iter().enumerate() {
        let who = || {
            if raw.len() > 1 {
                format!("dancer {i}")
            } else {
                "motion".to_string()
            }
        };
        dancers.push(protocol.prepare(d, joints, fps).with_context(who)?);
        placed.push(as_given.prepare(d, joints, fps).with_context(who)?.joints);
    }
    Ok(Clip {
        path,
        dancers,
        placed,
    })
}
