//! Golden test: beat-align scores against `shared/fixtures/metrics/outputs/bas/` (README §4.3).
//!
//! Per clip and variant: the motion-beat list must equal the reference's exactly; the score must
//! match to relative 1e-6 (Bailando/LODGE float64; Fact/GCD float32 — also reported whether it is
//! bit-identical), or be `None` where the reference raised (`"error"` entries: the frozen clip
//! under Bailando/LODGE). Music beats: `music_beats_real_freezingpoint_fps{30,60}.npy` cut per
//! variant ([`clip_music_beats`]); LODGE uses the whole-song list `lodge_beats_from_wav_fps30.npy`.
//! The set means in the JSON are recomputed from our per-clip scores as well.

mod common;

use common::metrics_fixtures;
use std::path::Path;

use dancegen_metrics::bas::{Variant, beat_align_score, clip_music_beats, motion_beats};
use dancegen_metrics::read_joints;

const REL_TOL: f64 = 1e-6;

fn read_indices(path: &Path) -> Vec<usize> {
    dancegen_io::read_npy(path)
        .unwrap_or_else(|e| panic!("{e}"))
        .data
        .iter()
        .map(|&v| v as usize)
        .collect()
}

fn rel(a: f64, g: f64) -> f64 {
    if a == g {
        0.0
    } else if g == 0.0 {
        f64::INFINITY
    } else {
        (a - g).abs() / g.abs()
    }
}

#[test]
fn bas_matches_reference_golden_files() {
    let dir = metrics_fixtures();
    let out = dir.join("outputs/bas");
    let beats30 = read_indices(&out.join("music_beats_real_freezingpoint_fps30.npy"));
    let beats60 = read_indices(&out.join("music_beats_real_freezingpoint_fps60.npy"));
    let lodge_beats = read_indices(&out.join("lodge_beats_from_wav_fps30.npy"));
    assert_eq!(
        (beats30.len(), beats60.len(), lodge_beats.len()),
        (59, 59, 89)
    );

    let mut failures = Vec::new();
    let mut checked = 0;
    for variant in Variant::ALL {
        let json: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(out.join(format!("bas_{}.json", variant.name()))).unwrap(),
        )
        .unwrap();
        let per_clip = json["per_clip"].as_object().unwrap();
        // (real, generated) scores per fps, for the set means.
        let mut sets: std::collections::BTreeMap<(u32, bool), Vec<f64>> = Default::default();
        let (mut f32_exact, mut scored) = (0, 0);
        println!("== {}", variant.name());
        for (key, entry) in per_clip {
            let (name, fps) = key.split_once('@').unwrap();
            let fps: u32 = fps.trim_end_matches("fps").parse().unwrap();
            let sub = if name.starts_with("gen") {
                "generated"
            } else {
                "real"
            };
            let joints =
                read_joints(&dir.join(format!("inputs/{sub}/{name}_yup_{fps}fps.npy"))).unwrap();
            let frames = joints.len() / 72;
            let song = match (variant, fps) {
                (Variant::Lodge, _) => &lodge_beats,
                (_, 30) => &beats30,
                _ => &beats60,
            };
            let music = clip_music_beats(song, frames, variant);
            let motion = motion_beats(&joints, variant);
            let score = beat_align_score(&music, &motion, variant);
            checked += 1;

            if let Some(err) = entry.get("error") {
                println!("{key:28} T={frames:4} ours {score:?}  golden raises ({err})");
                if score.is_some() {
                    failures.push(format!(
                        "{}/{key}: expected None, got {score:?}",
                        variant.name()
                    ));
                }
                continue;
            }
            let golden_beats: Vec<usize> = entry["motion_beats"]
                .as_array()
                .unwrap()
                .iter()
                .map(|v| v.as_u64().unwrap() as usize)
                .collect();
            if motion != golden_beats {
                failures.push(format!(
                    "{}/{key}: motion beats\n  ours   {motion:?}\n  golden {golden_beats:?}",
                    variant.name()
                ));
            }
            if let Some(used) = entry.get("music_beats_used") {
                let used: Vec<usize> = used
                    .as_array()
                    .unwrap()
                    .iter()
                    .map(|v| v.as_u64().unwrap() as usize)
                    .collect();
                if used != music {
                    failures.push(format!("{}/{key}: music beats used differ", variant.name()));
                }
            }
            if let Some(n) = entry.get("n_music_beats_used") {
                assert_eq!(n.as_u64(), Some(music.len() as u64), "{key}");
            }
            if let Some(len) = entry.get("length") {
                assert_eq!(len.as_u64(), Some(frames as u64 - 1), "{key}: length");
            }
            let golden = entry["score"].as_f64().unwrap();
            let Some(ours) = score else {
                failures.push(format!(
                    "{}/{key}: ours None, golden {golden}",
                    variant.name()
                ));
                continue;
            };
            let e = rel(ours, golden);
            scored += 1;
            if ours == golden {
                f32_exact += 1;
            }
            println!(
                "{key:28} T={frames:4} beats {:3} ours {ours:.17} golden {golden:.17} rel {e:.2e}",
                motion.len()
            );
            if e > REL_TOL {
                failures.push(format!(
                    "{}/{key}: score ours {ours} golden {golden} rel {e:.3e}",
                    variant.name()
                ));
            }
            sets.entry((fps, sub == "real")).or_default().push(ours);
        }
        println!("   {scored} scores, {f32_exact} bit-identical to the golden value");

        // Set means as the fixtures record them (numpy mean for Bailando/LODGE; Python
        // `sum / len` for Fact/GCD — same value up to rounding, checked at REL_TOL).
        for ((fps, real), vals) in &sets {
            let mean = vals.iter().sum::<f64>() / vals.len() as f64;
            let which = if *real { "real" } else { "gen" };
            let golden = match variant {
                Variant::Bailando => {
                    json[format!("calc_ba_score_{which}_{fps}fps")]["value"].as_f64()
                }
                _ => json[format!("mean_{which}_{fps}fps")].as_f64(),
            }
            .unwrap();
            let e = rel(mean, golden);
            println!("   mean {which}@{fps}fps ours {mean:.17} golden {golden:.17} rel {e:.2e}");
            if e > REL_TOL {
                failures.push(format!(
                    "{}: mean {which}@{fps}: {mean} vs {golden}",
                    variant.name()
                ));
            }
        }
    }
    assert_eq!(checked, 22 + 11 + 11 + 11);
    assert!(
        failures.is_empty(),
        "{} mismatches:\n{}",
        failures.len(),
        failures.join("\n")
    );
}
