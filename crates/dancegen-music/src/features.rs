//! The per-frame music features the published dance models are conditioned on.
//!
//! [`FeatureSet::Edge35`] is the 35-dim librosa pipeline of FACT/AIST++ (mint), EDGE, Lodge,
//! FineDance, TCDiff and SoulNet's "baseline" features (`shared/reference/anchors.md` B.1):
//! per frame `[onset envelope, 20 MFCC, 12 chroma_cens, onset-peak one-hot, beat one-hot]`.
//! [`FeatureSet::Tcdiff438`] is TCDiff/TCDiff++'s 438-dim set (anchors B.2), always at 60 fps.

use std::path::Path;

use crate::HOP;
use crate::beat;
use crate::chroma;
use crate::decode::AudioSource;
use crate::error::{MusicError, Result};
use crate::load::{Audio, load_many};
use crate::mel::{self, MelFilterbank, N_FFT};
use crate::mfcc::mfcc_from_mel_db;
use crate::onset;
use crate::stft::{FrameMatrix, Stft, power_of};
use crate::tuning;

use crate::tcdiff;
use crate::tempo;

/// Width of the EDGE/Lodge/FACT feature vector.
pub const EDGE35_DIM: usize = 35;
/// Column of the onset-peak one-hot in the 35-dim vector (Lodge++ retrieval reads `[:, -2]`).
pub const EDGE35_PEAK_COL: usize = 33;
/// Column of the beat one-hot (`[:, -1]`).
pub const EDGE35_BEAT_COL: usize = 34;
/// librosa's default load rate, used by EDGE/Lodge's start-BPM fallback
/// (`librosa.beat.tempo(y=librosa.load(path)[0])`).
pub const LIBROSA_DEFAULT_SR: u32 = 22050;
/// Tightness of the dance pipelines' `beat_track` call.
pub const BEAT_TIGHTNESS: f64 = 100.0;
/// EDGE's slice length (`Stanford-TML/EDGE:data/slice.py`) and frames kept per slice.
pub const EDGE_SLICE_SECONDS: f64 = 5.0;
/// EDGE's test-time slice stride (`test.py`: 2.5 s; training uses 0.5 s).
pub const EDGE_TEST_STRIDE_SECONDS: f64 = 2.5;

/// Which feature set to compute.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FeatureSet {
    Edge35,
    Tcdiff438,
}

impl FeatureSet {
    pub fn dim(self) -> usize {
        match self {
            FeatureSet::Edge35 => EDGE35_DIM,
            FeatureSet::Tcdiff438 => tcdiff::TCDIFF438_DIM,
        }
    }
}

/// Where the beat tracker's prior tempo comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum StartBpm {
    /// Given by the caller.
    Given(f64),
    /// Parsed from an AIST++ music name in the file name (`mBR3` → 110 BPM).
    AistName(f64),
    /// EDGE/Lodge's fallback: the tempo of the file loaded at 22050 Hz with librosa's defaults.
    Estimated22050(f64),
}

impl StartBpm {
    pub fn bpm(&self) -> f64 {
        match *self {
            StartBpm::Given(b) | StartBpm::AistName(b) | StartBpm::Estimated22050(b) => b,
        }
    }
}

/// Features of one song (or one slice).
#[derive(Clone, Debug)]
pub struct MusicFeatures {
    pub fps: u32,
    pub start_bpm: StartBpm,
    pub tempo_bpm: f64,
    pub beat_frames: Vec<usize>,
    pub onset_frames: Vec<usize>,
    /// frames × dim.
    pub features: FrameMatrix,
}

impl MusicFeatures {
    pub fn beat_times(&self) -> Vec<f64> {
        frames_to_times(&self.beat_frames, self.fps)
    }
    pub fn onset_times(&self) -> Vec<f64> {
        frames_to_times(&self.onset_frames, self.fps)
    }
}

/// `librosa.frames_to_time`: frame · hop / sr = frame / fps.
pub fn frames_to_times(frames: &[usize], fps: u32) -> Vec<f64> {
    frames.iter().map(|&f| f as f64 / fps as f64).collect()
}

/// Sample rate of a feature frame rate: `fps · 512`.
pub fn sample_rate_for_fps(fps: u32) -> Result<u32> {
    match fps {
        30 | 60 => Ok(fps * HOP as u32),
        other => Err(MusicError::InvalidParameter(format!(
            "fps must be 30 (EDGE, Lodge, TCDiff) or 60 (FACT), got {other}"
        ))),
    }
}

/// Everything of the 35-dim features that does not depend on the beat prior.
struct Edge35Analysis {
    sr: f64,
    env: Vec<f32>,
    mfcc: FrameMatrix,
    chroma: FrameMatrix,
}

impl Edge35Analysis {
    fn compute(y: &[f32], sr: f64) -> Result<Self> {
        // One 2048/512 Hann STFT feeds both the mel spectrogram (onset strength, MFCC) and
        // chroma_cens's tuning estimate, which librosa computes from the very same STFT; the
        // CQT's octave cascade is resampled meanwhile.
        let t0 = std::time::Instant::now();
        let mut spectral: Option<(Vec<f32>, FrameMatrix)> = None;
        let mut chroma = None;
        rayon::scope(|scope| {
            let spectral = &mut spectral;
            chroma = Some(chroma::chroma_cens_with_estimator(y, sr, HOP, 12, || {
                let (mut db, peaks) = mel_power_and_pitch_peaks(y, sr);
                tracing::debug!("timing: STFT for mel and tuning done at {:?}", t0.elapsed());
                // dB, onset strength and MFCC run while the CQT is computed.
                scope.spawn(move |_| {
                    mel::power_to_db_in_place(&mut db.data, Some(80.0));
                    let env = onset::onset_strength_from_mel_db(&db, N_FFT, HOP);
                    *spectral = Some((env, mfcc_from_mel_db(&db, 20)));
                });
                tuning::tuning_from_peaks(&peaks, tuning::TUNING_RESOLUTION, CHROMA_BINS_PER_OCTAVE)
            }));
        });
        tracing::debug!("timing: chroma_cens and MFCC done at {:?}", t0.elapsed());
        let chroma = chroma.expect("the scope ran")?;
        let (env, mfcc) = spectral.expect("the tuning estimator always runs");
        Ok(Self {
            sr,
            env,
            mfcc,
            chroma,
        })
    }

    fn finish(self, fps: u32, start_bpm: StartBpm) -> MusicFeatures {
        let Self {
            sr,
            env,
            mfcc,
            chroma,
        } = self;
        let onset_frames = onset::onset_detect(&env, sr, HOP);
        let (tempo_bpm, beat_frames) =
            beat::beat_track(&env, sr, HOP, start_bpm.bpm(), BEAT_TIGHTNESS, true);
        let t = env.len();
        debug_assert_eq!(mfcc.rows, t);
        debug_assert_eq!(chroma.rows, t);
        let mut features = FrameMatrix::zeros(t, EDGE35_DIM);
        for (i, &e) in env.iter().enumerate() {
            let row = features.row_mut(i);
            row[0] = e;
            row[1..21].copy_from_slice(mfcc.row(i));
            row[21..33].copy_from_slice(chroma.row(i));
        }
        for &p in &onset_frames {
            features.row_mut(p)[EDGE35_PEAK_COL] = 1.0;
        }
        for &b in &beat_frames {
            features.row_mut(b)[EDGE35_BEAT_COL] = 1.0;
        }
        MusicFeatures {
            fps,
            start_bpm,
            tempo_bpm,
            beat_frames,
            onset_frames,
            features,
        }
    }
}

/// `chroma_cens`'s CQT resolution (librosa ≥ 0.10 default).
const CHROMA_BINS_PER_OCTAVE: usize = 36;

/// The mel power spectrogram (frames × 128) and `piptrack`'s pitch peaks from one STFT pass.
fn mel_power_and_pitch_peaks(y: &[f32], sr: f64) -> (FrameMatrix, Vec<tuning::PitchPeak>) {
    let stft = Stft::hann(N_FFT, HOP);
    let fb = MelFilterbank::slaney(sr, N_FFT, mel::N_MELS);
    let tracker = tuning::PitchTracker::new(sr, N_FFT);
    let cols = fb.n_mels();
    let mut mel = FrameMatrix::zeros(crate::stft::n_frames(y.len(), HOP), cols);
    let peaks = mel.par_row_blocks(128, |frames, rows| {
        let start = frames.start;
        let (mut mag, mut power, mut peaks) = (Vec::new(), Vec::new(), Vec::new());
        stft.for_each_frame(y, frames, |ti, spec| {
            power.clear();
            power.extend(spec.iter().map(|&c| power_of(c)));
            let r = ti - start;
            fb.apply(&power, &mut rows[r * cols..(r + 1) * cols]);
            tracker.frame_peaks(ti, spec, &mut mag, &mut peaks);
        });
        peaks
    });
    (mel, peaks.concat())
}

/// The 35-dim features of a signal already at `fps · 512` Hz, with the given beat prior.
pub fn edge35_from_signal(y: &[f32], fps: u32, start_bpm: StartBpm) -> Result<MusicFeatures> {
    let sr = sample_rate_for_fps(fps)? as f64;
    Ok(Edge35Analysis::compute(y, sr)?.finish(fps, start_bpm))
}

/// EDGE/Lodge's start-BPM fallback on a signal loaded at 22050 Hz: `librosa.beat.tempo(y)`
/// with default onset strength (n_fft 2048, hop 512) and default prior (120 BPM).
pub fn tempo_at_22050(y22050: &[f32]) -> f64 {
    let sr = LIBROSA_DEFAULT_SR as f64;
    let mut db = mel::mel_power(y22050, sr, HOP);
    mel::power_to_db_in_place(&mut db.data, Some(80.0));
    let env = onset::onset_strength_from_mel_db(&db, N_FFT, HOP);
    tempo::tempo_fallback_from_env22050(&env)
}

/// Options for [`extract`].
#[derive(Clone, Debug)]
pub struct ExtractOptions {
    pub fps: u32,
    pub set: FeatureSet,
    /// Beat prior; `None` = AIST++ name, else the 22050 Hz estimate (as EDGE/Lodge do).
    pub start_bpm: Option<f64>,
}

impl Default for ExtractOptions {
    fn default() -> Self {
        Self {
            fps: 30,
            set: FeatureSet::Edge35,
            start_bpm: None,
        }
    }
}

/// Computes a song's features from its file, as the reference repos do on the whole song.
pub fn extract(source: &AudioSource, opts: &ExtractOptions) -> Result<MusicFeatures> {
    extract_with_signal(source, opts).map(|(f, _)| f)
}

/// [`extract`], also returning the signal the features were computed from (for plots).
pub fn extract_with_signal(
    source: &AudioSource,
    opts: &ExtractOptions,
) -> Result<(MusicFeatures, Audio)> {
    let path = source.label();
    match opts.set {
        FeatureSet::Edge35 => {
            let sr = sample_rate_for_fps(opts.fps)?;
            let t0 = std::time::Instant::now();
            let (audio, y22) = load_with_prior(source, sr, opts.start_bpm)?;
            tracing::debug!("timing: load done at {:?}", t0.elapsed());
            // The beat prior is only needed by the final beat tracking, so its 22050 Hz tempo
            // estimate runs alongside the spectral analysis.
            let (analysis, start) = rayon::join(
                || Edge35Analysis::compute(&audio.samples, sr as f64),
                || {
                    let b = resolve_start_bpm(path, opts.start_bpm, y22.as_ref());
                    tracing::debug!("timing: beat prior done at {:?}", t0.elapsed());
                    b
                },
            );
            let f = analysis?.finish(opts.fps, start);
            tracing::debug!("timing: features done at {:?}", t0.elapsed());
            Ok((f, audio))
        }
        FeatureSet::Tcdiff438 => {
            if opts.fps != 60 {
                return Err(MusicError::InvalidParameter(
                    "the TCDiff 438-dim set is defined at 60 fps (SR 30720); use --fps 60".into(),
                ));
            }
            if opts.start_bpm.is_some() {
                return Err(MusicError::InvalidParameter(
                    "--start-bpm does not apply to the TCDiff 438-dim set: TCDiff calls \
                     beat_track with librosa's default prior (120 BPM)"
                        .into(),
                ));
            }
            let audio = load_many(source, &[tcdiff::TCDIFF_SR], |_| {})?.remove(0);
            let p = tcdiff::tcdiff438_parts(&audio.samples, tcdiff::TCDIFF_SR as f64)?;
            let f = MusicFeatures {
                fps: tcdiff::TCDIFF_FPS,
                start_bpm: StartBpm::Given(tcdiff::BEAT_START_BPM),
                tempo_bpm: p.tempo_bpm,
                beat_frames: p.beat_frames.clone(),
                onset_frames: p.onset_peaks(),
                features: p.assemble(),
            };
            Ok((f, audio))
        }
    }
}

/// Loads at `sr`, and also at 22050 Hz in the same decoding pass when the beat prior has to
/// be estimated.
fn load_with_prior(
    source: &AudioSource,
    sr: u32,
    start_bpm: Option<f64>,
) -> Result<(Audio, Option<Audio>)> {
    let need_22050 = start_bpm.is_none() && aist_start_bpm(source.label()).is_none();
    if need_22050 {
        let mut v = load_many(source, &[sr, LIBROSA_DEFAULT_SR], |_| {})?;
        let y22 = v.pop();
        let main = v.pop().expect("one output per rate");
        Ok((main, y22))
    } else {
        let mut v = load_many(source, &[sr], |_| {})?;
        Ok((v.pop().expect("one output per rate"), None))
    }
}

pub(crate) fn aist_start_bpm(path: &Path) -> Option<f64> {
    let name = path.file_name()?.to_str()?;
    beat::start_bpm_from_aist_name(name)
}

fn resolve_start_bpm(path: &Path, given: Option<f64>, y22: Option<&Audio>) -> StartBpm {
    if let Some(b) = given {
        return StartBpm::Given(b);
    }
    if let Some(b) = aist_start_bpm(path) {
        return StartBpm::AistName(b);
    }
    let y22 = y22.expect("22050 Hz signal loaded when no prior is known");
    StartBpm::Estimated22050(tempo_at_22050(&y22.samples))
}
