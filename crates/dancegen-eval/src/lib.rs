//! Dance metrics of generated motion (and ground truth) under a paper's protocol, over files:
//! what `dancegen eval` computes ([`evaluate`]), for every front end (the CLI prints it as a
//! table and writes it as `--json`; the Python package returns it as a dict). The metrics
//! themselves are `dancegen_metrics`' (pure functions of arrays); this crate reads the clips,
//! pairs them, chooses the metrics the inputs allow and assembles the report. Options are named
//! as `dancegen eval`'s flags, and errors say the flag (`--gt`).
//!
//! Inputs are clips: a solo clip is one dancer; a group scene (`(N, T, 24, 3)` `.npy` or a group
//! motion file) holds `N` dancers of equal length.
//!
//! - Solo metrics, per clip: `bas` (needs `--beats` or `--music`), `pfc` (EDGE, on the Z-up
//!   rotation `(x, −z, y)`), `fsr` (LODGE foot-skating ratio), `mpjpe` (against the `--gt` clip of
//!   the same file stem), `freeze`, `inverted` (share of upside-down frames, ours: see
//!   `dancegen_metrics::posture`), `boundary_jerk` (boundaries every `--window` frames, default 150:
//!   EDGE's 5-second windows at 30 fps), `fsd` (Duolando foot-skating duration in %, pooled over all clips' frame
//!   steps as the reference prints it), `penetration` (percent of forearm/hand samples inside
//!   another body part, on the capsule body: our approximation of Lodge++'s self-penetration
//!   ratio, see `dancegen_metrics::penetration`). Over the set: `fid_k`, `fid_g`, `div_k`,
//!   `div_g` (Bailando: features normalised by the GT statistics; without `--gt`, `div_*` is the
//!   diversity of the raw features). In a scene every dancer counts as a solo sequence (TCDiff);
//!   its per-clip value is the mean over its dancers. `pfc` is scaled by 10⁴ as EDGE prints it.
//! - Group metrics (scenes only, world positions): `gmr` (set, needs `--gt` scenes), `gmc`,
//!   `tif` (per scene).
//! - Duet metrics (Duolando, world positions): the follower is the `--pred` clip and its leader
//!   the `--leader` clip of the same stem (`--gt-leader` for `--gt`), or a two-dancer clip is
//!   `[leader, follower]`. `fid_cd` (needs GT duets), `div_cd` over the set; per duet `bed`,
//!   `ipr` (share of frames in which the two capsule bodies intersect) and `contact_range`
//!   (share of frames within `dancegen_metrics::duet::CONTACT_RANGE_M` of touching).
//! - Genre control: `genre` (needs `--gt`, `--gt-genres` and `--want-genre`) fits a
//!   nearest-centroid classifier on the kinetic features of the `--gt` clips (the `fid_k`
//!   features under the same protocol, genres from the data set manifest) and reports the share
//!   of `--pred` dancers it assigns to the requested genre, with chance levels and the
//!   classifier's leave-one-out accuracy on the real clips; per clip, the assigned genre.
//!
//! A set value is the mean over the clips where the metric is defined; undefined clips are
//! `null` in `per_clip` and warned about.

mod duet;
mod genre;
mod group;
mod input;
mod physical;
pub mod report;
mod solo;

use std::collections::BTreeMap;

use anyhow::{Context, Result, bail};
use dancegen_metrics::bas::Variant;
use dancegen_metrics::fid::EPS_BAILANDO;
use dancegen_metrics::{diversity, frechet_distance, normalize_by_gt};
use serde_json::{Value, json};

use dancegen_metrics::protocol::Protocol;
use input::Clip;
pub use input::{ClipArray, Input};
use std::path::PathBuf;

/// The metrics `eval` knew before the physical figures ([`all_metrics`] adds them), in table
/// order (names are a contract: external checks read them).
const METRICS: [&str; 24] = [
    "fid_k",
    "fid_g",
    "div_k",
    "div_g",
    "bas",
    "pfc",
    "fsr",
    "fsd",
    "mpjpe",
    "penetration",
    "gmr",
    "gmc",
    "tif",
    "collision",
    "min_distance",
    "fid_cd",
    "div_cd",
    "bed",
    "ipr",
    "contact_range",
    "freeze",
    "inverted",
    "boundary_jerk",
    "genre",
];

/// Metrics with one value per clip, in `per_clip` order ([`per_clip_metrics`] adds the
/// physical figures).
const PER_CLIP: [&str; 16] = [
    "bas",
    "pfc",
    "fsr",
    "fsd",
    "mpjpe",
    "penetration",
    "freeze",
    "inverted",
    "boundary_jerk",
    "gmc",
    "tif",
    "collision",
    "min_distance",
    "bed",
    "ipr",
    "contact_range",
];

/// Every metric name, in table order: [`METRICS`], then the physical figures.
fn all_metrics() -> impl Iterator<Item = &'static str> {
    METRICS.into_iter().chain(dancegen_metrics::physical::KEYS)
}

/// Every per-clip metric, in `per_clip` order: [`PER_CLIP`], then the physical figures.
fn per_clip_metrics() -> impl Iterator<Item = &'static str> {
    PER_CLIP.into_iter().chain(dancegen_metrics::physical::KEYS)
}

/// Names that stand for several metrics in `--metrics`.
const GROUPS: [(&str, &str); 2] = [
    ("physical", "the physical-plausibility figures"),
    ("all", "every metric the inputs allow (the default)"),
];

/// What the inputs offer, to choose the default metrics and reject impossible requests.
struct Offer {
    gt: bool,
    beats: bool,
    pred_groups: bool,
    gt_groups: bool,
    pred_duets: bool,
    gt_duets: bool,
    gt_genres: bool,
    want_genre: bool,
}

impl Offer {
    /// `Err(reason)` if metric `m` cannot be computed from these inputs.
    fn check(&self, m: &str) -> Result<(), &'static str> {
        match m {
            "fid_k" | "fid_g" | "mpjpe" if !self.gt => Err("needs --gt"),
            "bas" if !self.beats => Err("needs --beats or --music"),
            "gmr" if !(self.pred_groups && self.gt_groups) => {
                Err("needs group scenes (N, T, 24, 3) in both --pred and --gt")
            }
            "gmc" | "tif" | "collision" | "min_distance" if !self.pred_groups => {
                Err("needs group scenes (N, T, 24, 3) in --pred")
            }
            "fid_cd" if !(self.pred_duets && self.gt_duets) => {
                Err("needs duets in --pred and --gt (--leader / --gt-leader, or two-dancer clips)")
            }
            "div_cd" | "bed" | "ipr" | "contact_range" if !self.pred_duets => {
                Err("needs duets in --pred (--leader, or two-dancer clips)")
            }
            "genre" if !self.gt => {
                Err("needs --gt (the real clips the genre classifier is fit on)")
            }
            "genre" if !self.gt_genres => {
                Err("needs --gt-genres (the data set manifest giving each --gt clip's genre)")
            }
            "genre" if !self.want_genre => {
                Err("needs --want-genre (the genre the --pred dances were asked for)")
            }
            _ => Ok(()),
        }
    }

    /// Whether `m` is computed when `--metrics` is not given.
    fn default_on(&self, m: &str, args: &EvalOptions) -> bool {
        match m {
            // Duet metrics by default only when leaders are given: a two-dancer scene is a group
            // unless the user asks for duet metrics.
            "fid_cd" | "div_cd" | "bed" | "ipr" | "contact_range" => {
                !args.leader.is_empty() && self.check(m).is_ok()
            }
            _ => self.check(m).is_ok(),
        }
    }
}

/// `--metrics`: the names asked for (`physical` expanded), or `None` when `all` is among them.
fn parse_metric_list(list: &str) -> Result<Option<Vec<String>>> {
    let mut out: Vec<String> = Vec::new();
    let mut all = false;
    let push = |m: &str, out: &mut Vec<String>| {
        if !out.iter().any(|o| o == m) {
            out.push(m.to_string());
        }
    };
    for m in list.split(',').map(str::trim).filter(|m| !m.is_empty()) {
        match m {
            "all" => all = true,
            "physical" => {
                for k in dancegen_metrics::physical::KEYS {
                    push(k, &mut out);
                }
            }
            _ if all_metrics().any(|k| k == m) => push(m, &mut out),
            _ => bail!(
                "unknown metric {m}; known: {}, or a group: {}",
                all_metrics().collect::<Vec<_>>().join(","),
                GROUPS.map(|(g, what)| format!("{g} ({what})")).join(", ")
            ),
        }
    }
    if all {
        return Ok(None);
    }
    if out.is_empty() {
        bail!("--metrics is empty");
    }
    Ok(Some(out))
}

/// What to evaluate and how: `dancegen eval`'s flags, with its defaults in [`Default`].
#[derive(Clone, Debug)]
pub struct EvalOptions {
    /// Generated clips: files or folders, or arrays (`--pred`).
    pub pred: Vec<Input>,
    /// Ground-truth clips (`--gt`).
    pub gt: Vec<Input>,
    /// The leaders of duet `pred` clips, paired by file stem (`--leader`).
    pub leader: Vec<Input>,
    /// The leaders of duet `gt` clips (`--gt-leader`).
    pub gt_leader: Vec<Input>,
    /// The paper's protocol (`--protocol`).
    pub protocol: Protocol,
    /// Frame rate of `.npy` clips without one (`--fps`).
    pub fps: Option<f64>,
    /// The true frame rate of the clips, when their files say another (`--source-fps`).
    pub source_fps: Option<f64>,
    /// Comma-separated metric names, `physical` or `all` (`--metrics`; `None`: every metric
    /// the inputs allow).
    pub metrics: Option<String>,
    /// The data set manifest giving each `gt` clip's genre (`--gt-genres`).
    pub gt_genres: Option<PathBuf>,
    /// The genre the `pred` dances were asked for (`--want-genre`).
    pub want_genre: Option<String>,
    /// Fewest `gt` clips a genre needs to be classified (`--genre-min-clips`).
    pub genre_min_clips: u64,
    /// BAS variant (`--bas-variant`).
    pub bas_variant: Variant,
    /// Music beats: a `.npy` of beat frames, or of features whose last column marks beats
    /// (`--beats`).
    pub beats: Option<PathBuf>,
    /// Music beat frames given directly (the library's `--beats`; wins over `beats`).
    pub beat_frames: Option<Vec<usize>>,
    /// The song, whose beats are found (`--music`).
    pub music: Option<PathBuf>,
    /// Frames between the boundaries `boundary_jerk` measures (`--window`).
    pub window: u64,
}

impl Default for EvalOptions {
    /// `dancegen eval`'s defaults: no clips, protocol `none`, every metric the inputs allow,
    /// BAS as Bailando computes it, genres of any size, 150-frame windows.
    fn default() -> Self {
        EvalOptions {
            pred: Vec::new(),
            gt: Vec::new(),
            leader: Vec::new(),
            gt_leader: Vec::new(),
            protocol: dancegen_metrics::protocol::NONE,
            fps: None,
            source_fps: None,
            metrics: None,
            gt_genres: None,
            want_genre: None,
            genre_min_clips: 1,
            bas_variant: Variant::Bailando,
            beats: None,
            beat_frames: None,
            music: None,
            window: DEFAULT_WINDOW,
        }
    }
}

/// The protocol `dancegen eval --protocol` names `name`: `aistpp-bailando`, `finedance-lodge`,
/// `edge-5s` or `none`.
pub fn protocol_named(name: &str) -> Result<Protocol> {
    Ok(match name {
        "aistpp-bailando" => dancegen_metrics::protocol::AISTPP_BAILANDO,
        "finedance-lodge" => dancegen_metrics::protocol::FINEDANCE_LODGE,
        "edge-5s" => dancegen_metrics::protocol::EDGE_5S,
        "none" => dancegen_metrics::protocol::NONE,
        other => {
            bail!("protocol '{other}': choose aistpp-bailando, finedance-lodge, edge-5s or none")
        }
    })
}

/// The BAS variant `dancegen eval --bas-variant` names `name`: `bailando`, `lodge`, `fact` or
/// `gcd`.
pub fn bas_variant_named(name: &str) -> Result<Variant> {
    Ok(match name {
        "bailando" => Variant::Bailando,
        "lodge" => Variant::Lodge,
        "fact" => Variant::Fact,
        "gcd" => Variant::Gcd,
        other => bail!("bas variant '{other}': choose bailando, lodge, fact or gcd"),
    })
}

/// Frames between the boundaries `boundary_jerk` measures by default: EDGE's 5-second windows
/// at 30 fps.
pub const DEFAULT_WINDOW: u64 = 150;

/// The result of [`evaluate`]: every set value by metric name (`bas_gt`, `div_k_gt` … beside
/// them), each clip's values, and the protocol. [`Report::to_json`] is `dancegen eval
/// --json`'s object.
#[derive(Clone, Debug)]
pub struct Report {
    pub summary: BTreeMap<String, Value>,
    pub per_clip: Vec<Value>,
    pub protocol: Protocol,
    /// Clips read: generated, ground truth.
    pub pred_clips: usize,
    pub gt_clips: usize,
}

impl Report {
    /// One object: the metric names as keys, `protocol`, and `per_clip`.
    pub fn to_json(&self) -> Value {
        let mut obj = serde_json::Map::new();
        for (k, v) in &self.summary {
            obj.insert(k.clone(), v.clone());
        }
        obj.insert("protocol".into(), json!(self.protocol.name));
        obj.insert("per_clip".into(), Value::Array(self.per_clip.clone()));
        Value::Object(obj)
    }
}

/// Reads the clips `opts` names and computes the metrics (those asked for, else every one the
/// inputs allow). Errors name the flag and the file.
pub fn evaluate(opts: &EvalOptions) -> Result<Report> {
    let args = opts;
    let protocol = opts.protocol;
    let variant = opts.bas_variant;
    // Unknown names fail before any file is read.
    let requested = args
        .metrics
        .as_deref()
        .map(parse_metric_list)
        .transpose()?
        .flatten();
    if !args.gt_leader.is_empty() && args.gt.is_empty() {
        bail!("--gt-leader needs --gt (the GT followers)");
    }

    let load = |inputs: &[Input], flag: &str| -> Result<Vec<Clip>> {
        if inputs.is_empty() {
            return Ok(Vec::new());
        }
        input::load_set(inputs, &protocol, args.fps, args.source_fps)
            .with_context(|| flag.to_string())
    };
    let pred = load(&args.pred, "--pred")?;
    let gt = load(&args.gt, "--gt")?;
    let leaders = load(&args.leader, "--leader")?;
    let gt_leaders = load(&args.gt_leader, "--gt-leader")?;
    let pred_pairs = duet::pairs(&pred, &leaders, "--leader")?;
    let gt_pairs = duet::pairs(&gt, &gt_leaders, "--gt-leader")?;

    let offer = Offer {
        gt: !gt.is_empty(),
        beats: args.beats.is_some() || args.beat_frames.is_some() || args.music.is_some(),
        pred_groups: pred.iter().any(Clip::is_group),
        gt_groups: gt.iter().any(Clip::is_group),
        pred_duets: pred_pairs.iter().any(Option::is_some),
        gt_duets: gt_pairs.iter().any(Option::is_some),
        gt_genres: args.gt_genres.is_some(),
        want_genre: args.want_genre.is_some(),
    };
    let metrics: Vec<String> = match requested {
        Some(list) => {
            for m in &list {
                if let Err(why) = offer.check(m) {
                    bail!("metric {m} {why}");
                }
            }
            list
        }
        None => {
            let gt_stems: Vec<String> = gt.iter().map(Clip::stem).collect();
            let paired = pred.iter().any(|c| gt_stems.contains(&c.stem()));
            all_metrics()
                .filter(|m| offer.default_on(m, args))
                // By default mpjpe only when some --pred clip has a --gt clip of its stem.
                .filter(|m| *m != "mpjpe" || paired)
                .map(|m| m.to_string())
                .collect()
        }
    };
    let want = |m: &str| metrics.iter().any(|x| x == m);

    let music_beats = if want("bas") {
        Some(solo::music_beats(args, &pred)?)
    } else {
        None
    };
    let music = music_beats.as_deref().unwrap_or(&[]);

    let mut summary: BTreeMap<String, Value> = BTreeMap::new();

    // Set metrics: FID / Div on kinetic and geometric features.
    for (kind, fid_key, div_key) in [("k", "fid_k", "div_k"), ("g", "fid_g", "div_g")] {
        if !(want(fid_key) || want(div_key)) {
            continue;
        }
        let p = solo::features(&pred, kind, &protocol)?;
        let g = solo::features(&gt, kind, &protocol)?;
        fid_div(&mut summary, &g, &p, fid_key, div_key, want);
    }
    if want("gmr") {
        let p = group::gmr_features(&pred)?;
        let g = group::gmr_features(&gt)?;
        let (fd, _) = dancegen_metrics::group::gmr(&g, &p);
        summary.insert("gmr".into(), num(fd));
    }
    if want("fid_cd") || want("div_cd") {
        let p = duet::features(&pred, &pred_pairs)?;
        let g = duet::features(&gt, &gt_pairs)?;
        fid_div(&mut summary, &g, &p, "fid_cd", "div_cd", want);
    }

    // Genre control: one classifier fit on the GT, every pred dancer classified.
    let genres = match (&args.gt_genres, &args.want_genre) {
        (Some(manifest), Some(want_genre)) if want("genre") => {
            let r = genre::check(
                &pred,
                &gt,
                manifest,
                want_genre,
                args.genre_min_clips as usize,
                &protocol,
            )?;
            summary.insert("genre".into(), r.summary);
            Some(r.per_clip)
        }
        _ => None,
    };

    // Per-clip metrics.
    let gt_by_stem: BTreeMap<String, &Clip> = gt.iter().map(|c| (c.stem(), c)).collect();
    let mut per_clip = Vec::new();
    let mut columns: BTreeMap<&str, Vec<Option<f64>>> = BTreeMap::new();
    let mut fsd_all = Vec::new();
    let want_physical = metrics.iter().any(|m| physical::is_physical(m));
    for (i, (clip, pair)) in pred.iter().zip(&pred_pairs).enumerate() {
        let figures = if want_physical {
            physical::clip_figures(clip)?
        } else {
            Vec::new()
        };
        let mut row = serde_json::Map::new();
        row.insert("file".into(), json!(clip.path.display().to_string()));
        row.insert("frames".into(), json!(clip.frames()));
        row.insert("dancers".into(), json!(clip.dancers.len()));
        if let Some(g) = &genres {
            // A solo clip's genre, or one per dancer of a scene.
            let v = match g[i].as_slice() {
                [one] => json!(one),
                many => json!(many),
            };
            row.insert("genre".into(), v);
        }
        for m in per_clip_metrics().filter(|m| want(m)) {
            let (v, quiet_none) = match m {
                "bas" => (solo::clip_bas(clip, music, variant)?, false),
                "mpjpe" => match gt_by_stem.get(&clip.stem()) {
                    Some(g) => (solo::clip_mpjpe(clip, g)?, false),
                    None => {
                        tracing::warn!(
                            "{}: no --gt clip with the same file stem; mpjpe skipped",
                            clip.path.display()
                        );
                        (None, true)
                    }
                },
                "fsd" => {
                    let d = solo::skating_duration(clip)?;
                    fsd_all.push(d);
                    (d.percent(), false)
                }
                // Not a scene / not a duet: nothing to measure, nothing to warn about.
                "gmc" | "tif" | "collision" | "min_distance" => {
                    (group::clip_metric(m, clip)?, !clip.is_group())
                }
                "bed" | "ipr" | "contact_range" => match pair {
                    Some(p) => (duet::clip_metric(m, clip, p)?, false),
                    None => (None, true),
                },
                _ if physical::is_physical(m) => (physical::value(&figures, m), false),
                other => (
                    solo::over_dancers(clip, |d| solo::clip_metric(other, d, args.window as usize))
                        .with_context(|| format!("{}: {other}", clip.path.display()))?,
                    false,
                ),
            };
            if v.is_none() && !quiet_none {
                tracing::warn!(
                    "{}: {m} is undefined for this clip (excluded from the mean)",
                    clip.path.display()
                );
            }
            row.insert(m.into(), v.map_or(Value::Null, num));
            if m == "bas"
                && let Some((motion, music_in_clip)) = solo::clip_beat_counts(clip, music, variant)?
            {
                row.insert("motion_beats".into(), json!(motion));
                row.insert("music_beats".into(), json!(music_in_clip));
            }
            columns.entry(m).or_default().push(v);
        }
        per_clip.push(Value::Object(row));
    }
    for m in per_clip_metrics().filter(|m| want(m)) {
        let vals: Vec<f64> = columns
            .get(m)
            .into_iter()
            .flatten()
            .flatten()
            .copied()
            .collect();
        let scale = if m == "pfc" {
            dancegen_metrics::pfc::PFC_SCALE
        } else {
            1.0
        };
        let value = if m == "fsd" {
            dancegen_metrics::foot_skating_duration::pooled_percent(&fsd_all)
        } else if physical::is_physical(m) {
            physical::combine(m, &vals)
        } else {
            mean(&vals).map(|v| v * scale)
        };
        summary.insert(m.into(), value.map_or(Value::Null, num));
    }
    if want("bas") && offer.gt {
        let mut vals = Vec::new();
        for c in &gt {
            match solo::clip_bas(c, music, variant)? {
                Some(v) => vals.push(v),
                None => tracing::warn!(
                    "{}: bas is undefined for this clip (excluded from bas_gt)",
                    c.path.display()
                ),
            }
        }
        summary.insert("bas_gt".into(), mean(&vals).map_or(Value::Null, num));
    }

    Ok(Report {
        summary,
        per_clip,
        protocol,
        pred_clips: pred.len(),
        gt_clips: gt.len(),
    })
}

/// FID (needs GT) and diversity of one feature kind. With GT, both sets are normalised by the
/// GT statistics (Bailando / Duolando) and `<div>_gt` is added; without, the diversity of the
/// raw features.
fn fid_div(
    summary: &mut BTreeMap<String, Value>,
    gt: &[Vec<f64>],
    pred: &[Vec<f64>],
    fid_key: &str,
    div_key: &str,
    want: impl Fn(&str) -> bool,
) {
    if pred.len() < 2 && want(div_key) {
        tracing::warn!("{div_key} needs at least two samples");
    }
    if !gt.is_empty() {
        let (g_n, p_n) = normalize_by_gt(gt, pred);
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
        tracing::warn!("{div_key} without GT: diversity of the raw (not GT-normalised) features");
        summary.insert(div_key.into(), num(diversity(pred)));
    }
}

fn num(v: f64) -> Value {
    if v.is_finite() { json!(v) } else { Value::Null }
}

fn mean(v: &[f64]) -> Option<f64> {
    (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
}
