//! The generator: runs one [`Request`] as a job, keeping loaded models between jobs.

use std::any::{Any, TypeId};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use dancegen_nn::burn::tensor::Device;

use crate::error::GenerateError;
use crate::models::ModelLocator;
use crate::output;
use crate::progress::{CancelToken, Progress, Tracker, stage};
use crate::record::DanceRecord;
use crate::request::{OutputRequest, Request, Song, SystemRequest};
use crate::song::{AnalysedSong, FPS};
use crate::system::{Dance, DanceInput, DanceSystem, Dancer};
use crate::systems::duet::Duet;
use crate::systems::group::Group;
use crate::systems::holistic::Holistic;
use crate::systems::solo::Solo;
use crate::time_plan::{self, MeasuredSpeeds};

/// Where a job's time went (seconds).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct Timings {
    pub load_model_s: f64,
    pub analyse_song_s: f64,
    /// The system itself (sampling, decoding, post-processing).
    pub generate_s: f64,
    pub write_outputs_s: f64,
    pub total_s: f64,
}

/// A finished job.
#[derive(Clone, Debug)]
pub struct Generated {
    /// `"solo"`, `"duet"`.
    pub system: &'static str,
    /// The model folder used.
    pub model_dir: PathBuf,
    /// The song's path or name.
    pub song_label: String,
    pub dancers: Vec<Dancer>,
    /// Motion frame rate.
    pub fps: u32,
    /// Seconds of the song danced to.
    pub start_s: f64,
    pub end_s: f64,
    /// Music beats in the danced part, seconds from its start.
    pub beat_times_s: Vec<f64>,
    pub tempo_bpm: f64,
    /// The system's account of what it made ([`Dance::summary`] and friends).
    pub summary: String,
    pub timing_breakdown: String,
    pub notes: Vec<String>,
    /// What the user should know about the result although it was made (a song without a
    /// beat: [`beat_warning`]); every front end shows them.
    pub warnings: Vec<String>,
    pub timings: Timings,
    /// Files written, in request order.
    pub written: Vec<PathBuf>,
    /// The dance itself, kept to write more outputs later, when the job asked for it
    /// ([`Generator::run_keeping`]).
    pub kept: Option<Arc<KeptDance>>,
}

/// A finished dance with its song and record: what writing an output needs, so that an
/// output written later ([`KeptDance::write`]) is the file the job would have written (the
/// Python package's `Dance.save`).
pub struct KeptDance {
    dance: Dance,
    song: AnalysedSong,
    record: DanceRecord,
    makes_face: bool,
}

impl std::fmt::Debug for KeptDance {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("KeptDance")
            .field("record", &self.record)
            .finish_non_exhaustive()
    }
}

impl KeptDance {
    /// Writes `outputs` as the job that made the dance would have (staged, then renamed into
    /// place; nothing is left of a failed write).
    pub fn write(&self, outputs: &[OutputRequest]) -> Result<Vec<PathBuf>, GenerateError> {
        let planned = output::plan(outputs, self.makes_face)?;
        let plan = vec![(stage::WRITE_OUTPUTS, output::estimated_seconds(&planned))];
        let cancel = CancelToken::new();
        let tracker = Tracker::new(plan, &|_: &Progress| {}, &cancel);
        tracker.begin(stage::WRITE_OUTPUTS)?;
        output::write_all(&planned, &self.dance, &self.song, &self.record, &tracker)
    }

    /// The array the `.npy` output holds (`(T, J, 3)`, or `(N, T, 24, 3)` for a group) as
    /// `(shape, values)`. The `.npy` writer is the one definition of that array, so it is
    /// written to a temporary folder and read back.
    pub fn joints(&self) -> Result<(Vec<usize>, Vec<f32>), GenerateError> {
        let dir = tempfile::tempdir().map_err(|e| GenerateError::Output {
            path: std::env::temp_dir(),
            reason: format!("cannot create a temporary folder: {e}"),
        })?;
        let path = dir.path().join("joints.npy");
        self.write(&[OutputRequest::new(&path)])?;
        let bad = |reason: String| GenerateError::Output {
            path: path.clone(),
            reason,
        };
        let a = dancegen_io::read_npy(&path).map_err(|e| bad(e.to_string()))?;
        // float32 values widened to f64 by the reader: narrowing them back is exact.
        Ok((a.shape, a.data.into_iter().map(|v| v as f32).collect()))
    }
}

/// Runs generation jobs. Long-running front ends (the web server, batch runs) keep one and
/// reuse its loaded models; it is `Sync`, and jobs may run from several threads.
pub struct Generator {
    locator: ModelLocator,
    device: Device,
    /// Loaded models by system and canonical folder.
    models: Mutex<HashMap<(TypeId, PathBuf), Arc<dyn Any + Send + Sync>>>,
    /// This machine's speeds, learnt from finished jobs, for honest progress.
    speeds: MeasuredSpeeds,
}

impl Generator {
    /// A generator finding models on `locator`'s path, on the inference device.
    pub fn new(locator: ModelLocator) -> Self {
        Generator {
            locator,
            device: dancegen_nn::device::inference(),
            models: Mutex::new(HashMap::new()),
            speeds: MeasuredSpeeds::default(),
        }
    }

    pub fn locator(&self) -> &ModelLocator {
        &self.locator
    }

    /// Runs `request`: `on_progress` hears of every stage and step (fractions only grow, the
    /// last report is `done` at 1.0); `cancel` stops the job between steps, and a cancelled
    /// or failed job leaves no output file.
    pub fn run(
        &self,
        request: &Request,
        on_progress: &(dyn Fn(&Progress) + Sync),
        cancel: &CancelToken,
    ) -> Result<Generated, GenerateError> {
        self.run_with(request, on_progress, cancel, false)
    }

    /// [`Generator::run`], keeping the dance in [`Generated::kept`] to write more outputs
    /// later.
    pub fn run_keeping(
        &self,
        request: &Request,
        on_progress: &(dyn Fn(&Progress) + Sync),
        cancel: &CancelToken,
    ) -> Result<Generated, GenerateError> {
        self.run_with(request, on_progress, cancel, true)
    }

    fn run_with(
        &self,
        request: &Request,
        on_progress: &(dyn Fn(&Progress) + Sync),
        cancel: &CancelToken,
        keep: bool,
    ) -> Result<Generated, GenerateError> {
        let (r, p, c, k) = (request, on_progress, cancel, keep);
        match &request.system {
            SystemRequest::Solo(o) => self.run_system::<Solo>(r, o, p, c, k),
            SystemRequest::Duet(o) => self.run_system::<Duet>(r, o, p, c, k),
            SystemRequest::Group(o) => self.run_system::<Group>(r, o, p, c, k),
            SystemRequest::Holistic(o) => self.run_system::<Holistic>(r, o, p, c, k),
        }
    }

    /// The cache key of `S`'s model in `dir`.
    fn key<S: DanceSystem>(dir: &Path) -> (TypeId, PathBuf) {
        (
            TypeId::of::<S>(),
            dir.canonicalize().unwrap_or_else(|_| dir.to_path_buf()),
        )
    }

    /// The model in `dir` for `S`, loaded once per generator.
    fn model<S: DanceSystem>(&self, dir: &Path) -> Result<Arc<S::Model>, GenerateError> {
        let key = Self::key::<S>(dir);
        if let Some(m) = self.lock_models().get(&key).cloned()
            && let Ok(m) = m.downcast::<S::Model>()
        {
            return Ok(m);
        }
        check_kind::<S>(dir)?;
        // Loaded outside the lock: another job may load another model meanwhile (a second
        // load of the same one only costs time).
        let m = Arc::new(S::load(dir, &self.device)?);
        self.lock_models().insert(key, m.clone());
        Ok(m)
    }

    fn lock_models(
        &self,
    ) -> std::sync::MutexGuard<'_, HashMap<(TypeId, PathBuf), Arc<dyn Any + Send + Sync>>> {
        self.models.lock().unwrap_or_else(|e| e.into_inner())
    }

    fn is_cached<S: DanceSystem>(&self, dir: &Path) -> bool {
        self.lock_models().contains_key(&Self::key::<S>(dir))
    }

    fn run_system<S: DanceSystem>(
        &self,
        request: &Request,
        options: &S::Options,
        on_progress: &(dyn Fn(&Progress) + Sync),
        cancel: &CancelToken,
        keep: bool,
    ) -> Result<Generated, GenerateError> {
        let started = Instant::now();
        if let Some(op) = request
            .common
            .edit
            .operations()
            .into_iter()
            .find(|op| !S::EDITS.contains(op))
        {
            return Err(GenerateError::Invalid(format!(
                "{op} is not supported by --system {} (see the table of edits in `dancegen \
                 generate --help`)",
                S::NAME
            )));
        }
        request.common.edit.check()?;
        let planned = output::plan(&request.outputs, request.system.makes_face())?;
        let model_dir = match &request.model {
            Some(d) => d.clone(),
            None => self.locator.find(S::DEFAULT_MODEL, S::NAME)?,
        };
        // Each stage's expected seconds ([`crate::time_plan`]): the ETA extrapolates from the
        // time spent, so the shares must follow the time the stages take, which grows with
        // the song (analysis) and with the music danced (the dance).
        let load_share = if self.is_cached::<S>(&model_dir) {
            0.0
        } else {
            LOAD_MODEL_SECONDS
        };
        let song_s =
            time_plan::song_seconds_hint(&request.song).unwrap_or(time_plan::UNKNOWN_SONG_SECONDS);
        let danced_s = time_plan::danced_seconds(song_s, request.common.start, request.common.end);
        let analyse_s = time_plan::ANALYSE_FIXED_SECONDS + song_s * self.speeds.analyse();
        let dance_s = danced_s * self.speeds.generate(S::NAME, S::SECONDS_PER_DANCED_SECOND);
        let mut plan = vec![
            (stage::LOAD_MODEL, load_share),
            (stage::ANALYSE_SONG, analyse_s),
        ];
        plan.extend(S::PARTS.iter().map(|&(p, w)| (p, w * dance_s)));
        plan.push((stage::WRITE_OUTPUTS, output::estimated_seconds(&planned)));
        let tracker = Tracker::new(plan, on_progress, cancel);

        tracker.begin(stage::LOAD_MODEL)?;
        let t = Instant::now();
        let model = self.model::<S>(&model_dir)?;
        let load_model_s = t.elapsed().as_secs_f64();
        S::check(&model, &request.common, options)?;

        tracker.begin(stage::ANALYSE_SONG)?;
        let t = Instant::now();
        let song = AnalysedSong::analyse(&request.song)?;
        let analyse_song_s = t.elapsed().as_secs_f64();
        tracker.advance(stage::ANALYSE_SONG, 1, 1);
        tracker.check()?;

        let t = Instant::now();
        let dance: Dance = S::dance(
            &model,
            DanceInput {
                song: &song,
                common: &request.common,
                options,
                device: &self.device,
                hook: &tracker,
            },
        )?;
        let generate_s = t.elapsed().as_secs_f64();
        self.speeds.learn(
            S::NAME,
            (analyse_song_s, song.seconds()),
            (generate_s, dance.span.end_s - dance.span.start_s),
        );

        tracker.begin(stage::WRITE_OUTPUTS)?;
        let t = Instant::now();
        let record = DanceRecord {
            song: recorded_song(&request.song),
            start_s: dance.span.start_s,
            end_s: dance.span.end_s,
            system: S::NAME.into(),
            model: std::path::absolute(&model_dir)
                .unwrap_or_else(|_| model_dir.clone())
                .display()
                .to_string(),
            seed: request.common.seed,
            dancers: dance.dancers.len(),
            dancer: 0,
            fps: FPS,
            version: env!("CARGO_PKG_VERSION").into(),
        };
        let written = output::write_all(&planned, &dance, &song, &record, &tracker)?;
        let write_outputs_s = t.elapsed().as_secs_f64();
        tracker.finish();

        let span = dance.span;
        let beat_times_s: Vec<f64> = song
            .beat_frames(&span)
            .into_iter()
            .map(|f| f as f64 / f64::from(FPS))
            .collect();
        let warnings = beat_warning(beat_times_s.len(), span.start_s, span.end_s)
            .into_iter()
            .collect();
        let song_label = song.label.clone();
        let tempo_bpm = song.features.tempo_bpm;
        let dancers = dance.dancers.clone();
        let (summary, timing_breakdown, notes) = (
            dance.summary.clone(),
            dance.timing_breakdown.clone(),
            dance.notes.clone(),
        );
        let kept = keep.then(|| {
            Arc::new(KeptDance {
                dance,
                song,
                record,
                makes_face: request.system.makes_face(),
            })
        });
        Ok(Generated {
            system: S::NAME,
            model_dir,
            song_label,
            fps: FPS,
            start_s: span.start_s,
            end_s: span.end_s,
            beat_times_s,
            tempo_bpm,
            dancers,
            summary,
            timing_breakdown,
            notes,
            warnings,
            timings: Timings {
                load_model_s,
                analyse_song_s,
                generate_s,
                write_outputs_s,
                total_s: started.elapsed().as_secs_f64(),
            },
            written,
            kept,
        })
    }
}

/// Seconds loading a model from disk takes in the time plan (the first job of a system).
const LOAD_MODEL_SECONDS: f64 = 2.0;

/// Fewest beats per second of danced music below which the song is said to have no beat:
/// one every 4 s (a 15 bpm pulse, slower than any dance tempo; silence has none, a song with
/// a beat at 60-200 bpm has 4-13 times as many).
pub const MIN_BEATS_PER_SECOND: f64 = 0.25;

/// The warning for a dance from `start_s` to `end_s` of a song in which the beat tracker found
/// `beats` beats, when that is fewer than [`MIN_BEATS_PER_SECOND`]: the dance is made, but no
/// model can keep a beat the music does not have (30 s of silence was danced without a word).
pub fn beat_warning(beats: usize, start_s: f64, end_s: f64) -> Option<String> {
    let seconds = end_s - start_s;
    ((beats as f64) < MIN_BEATS_PER_SECOND * seconds).then(|| {
        format!(
            "no beat was found in the music from {start_s:.1} to {end_s:.1} s ({beats} beats in \
             {seconds:.1} s): is it silent, or without a rhythm? The dance cannot keep a beat \
             the music does not have"
        )
    })
}

/// How a job's song is recorded in its files ([`DanceRecord::song`]).
fn recorded_song(song: &Song) -> String {
    match song {
        Song::Demo => crate::record::DEMO_SONG.into(),
        Song::File(p) => std::path::absolute(p)
            .unwrap_or_else(|_| p.clone())
            .display()
            .to_string(),
        Song::Bytes { name, .. } => name.clone(),
    }
}

/// A model of another system (its `model.toml` `kind`) is refused with the `--system` that
/// runs it, instead of the system's own loader reporting the other format's fields as unknown.
/// A folder without a readable `kind` goes on to the loader, whose error names the problem.
fn check_kind<S: DanceSystem>(dir: &Path) -> Result<(), GenerateError> {
    let Some(kind) = crate::models::model_kind(dir) else {
        return Ok(());
    };
    if kind == S::MODEL_KIND {
        return Ok(());
    }
    Err(GenerateError::Invalid(
        match crate::systems::by_model_kind(&kind) {
            Some(other) => format!(
                "{}: a {} model ({}, kind {kind:?}), not a {} one; run it with --system {}",
                dir.display(),
                other.name,
                other.method,
                S::NAME,
                other.name
            ),
            None => format!(
                "{}: kind {kind:?} is not a model this version can run (a {} model has kind {:?})",
                dir.display(),
                S::NAME,
                S::MODEL_KIND
            ),
        },
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_song_without_a_beat_is_warned_of() {
        // Silence: the beat tracker finds none.
        let w = beat_warning(0, 0.0, 30.0).expect("a warning");
        assert!(w.contains("0 beats in 30.0 s"), "{w}");
        // Two beats in 10 s are fewer than one every 4 s; three are not.
        assert!(beat_warning(2, 5.0, 15.0).is_some());
        assert!(beat_warning(3, 5.0, 15.0).is_none());
        // A song at 60 bpm is far from it.
        assert!(beat_warning(60, 0.0, 60.0).is_none());
    }
}
