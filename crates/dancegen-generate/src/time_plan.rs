//! How long each stage of a job should take, in seconds, so that progress advances with time
//! and its ETA (elapsed / fraction done × fraction left) is honest. The shares used to be fixed
//! (1.5 s to analyse, 4 s to dance, whatever the song): a 288 s song said "about 5 s left" at
//! 31 % and took 74.5 s. Now the analysis scales with the song's length, the dance with the
//! seconds danced, each at this machine's measured speed once a job has run
//! ([`MeasuredSpeeds`]), and at a speed measured on the 2-core reference machine before that.

use std::collections::HashMap;
use std::sync::Mutex;

use dancegen_music::decode::MonoDecoder;

use crate::song::{Song, audio_source};

/// Seconds the song analysis takes per second of song on the 2-core reference machine
/// (`dancegen features` on a 288 s song: 1.8 s, and the generation's analysis adds the beat
/// tracker; 2026-12-07).
pub const ANALYSE_SECONDS_PER_SONG_SECOND: f64 = 0.02;

/// Fixed cost of analysing any song (decoding setup, the feature plan), seconds.
pub const ANALYSE_FIXED_SECONDS: f64 = 0.5;

/// A song's length when its header does not say (a stream without a frame count), seconds.
pub const UNKNOWN_SONG_SECONDS: f64 = 180.0;

/// The song's length from its header (cheap: nothing is decoded), or `None`.
pub fn song_seconds_hint(song: &Song) -> Option<f64> {
    let decoder = MonoDecoder::open_source(&audio_source(song)).ok()?;
    let rate = decoder.sample_rate();
    let frames = decoder.total_frames()?;
    (rate > 0).then(|| frames as f64 / f64::from(rate))
}

/// Seconds of music a request dances: from `start` (0) to `end` (the song's end) of a song
/// `song_s` long, at least 0.
pub fn danced_seconds(song_s: f64, start: Option<f64>, end: Option<f64>) -> f64 {
    let start = start.unwrap_or(0.0).max(0.0);
    let end = end.unwrap_or(song_s).min(song_s);
    (end - start).max(0.0)
}

/// Speeds measured on this machine by finished jobs: analysis seconds per song second, and
/// per system, generation seconds per danced second. Each new measure is blended into the
/// last (`BLEND` of the new), so one slow job (a busy machine) does not swing the next ETA
/// far.
#[derive(Default)]
pub struct MeasuredSpeeds {
    analyse: Mutex<Option<f64>>,
    generate: Mutex<HashMap<&'static str, f64>>,
}

/// Weight of a new measure in [`MeasuredSpeeds`].
const BLEND: f64 = 0.5;

fn blend(old: Option<f64>, new: f64) -> f64 {
    old.map_or(new, |o| o + BLEND * (new - o))
}

impl MeasuredSpeeds {
    /// Analysis seconds per song second: measured, or [`ANALYSE_SECONDS_PER_SONG_SECOND`].
    pub fn analyse(&self) -> f64 {
        let m = self.analyse.lock().unwrap_or_else(|e| e.into_inner());
        m.unwrap_or(ANALYSE_SECONDS_PER_SONG_SECOND)
    }

    /// Generation seconds per danced second of `system`: measured, or `reference`.
    pub fn generate(&self, system: &'static str, reference: f64) -> f64 {
        let m = self.generate.lock().unwrap_or_else(|e| e.into_inner());
        m.get(system).copied().unwrap_or(reference)
    }

    /// Learns from a finished job: `analyse_s` to analyse a `song_s` song, `generate_s` to
    /// dance `danced_s` with `system`. Measures too short to mean anything are skipped.
    pub fn learn(
        &self,
        system: &'static str,
        (analyse_s, song_s): (f64, f64),
        (generate_s, danced_s): (f64, f64),
    ) {
        if song_s >= 1.0 && analyse_s.is_finite() {
            let rate = ((analyse_s - ANALYSE_FIXED_SECONDS).max(0.0)) / song_s;
            let mut m = self.analyse.lock().unwrap_or_else(|e| e.into_inner());
            *m = Some(blend(*m, rate));
        }
        if danced_s >= 1.0 && generate_s.is_finite() {
            let mut m = self.generate.lock().unwrap_or_else(|e| e.into_inner());
            let new = blend(m.get(system).copied(), generate_s / danced_s);
            m.insert(system, new);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_dance_is_measured_by_the_seconds_danced() {
        assert_eq!(danced_seconds(288.0, None, None), 288.0);
        assert_eq!(danced_seconds(288.0, Some(30.0), Some(90.0)), 60.0);
        assert_eq!(danced_seconds(45.0, Some(30.0), Some(90.0)), 15.0);
        assert_eq!(danced_seconds(45.0, Some(50.0), None), 0.0);
    }

    #[test]
    fn measured_speeds_replace_the_reference_and_move_halfway_to_each_new_one() {
        let m = MeasuredSpeeds::default();
        assert_eq!(m.generate("solo", 0.4), 0.4);
        assert_eq!(m.analyse(), ANALYSE_SECONDS_PER_SONG_SECOND);
        m.learn("solo", (0.5 + 2.88, 288.0), (60.0, 120.0));
        assert!((m.generate("solo", 0.4) - 0.5).abs() < 1e-12);
        assert!((m.analyse() - 0.01).abs() < 1e-12);
        m.learn("solo", (0.5, 288.0), (120.0, 120.0));
        assert!((m.generate("solo", 0.4) - 0.75).abs() < 1e-12);
        // Another system keeps its reference; a 0.2 s dance teaches nothing.
        assert_eq!(m.generate("group", 0.6), 0.6);
        m.learn("group", (0.0, 0.0), (5.0, 0.2));
        assert_eq!(m.generate("group", 0.6), 0.6);
    }
}
