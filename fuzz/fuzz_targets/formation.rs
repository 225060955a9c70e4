//! Arbitrary text as FORMATION.json → `Formation::parse` (the group's `--formation` and the
//! solo dancer's `--path`, from the CLI and the web form). The first byte picks the dancer
//! count (1–8) and the song length (0.5–600 s); `Ok`/`Err`, never a panic. An accepted
//! formation has finite keyframe times and positions.
#![no_main]

use dancegen_refine::formation::keyframes::Formation;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&pick, rest)) = data.split_first() else {
        return;
    };
    let Ok(json) = std::str::from_utf8(rest) else {
        return;
    };
    let dancers = 1 + (pick & 7) as usize;
    let song_seconds = [0.5, 10.0, 60.0, 600.0][(pick >> 3) as usize % 4];
    if let Ok(formation) = Formation::parse("FORMATION.json", json, dancers, song_seconds) {
        let text = format!("{formation:?}");
        assert!(!text.contains("NaN") && !text.contains("inf"), "{text}");
    }
});
