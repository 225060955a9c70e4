//! Arbitrary bytes as an uploaded character → `Character::from_self_contained_bytes` (the
//! web app's upload path: glTF JSON or GLB, VRM; external file URIs refused). The first byte
//! picks the name's extension. `Ok`/`Err`, never a panic or a hang.
#![no_main]

use dancegen_character::Character;
use libfuzzer_sys::fuzz_target;

const NAMES: [&str; 3] = ["upload.glb", "upload.vrm", "upload.gltf"];

fuzz_target!(|data: &[u8]| {
    let Some((&hint, file)) = data.split_first() else {
        return;
    };
    let name = NAMES[hint as usize % NAMES.len()];
    let _ = std::hint::black_box(Character::from_self_contained_bytes(name, file));
});
