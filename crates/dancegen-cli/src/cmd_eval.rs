//! `dancegen eval`: dance metrics of generated motion (and ground truth) under a paper's protocol.
//!
//! Per clip: `bas` (beat align score, needs `--beats` or `--music`), `pfc` (EDGE, on the Z-up
//! rotation `(x, −z, y)` of the Y-up joints), `fsr` (LODGE foot-skating ratio), `mpjpe` (paired
//! with the `--gt` clip of the same file stem), `freeze`, `boundary_jerk` (boundaries every 150
//! frames, EDGE's 5-second windows at 30 fps). Over the set: `fid_k`, `fid_g`, `div_k`, `div_g`
//! (Bailando: features normalised by the GT statistics; without `--gt`, `div_*` is the
//! diversity of the raw features). A set value is the mean over the clips where the metric is
//! defined; undefined clips are `null` in `per_clip` and warned about. `pfc` is scaled by 10⁴ as
//! EDGE prints it.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use dancegen_metrics::bas::{self, Variant};
use dancegen_metrics::fid::EPS_BAILANDO;
use dancegen_metrics::protocol::{Prepared, Protocol};
use dancegen_metrics::{KineticVariant, diversity, frechet_distance, normalize_by_gt};
use serde_json::{Value, json};

use crate::cli::{BasVariantArg, EvalArgs, ProtocolArg};

/// Metrics `eval` computes.
const AVAILABLE: [&str; 10] = [
    "fid_k",
    "fid_g",
    "div_k",
    "div_g",
    "bas",
    "pfc",
    "fsr",
    "mpjpe",
    "freeze",
    "boundary_jerk",
];

/// Contract metrics not computed by `eval` yet.
const NOT_YET: [&str; 6] = ["gmr", "gmc", "tif", "fid_cd", "div_cd", "bed"];

/// Frames between the boundaries of `boundary_jerk` (EDGE's 5 s windows at 30 fps).
const BOUNDARY_EVERY: usize = 150;

/// Per-clip metrics, in table order.
const PER_CLIP: [&str; 6] = ["bas", "pfc", "fsr", "mpjpe", "freeze", "boundary_jerk"];

struct Clip {
    path: PathBuf,
    prep: Prepared,
}

pub fn run(args: &EvalArgs, _quiet: bool) -> Result<()> {
    let protocol = match args.protocol {
        ProtocolArg::AistppBailando => dancegen_metrics::protocol::AISTPP_BAILANDO,
        ProtocolArg::FinedanceLodge => dancegen_metrics::protocol::FINEDANCE_LODGE,
        ProtocolArg::Edge5s => dancegen_metrics::protocol::EDGE_5S,
        ProtocolArg::None => dancegen_metrics::protocol::NONE,
    };
    let variant = match args.bas_variant {
        BasVariantArg::Bailando => Variant::Bailando,
        BasVariantArg::Lodge => Variant::Lodge,
        BasVariantArg::Fact => Variant::Fact,
        BasVariantArg::Gcd => Variant::Gcd,
    };
    let have_gt = !args.gt.is_empty();
    let have_beats = args.beats.is_some() || args.music.is_some();
    let mut metrics: Vec<String> = match &args.metrics {
        Some(list) => {
            let mut out = Vec::new();
            for m in list.split(',').map(str::trim).filter(|m| !m.is_empty()) {
                if NOT_YET.contains(&m) {
                    bail!("metric {m} is not yet available in eval (group/duet metrics)");
                }
                if !AVAILABLE.contains(&m) {
                    bail!("unknown metric {m}; known: {}", AVAILABLE.join(","));
                }
                if matches!(m, "fid_k" | "fid_g" | "mpjpe") && !have_gt {
                    bail!("metric {m} needs --gt");
                }
                if m == "bas" && !have_beats {
                    bail!("metric bas needs --beats or --music");
                }
                if !out.iter().any(|o| o == m) {
                    out.push(m.to_string());
                }
            }
            if out.is_empty() {
                bail!("--metrics is empty");
            }
            out
        }
        None => AVAILABLE
            .iter()
            .filter(|m| match **m {
                "fid_k" | "fid_g" | "mpjpe" => have_gt,
                "bas" => have_beats,
                _ => true,
            })
            .map(|m| m.to_string())
            .collect(),
    };

    let pred = load_set(&args.pred, &protocol, args.fps).context("--pred")?;
    let gt = if have_gt {
        load_set(&args.gt, &protocol, args.fps).context("--gt")?
    } else {
        Vec::new()
    };

    // By default mpjpe only when some --pred clip has a --gt clip of the same file stem.
    if args.metrics.is_none() {
        let gt_stems: Vec<String> = gt.iter().map(|c| stem(&c.path)).collect();
        if !pred.iter().any(|c| gt_stems.contains(&stem(&c.path))) {
            metrics.retain(|m| m != "mpjpe");
        }
    }
    let want = |m: &str| metrics.iter().any(|x| x == m);

    let music_beats = if want("bas") {
        Some(music_beats(args, &pred)?)
    } else {
        None
    };

    let mut summary: BTreeMap<String, Value> = BTreeMap::new();

    // Set metrics: FID / Div on kinetic and geometric features.
    for (kind, fid_key, div_key) in [("k", "fid_k", "div_k"), ("g", "fid_g", "div_g")] {
        if !(want(fid_key) || want(div_key)) {
            continue;
        }
        let feats = |set: &[Clip]| -> Result<Vec<Vec<f64>>> {
            set.iter()
                .map(|c| features(c, kind, &protocol))
                .collect::<Result<_>>()
        };
        let p = feats(&pred)?;
        if have_gt {
            let g = feats(&gt)?;
            let (g_n, p_n) = normalize_by_gt(&g, &p);
            if want(fid_key) {
                summary.insert(
                    fid_key.into(),
                    num(frechet_distance(&p_n, &g_n, EPS_BAILANDO)),
                );
            }
            if want(div_key) {
                summary.insert(div_key.into(), num(diversity(&p_n)));
                summary.insert(format!("{div_key}_gt"), num(diversity(&g_n)));
            }
        } else if want(div_key) {
            tracing::warn!(
                "{div_key} without --gt: diversity of the raw (not GT-normalised) features"
            );
            summary.insert(div_key.into(), num(diversity(&p)));
        }
        if p.len() < 2 && want(div_key) {
            tracing::warn!("{div_key} needs at least two clips");
        }
    }

    // Per-clip metrics.
    let gt_by_stem: BTreeMap<String, &Clip> = gt.iter().map(|c| (stem(&c.path), c)).collect();
    let mut per_clip = Vec::new();
    let mut columns: BTreeMap<&str, Vec<Option<f64>>> = BTreeMap::new();
    for clip in &pred {
        let mut row = serde_json::Map::new();
        row.insert("file".into(), json!(clip.path.display().to_string()));
        row.insert("frames".into(), json!(clip.prep.frames));
        for m in PER_CLIP.into_iter().filter(|m| want(m)) {
            let v = match m {
                "bas" => clip_bas(clip, music_beats.as_deref().unwrap_or(&[]), variant)?,
                "mpjpe" => match gt_by_stem.get(&stem(&clip.path)) {
                    Some(g) => clip_mpjpe(clip, g),
                    None => {
                        tracing::warn!(
                            "{}: no --gt clip with the same file stem; mpjpe skipped",
                            clip.path.display()
                        );
                        None
                    }
                },
                other => clip_metric(other, &clip.prep)
                    .with_context(|| format!("{}: {other}", clip.path.display()))?,
            };
            if v.is_none() && m != "mpjpe" {
                tracing::warn!(
                    "{}: {m} is undefined for this clip (excluded from the mean)",
                    clip.path.display()
                );
            }
            row.insert(m.into(), v.map_or(Value::Null, num));
            columns.entry(m).or_default().push(v);
        }
        per_clip.push(Value::Object(row));
    }
    for m in PER_CLIP.into_iter().filter(|m| want(m)) {
        let vals: Vec<f64> = columns
            .get(m)
            .into_iter()
            .flatten()
            .flatten()
            .copied()
            .collect();
        let mean = mean(&vals).map(|v| {
            if m == "pfc" {
                v * dancegen_metrics::pfc::PFC_SCALE
            } else {
                v
            }
        });
        summary.insert(m.into(), mean.map_or(Value::Null, num));
    }
    if want("bas") && have_gt {
        let mut vals = Vec::new();
        for c in &gt {
            match clip_bas(c, music_beats.as_deref().unwrap_or(&[]), variant)? {
                Some(v) => vals.push(v),
                None => tracing::warn!(
                    "{}: bas is undefined for this clip (excluded from bas_gt)",
                    c.path.display()
                ),
            }
        }
        summary.insert("bas_gt".into(), mean(&vals).map_or(Value::Null, num));
    }

    print_table(&summary, &protocol, pred.len(), gt.len());
    if let Some(out) = &args.json {
        let mut obj = serde_json::Map::new();
        for (k, v) in &summary {
            obj.insert(k.clone(), v.clone());
        }
        obj.insert("protocol".into(), json!(protocol.name));
        obj.insert("per_clip".into(), Value::Array(per_clip));
        let text = serde_json::to_string_pretty(&Value::Object(obj))?;
        std::fs::write(out, text + "\n").with_context(|| format!("writing {}", out.display()))?;
    }
    Ok(())
}

fn num(v: f64) -> Value {
    if v.is_finite() { json!(v) } else { Value::Null }
}

fn mean(v: &[f64]) -> Option<f64> {
    (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
}

fn stem(p: &Path) -> String {
    p.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
}

fn print_table(summary: &BTreeMap<String, Value>, protocol: &Protocol, n_pred: usize, n_gt: usize) {
    println!(
        "protocol {} ({n_pred} generated, {n_gt} ground-truth clips)",
        protocol.name
    );
    for (k, v) in summary {
        match v.as_f64() {
            Some(x) => println!("{k:<14} {x:.6}"),
            None => println!("{k:<14} undefined"),
        }
    }
}

/// Motion files of `--pred` / `--gt`: files as given, directories expanded (sorted).
fn collect_files(inputs: &[PathBuf]) -> Result<Vec<PathBuf>> {
    const EXT: [&str; 4] = ["npy", "pkl", "npz", "bvh"];
    let mut out = Vec::new();
    for input in inputs {
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
            out.extend(found);
        } else if input.is_file() {
            out.push(input.clone());
        } else {
            bail!("{}: no such file or directory", input.display());
        }
    }
    Ok(out)
}

fn load_set(inputs: &[PathBuf], protocol: &Protocol, fps: Option<f64>) -> Result<Vec<Clip>> {
    collect_files(inputs)?
        .into_iter()
        .map(|path| {
            let prep =
                load_clip(&path, protocol, fps).with_context(|| format!("{}", path.display()))?;
            Ok(Clip { path, prep })
        })
        .collect()
}

/// Reads one clip as `(T, 24, 3)` Y-up joints and applies the protocol.
fn load_clip(path: &Path, protocol: &Protocol, fps_arg: Option<f64>) -> Result<Prepared> {
    let is_npy = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("npy"));
    let (shape, data, file_fps) = if is_npy && npy_is_joints(path)? {
        let a = dancegen_io::read_npy(path)?;
        (a.shape, a.data, None)
    } else {
        let m = dancegen_motion::formats::load_motion_file(path)?;
        if matches!(m, dancegen_motion::formats::LoadedMotion::Group(_)) {
            bail!("group motion is not yet available in eval (gmr, gmc, tif)");
        }
        let fps = m.fps() as f64;
        let (shape, p) = dancegen_motion::formats::joint_positions(path, &m)?;
        let from_npy = is_npy;
        (
            shape,
            p.into_iter().map(f64::from).collect(),
            (!from_npy).then_some(fps),
        )
    };
    if shape.len() != 3 || shape[2] != 3 {
        bail!("expected (T, J, 3) joints, got shape {shape:?}");
    }
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
    Ok(protocol.prepare(&data, shape[1], fps)?)
}

/// `true` for a `(T, J, 3)` `.npy` (read directly), `false` for other layouts (FineDance `(T, 315)`).
fn npy_is_joints(path: &Path) -> Result<bool> {
    let a = dancegen_io::read_npy(path)?;
    Ok(a.shape.len() == 3 && a.shape[2] == 3)
}

/// Kinetic (`k`) or geometric (`g`) features of a clip, stored as float32 as the references do.
fn features(c: &Clip, kind: &str, protocol: &Protocol) -> Result<Vec<f64>> {
    let f: Vec<f64> = if kind == "k" {
        let k = dancegen_metrics::try_kinetic_features(
            &c.prep.joints,
            c.prep.frame_time,
            KineticVariant::Reference,
        )
        .with_context(|| format!("{}", c.path.display()))?;
        k[..protocol.kinetic_dims()].to_vec()
    } else {
        dancegen_metrics::try_manual_features(&c.prep.joints)
            .with_context(|| format!("{}", c.path.display()))?
            .to_vec()
    };
    Ok(f.into_iter().map(|v| v as f32 as f64).collect())
}

fn clip_metric(m: &str, p: &Prepared) -> Result<Option<f64>> {
    Ok(match m {
        "pfc" => {
            let mut z = p.joints.clone();
            for v in z.chunks_exact_mut(3) {
                let (y, zz) = (v[1], v[2]);
                v[1] = -zz;
                v[2] = y;
            }
            dancegen_metrics::pfc::pfc_clip_score(&z, 24)
        }
        "fsr" => {
            let r = dancegen_metrics::foot_skating::foot_skating_ratio(&p.joints, 24).ratio();
            r.is_finite().then_some(r)
        }
        "freeze" => dancegen_metrics::longform::motion_freezing(&p.joints, p.fps)?,
        "boundary_jerk" => {
            let b: Vec<usize> = (1..)
                .map(|i| i * BOUNDARY_EVERY)
                .take_while(|&b| b < p.frames)
                .collect();
            if b.is_empty() {
                None
            } else {
                dancegen_metrics::longform::boundary_jerk_ratio(&p.joints, p.fps, &b)?
            }
        }
        other => unreachable!("per-clip metric {other}"),
    })
}

fn clip_mpjpe(c: &Clip, g: &Clip) -> Option<f64> {
    let n = c.prep.frames.min(g.prep.frames);
    if c.prep.frames != g.prep.frames {
        tracing::warn!(
            "{}: {} frames vs {} in the GT; mpjpe over the first {n}",
            c.path.display(),
            c.prep.frames,
            g.prep.frames
        );
    }
    let len = n * dancegen_metrics::FRAME_LEN;
    dancegen_metrics::mpjpe::mpjpe_mean(&g.prep.joints[..len], &c.prep.joints[..len], 24)
}

fn clip_bas(c: &Clip, music: &[usize], variant: Variant) -> Result<Option<f64>> {
    let motion = bas::try_motion_beats(&c.prep.joints, variant)
        .with_context(|| format!("{}", c.path.display()))?;
    let music = bas::clip_music_beats(music, c.prep.frames, variant);
    Ok(bas::beat_align_score(&music, &motion, variant))
}

/// Music-beat frame indices from `--beats` (`.npy` of indices, or a 35-dim feature file whose
/// last column is the beat flag) or `--music` (computed at the clips' frame rate).
fn music_beats(args: &EvalArgs, clips: &[Clip]) -> Result<Vec<usize>> {
    if let Some(path) = &args.beats {
        let a = dancegen_io::read_npy(path).with_context(|| format!("{}", path.display()))?;
        return Ok(match a.shape.as_slice() {
            [_] => a
                .data
                .iter()
                .map(|&v| v.round().max(0.0) as usize)
                .collect(),
            [_, d] if *d > 0 => a
                .data
                .chunks(*d)
                .enumerate()
                .filter(|(_, row)| row[d - 1] > 0.0)
                .map(|(i, _)| i)
                .collect(),
            s => bail!(
                "{}: expected beat indices (N,) or features (T, D), got shape {s:?}",
                path.display()
            ),
        });
    }
    let Some(audio) = &args.music else {
        bail!("bas needs --beats or --music");
    };
    let fps = clips.first().map_or(30.0, |c| c.prep.fps);
    if clips.iter().any(|c| (c.prep.fps - fps).abs() > 1e-3) {
        bail!("--music needs all clips at one frame rate");
    }
    let fps_u = fps.round() as u32;
    if fps_u != 30 && fps_u != 60 {
        bail!("--music computes beats at 30 or 60 fps; the motion is at {fps} fps");
    }
    let opts = dancegen_music::features::ExtractOptions {
        fps: fps_u,
        ..Default::default()
    };
    let f = dancegen_music::features::extract(
        &dancegen_music::decode::AudioSource::File(audio.clone()),
        &opts,
    )?;
    Ok(f.beat_frames)
}
