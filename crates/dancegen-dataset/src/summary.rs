//! The fixed-width summary table `dataset build` prints.

use std::path::Path;

use crate::manifest::{Manifest, WarpReport};
use crate::song::stem;

/// A fixed-width summary table of the clips (name, song, frames, rates, beats, BAS).
pub fn summary_table(m: &Manifest) -> String {
    let mut s = format!(
        "{:<28} {:<24} {:>6} {:>8} {:>8} {:>9} {:>8} {:>8} {}\n",
        "clip", "song", "frames", "rate_min", "rate_max", "matched", "bas_pre", "bas_post", "split"
    );
    let f = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.3}"));
    for c in &m.clips {
        let song = stem(Path::new(&c.source_song));
        let split = if m.held_out.contains(&c.name) {
            "held_out"
        } else {
            "train"
        };
        match &c.warp {
            Some(w) => s.push_str(&format!(
                "{:<28} {:<24} {:>6} {:>8.3} {:>8.3} {:>4}/{:<4} {:>8} {:>8} {split}\n",
                c.name,
                song,
                c.frames,
                w.min_rate,
                w.max_rate,
                w.matched_beats,
                w.motion_beats,
                f(w.bas_before),
                f(w.bas_after)
            )),
            None => s.push_str(&format!(
                "{:<28} {:<24} {:>6} {:>8} {:>8} {:>9} {:>8} {:>8} {split}\n",
                c.name, song, c.frames, "-", "-", "-", "-", "-"
            )),
        }
    }
    let warped: Vec<&WarpReport> = m.clips.iter().filter_map(|c| c.warp.as_ref()).collect();
    if !warped.is_empty() {
        let mean = |g: &dyn Fn(&WarpReport) -> Option<f64>| {
            let v: Vec<f64> = warped.iter().filter_map(|w| g(w)).collect();
            v.iter().sum::<f64>() / v.len().max(1) as f64
        };
        s.push_str(&format!(
            "{} warped clips: mean BAS {:.3} -> {:.3}, rates {:.3}..{:.3}, {} / {} motion beats matched\n",
            warped.len(),
            mean(&|w| w.bas_before),
            mean(&|w| w.bas_after),
            warped.iter().map(|w| w.min_rate).fold(f64::INFINITY, f64::min),
            warped.iter().map(|w| w.max_rate).fold(f64::NEG_INFINITY, f64::max),
            warped.iter().map(|w| w.matched_beats).sum::<usize>(),
            warped.iter().map(|w| w.motion_beats).sum::<usize>(),
        ));
    }
    s
}
