//! Each input take's true frame rate, kinematic tempo and floor: what `dataset build` prints,
//! records in the manifest (`takes`) and warns about before anything is trained on it.
//!
//! A BVH header can be wrong: the CMU salsa conversions say 120 fps for a 60 fps capture, and
//! every model trained on them learned salsa at double speed. The rate of a take is therefore
//! given per input (`--source-fps INPUT=FPS`, [`SourceRates`]) or read from its header, and
//! the take's tempo is compared with the range of real dance of its genre
//! ([`HUMAN_TEMPO`]), so a mis-headed file is named before training.

use std::path::{Path, PathBuf};

use dancegen_metrics::physical::{Physical, physical};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

pub use crate::rates::{RateFrom, SourceRates};

use crate::error::DatasetError;
use crate::units::{MotionUnit, world_joints};

/// One input take (one dancer of one motion file) as the data set reads it: at `source_fps`,
/// resampled to 30 fps, retargeted to SMPL 24 and put on the floor. Figures are
/// `dancegen_metrics::physical`'s.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TakeEntry {
    /// Dancer name (the clip name before pairing: the file stem, `_d<k>` for group files).
    pub name: String,
    pub source: String,
    pub genre: String,
    pub source_fps: f64,
    pub rate_from: RateFrom,
    pub seconds: f64,
    /// Mean joint speed, m/s.
    pub joint_speed: f64,
    /// Mean horizontal pelvis speed, m/s.
    pub pelvis_speed: f64,
    /// Foot steps (both feet) per second.
    pub step_rate: f64,
    /// Median height of the lowest foot joint, m (0 = on the floor).
    pub floor_median: f64,
    /// Share of frames with no foot joint within 5 cm of the floor, %.
    pub float_pct: f64,
    /// Why the take looks like no human dance of its genre; `None` when it is in range.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub warning: Option<String>,
}

/// The kinematic tempo of real dance at its true rate, per genre: mean joint speed (m/s) and
/// steps per second, each `[min, max]` over the takes we trust (measured by
/// `tools/data_rates.sh`, which writes `docs/data-rates.md`), widened by [`TEMPO_MARGIN`].
///
/// Trusted rates (`break` covers CMU subject 85 and the AIST++ `gBR` takes): AIST++ at 60 fps (its release's rate); CMU subjects 05 and 55 at 120 fps and
/// 85 at 30 fps (the conversions' rates; their step rates and speeds are those of dancers);
/// the CMU salsa couples at 60 fps, not their headers' 120 (shared/data/README.md: at 120 each
/// foot lifts 2.0-2.4 times a second, salsa at ~320 BPM). The `*` row, for genres without
/// trusted takes, spans every trusted take.
pub const HUMAN_TEMPO: [(&str, [f64; 2], [f64; 2]); 5] = [
    ("salsa", [0.52, 0.84], [1.58, 2.25]),
    ("modern", [0.22, 1.97], [0.44, 2.29]),
    ("break", [1.10, 1.69], [1.36, 3.19]),
    ("whirl", [0.74, 0.74], [1.60, 1.60]),
    ("*", [0.22, 1.97], [0.44, 3.19]),
];

/// How far outside the trusted range a take may be before it is flagged: ±15 %, the playback
/// speed change the beat warp itself allows ([`crate::warp`]). Wider lets a salsa take read at
/// twice its rate through (the slowest salsa take at 120 fps moves its joints at 1.04 m/s, 1.25
/// times the fastest at 60).
pub const TEMPO_MARGIN: f64 = 0.15;

/// `Some(reason)` when the take's tempo is outside [`HUMAN_TEMPO`] for its genre.
pub fn tempo_warning(genre: &str, joint_speed: f64, step_rate: f64) -> Option<String> {
    let (g, speed, steps) = HUMAN_TEMPO
        .iter()
        .find(|(g, _, _)| *g == genre)
        .or_else(|| HUMAN_TEMPO.iter().find(|(g, _, _)| *g == "*"))
        .copied()?;
    let range = |r: [f64; 2]| [r[0] * (1.0 - TEMPO_MARGIN), r[1] * (1.0 + TEMPO_MARGIN)];
    let (sr, tr) = (range(speed), range(steps));
    let which = if g == "*" {
        "any real dance".to_string()
    } else {
        format!("real {g}")
    };
    let mut out = Vec::new();
    if !(sr[0]..=sr[1]).contains(&joint_speed) {
        out.push(format!(
            "joints move at {joint_speed:.2} m/s, {which} at {:.2}-{:.2}",
            sr[0], sr[1]
        ));
    }
    if !(tr[0]..=tr[1]).contains(&step_rate) {
        out.push(format!(
            "{step_rate:.2} steps/s, {which} {:.2}-{:.2}",
            tr[0], tr[1]
        ));
    }
    if out.is_empty() {
        return None;
    }
    let hint = if joint_speed > sr[1] || step_rate > tr[1] {
        "too fast: is its header's frame rate too high? give the true one with --source-fps"
    } else {
        "too slow: is its header's frame rate too low? give the true one with --source-fps"
    };
    Some(format!("{} ({hint})", out.join("; ")))
}

/// One dancer of an input take, read as a data set reads it (at its given or header rate,
/// resampled to 30 fps, retargeted to SMPL 24, its feet put on the floor), with every
/// physical figure. The real reference that generated dances are held to (the plausibility
/// gate, the eval reports) is computed this way, so it moves with the data's true rates.
#[derive(Clone, Debug, PartialEq)]
pub struct TakeFigures {
    /// Dancer name (the file stem, `_d<k>` for group files).
    pub name: String,
    pub genre: String,
    pub source_fps: f64,
    pub rate_from: RateFrom,
    pub seconds: f64,
    pub figures: Physical,
}

/// Every dancer of one motion file with its physical figures ([`TakeFigures`]); a dancer too
/// short for the figures is skipped with a warning.
pub fn measure_figures(
    path: &Path,
    genre: &str,
    rates: &SourceRates,
) -> Result<Vec<TakeFigures>, DatasetError> {
    let mut out = Vec::new();
    for unit in crate::units::load_units(path, genre, rates)? {
        match unit_figures(&unit)? {
            Some(t) => out.push(t),
            // The pairing drops it too (shorter than a clip); nothing to measure or warn about.
            None => tracing::warn!(
                "{}: {} has {} frames, too few to measure its tempo",
                path.display(),
                unit.name,
                unit.motion.frames()
            ),
        }
    }
    Ok(out)
}

/// [`measure_figures`] of every motion file `inputs` name (directories: their motion files),
/// each dancer's genre from its file name as `dataset build` infers it: the real motion a
/// model trained on these inputs is held to.
pub fn measure_inputs(
    inputs: &[PathBuf],
    rates: &SourceRates,
) -> Result<Vec<TakeFigures>, DatasetError> {
    let files = crate::inputs::expand_motion_inputs(inputs)?;
    rates.check_used(&files)?;
    let per_file: Vec<Result<Vec<TakeFigures>, DatasetError>> = files
        .par_iter()
        .map(|path| {
            let genre = crate::genre::genre_from_name(&crate::song::stem(path));
            measure_figures(path, &genre, rates)
        })
        .collect();
    let mut out = Vec::new();
    for r in per_file {
        out.extend(r?);
    }
    Ok(out)
}

/// Every dancer of one motion file as a data set reads it (`rates` gives its capture rate, if
/// any), with its figures and, when out of range for `genre`, its warning.
pub fn measure(
    path: &Path,
    genre: &str,
    rates: &SourceRates,
) -> Result<Vec<TakeEntry>, DatasetError> {
    Ok(measure_figures(path, genre, rates)?
        .into_iter()
        .map(|t| TakeEntry {
            source: path.display().to_string(),
            joint_speed: t.figures.joint_speed,
            pelvis_speed: t.figures.pelvis_speed,
            step_rate: t.figures.step_rate,
            floor_median: t.figures.floor_median,
            float_pct: t.figures.float_pct,
            warning: tempo_warning(&t.genre, t.figures.joint_speed, t.figures.step_rate),
            name: t.name,
            genre: t.genre,
            source_fps: t.source_fps,
            rate_from: t.rate_from,
            seconds: t.seconds,
        })
        .collect())
}

/// The figures of one loaded dancer (already at 30 fps, SMPL 24); `None` for a take too short
/// for them.
fn unit_figures(unit: &MotionUnit) -> Result<Option<TakeFigures>, DatasetError> {
    if unit.motion.frames() < dancegen_metrics::physical::MIN_FRAMES {
        return Ok(None);
    }
    let mut m = unit.motion.clone();
    m.put_feet_on_floor()
        .map_err(|e| DatasetError::input(&unit.source, e))?;
    let joints = world_joints(&m, &unit.source)?;
    let fps = f64::from(m.fps);
    let figures = physical(&joints, fps)
        .map_err(|e| DatasetError::input(&unit.source, format!("kinematic tempo: {e}")))?;
    Ok(Some(TakeFigures {
        name: unit.name.clone(),
        genre: unit.genre.clone(),
        source_fps: unit.source_fps,
        rate_from: unit.rate_from,
        seconds: m.frames() as f64 / fps,
        figures,
    }))
}

/// The table `dataset build` prints, one line per take.
pub fn table(takes: &[TakeEntry]) -> String {
    let mut s = format!(
        "{:<24} {:>7} {:>6} {:>6} {:>7} {:>7} {:>6} {:>6}\n",
        "take", "genre", "fps", "from", "joint", "steps", "floor", "float"
    );
    s.push_str(&format!(
        "{:<24} {:>7} {:>6} {:>6} {:>7} {:>7} {:>6} {:>6}\n",
        "", "", "", "", "m/s", "/s", "m", "%"
    ));
    for t in takes {
        let from = match t.rate_from {
            RateFrom::Given => "given",
            RateFrom::Header => "header",
        };
        s.push_str(&format!(
            "{:<24} {:>7} {:>6.1} {:>6} {:>7.3} {:>7.3} {:>6.3} {:>6.1}{}\n",
            t.name,
            t.genre,
            t.source_fps,
            from,
            t.joint_speed,
            t.step_rate,
            t.floor_median,
            t.float_pct,
            if t.warning.is_some() { "  !" } else { "" }
        ));
    }
    s
}
