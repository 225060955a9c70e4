//! Tempo on full real songs with a known tempo: the Sectoid "Frets on Fire" songs in
//! `shared/data/music/sectoid/`, whose `.mid` charts carry the true (constant) tempo.
//!
//! Runs the product path (`features::extract`: load, onset envelope, EDGE/Lodge start-BPM
//! estimate at 22050 Hz, `beat_track`) at both frame rates. The estimate must be the true tempo
//! or an octave of it (beat trackers legitimately lock onto half or double time); the test
//! prints which.
//!
//! Tolerance: 2 % (issue #2). librosa's tempo can only take the grid values `60·fps/lag` (lag
//! in whole frames). At 60 fps the grid is fine enough for 2 % everywhere in the dance range,
//! so 60 fps is held to 2 % strictly. At 30 fps the grid around 135 BPM is 128.57 / 138.46 —
//! 2.6 % from the true tempo — so there 2 % is impossible by construction and we accept the
//! grid value nearest the target (librosa itself gives 138.46 for this song).

mod common;

use std::path::Path;

use dancegen_music::decode::AudioSource;
use dancegen_music::features::{ExtractOptions, FeatureSet, extract};

/// Tempo of a standard MIDI file from its first set_tempo meta event `FF 51 03 tt tt tt`
/// (microseconds per quarter note), in BPM.
fn midi_tempo_bpm(path: &Path) -> f64 {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let at = bytes
        .windows(3)
        .position(|w| w == [0xFF, 0x51, 0x03])
        .unwrap_or_else(|| panic!("{}: no set_tempo event", path.display()));
    let us = bytes[at + 3..at + 6]
        .iter()
        .fold(0u32, |acc, &b| (acc << 8) | b as u32);
    60e6 / us as f64
}

#[test]
fn sectoid_songs_tempo_is_true_tempo_or_octave() {
    let dir = common::shared_dir().join("data/music/sectoid");
    let mut failures = Vec::new();
    for name in ["escape_from_chaosland", "feelings", "metal_madness"] {
        let truth = midi_tempo_bpm(&dir.join(format!("{name}.mid")));
        for fps in [30u32, 60] {
            let f = extract(
                &AudioSource::File(dir.join(format!("{name}.ogg"))),
                &ExtractOptions {
                    fps,
                    set: FeatureSet::Edge35,
                    start_bpm: None,
                },
            )
            .unwrap();
            let bpm = f.tempo_bpm;
            let matched = [
                (1.0, "true tempo"),
                (2.0, "double (octave)"),
                (0.5, "half (octave)"),
            ]
            .into_iter()
            .find_map(|(factor, what)| {
                let target = truth * factor;
                let rel = (bpm / target - 1.0).abs();
                if rel <= 0.02 {
                    return Some((factor, what, "within 2 %"));
                }
                // 30 fps only: the representable tempo nearest the target.
                let fpsf = fps as f64;
                let lag = (60.0 * fpsf / target).round().max(1.0);
                let nearest = 60.0 * fpsf / lag;
                (fps == 30 && bpm == nearest).then_some((factor, what, "nearest 30 fps grid value"))
            });
            println!(
                "{name:<22} fps{fps}: MIDI {truth:>7.3} BPM, tempo {bpm:>7.3} BPM -> {}",
                matched.map_or("NO MATCH".to_string(), |(factor, what, how)| format!(
                    "{what}, {:+.2} %, {how}",
                    (bpm / (truth * factor) - 1.0) * 100.0
                ))
            );
            if matched.is_none() {
                failures.push(format!("{name} fps{fps}: {bpm:.3} vs {truth:.3} BPM"));
            }
            // The beats cover the song at about the estimated tempo.
            let secs = f.features.rows as f64 / fps as f64;
            assert!(
                f.beat_frames.len() as f64 > 0.5 * secs * bpm / 60.0,
                "{name}: too few beats"
            );
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
