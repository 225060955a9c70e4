//! Arbitrary text as a batch manifest → `batch_manifest::parse` (each line a JSON object
//! turned into `generate`'s arguments and parsed by its clap definition), and every parsed
//! line's arguments through `parse_generate_args` again, as `dancegen batch` does. Never a
//! panic; ids of accepted lines are unique.
#![no_main]

use std::collections::HashSet;
use std::path::Path;

use dancegen_generate::batch_manifest::{parse, parse_generate_args};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let mut ids = HashSet::new();
    for (_, line) in parse(text, Path::new("songs/manifest.jsonl")) {
        if let Ok(entry) = line {
            assert!(ids.insert(entry.id.clone()), "id {} accepted twice", entry.id);
            let _ = parse_generate_args(&entry.args);
        }
    }
});
