//! What the viewer's timeline draws under the scrub bar: the danced part of the song as a
//! waveform (the loudest sample of each of [`BARS`] equal slices, scaled so the loudest slice
//! is 1) and its beats, as the generation found them (seconds from the dance's start). Written
//! once per job, after its first variation, as `timeline.json` in the job's folder.

use std::path::Path;

/// The timeline's file name in the job folder.
pub const TIMELINE: &str = "timeline.json";
/// Slices of the waveform (about one per pixel of a laptop-wide timeline).
pub const BARS: usize = 800;

/// The peaks of `samples` (mono, `rate` Hz) between `start_s` and `end_s`, in [`BARS`] slices,
/// scaled to the loudest (all 0 for silence).
pub fn peaks(samples: &[f32], rate: u32, start_s: f64, end_s: f64) -> Vec<f32> {
    let at = |s: f64| ((s * f64::from(rate)).round().max(0.0) as usize).min(samples.len());
    let (a, b) = (at(start_s), at(end_s));
    let span = b.saturating_sub(a);
    let mut bars: Vec<f32> = (0..BARS)
        .map(|i| {
            let lo = a + span * i / BARS;
            let hi = (a + span * (i + 1) / BARS).max(lo + 1).min(b.max(lo));
            samples[lo.min(samples.len())..hi.min(samples.len())]
                .iter()
                .fold(0f32, |m, s| m.max(s.abs()))
        })
        .collect();
    let loudest = bars.iter().fold(0f32, |m, &v| m.max(v));
    if loudest > 0.0 {
        for v in &mut bars {
            *v /= loudest;
        }
    }
    bars
}

/// Decodes the song and writes `dir/timeline.json`: `{"duration", "tempo_bpm", "beats",
/// "peaks"}`.
pub fn write_timeline(
    dir: &Path,
    song: &Path,
    span_s: (f64, f64),
    beats_s: &[f64],
    tempo_bpm: f64,
) -> Result<(), String> {
    let (samples, rate) = dancegen_music::decode::decode_mono(song).map_err(|e| e.to_string())?;
    let (start, end) = span_s;
    let json = serde_json::json!({
        "duration": end - start,
        "tempo_bpm": tempo_bpm,
        "beats": beats_s,
        "peaks": peaks(&samples, rate, start, end),
    });
    dancegen_io::write_atomic(&dir.join(TIMELINE), |w| {
        serde_json::to_writer(w, &json).map_err(std::io::Error::other)
    })
    .map_err(|e| e.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn peaks_are_the_loudest_sample_of_each_slice_of_the_span() {
        // 10 s at 100 Hz: silence, then a click of 0.5 at 3 s and one of -1 at 7 s.
        let mut s = vec![0f32; 1000];
        s[300] = 0.5;
        s[700] = -1.0;
        let p = peaks(&s, 100, 2.0, 8.0);
        assert_eq!(p.len(), BARS);
        // 6 s over 800 slices of 0.0075 s: 3 s falls in slice 134, 7 s in slice 667 (the
        // slices are shorter than a sample here, so a click shows in one slice only).
        let loud: Vec<(usize, f32)> = p
            .iter()
            .copied()
            .enumerate()
            .filter(|&(_, v)| v > 0.0)
            .collect();
        assert_eq!(loud, [(134, 0.5), (667, 1.0)]);
        assert!(peaks(&[0f32; 50], 100, 0.0, 0.5).iter().all(|&v| v == 0.0));
        // A span past the end of the samples reads what is there.
        assert_eq!(peaks(&s, 100, 6.0, 20.0).len(), BARS);
    }
}
