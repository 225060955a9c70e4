//! Arbitrary bytes as a `.npz` file → `dancegen_io::npz::read_npz` and `read_npz_text`: the zip
//! container (stored and deflated members, sizes from the archive) and each member's `.npy`.
//! `Ok`/`Err`, never a panic or a hang; the decompressed total stays within the reader's budget.
//! The reader takes a path, so each input is written to one file in the process's temp folder.
#![no_main]

use std::path::PathBuf;
use std::sync::OnceLock;

use dancegen_io::npz::{read_npz, read_npz_text};
use libfuzzer_sys::fuzz_target;

fn scratch() -> &'static PathBuf {
    static PATH: OnceLock<PathBuf> = OnceLock::new();
    PATH.get_or_init(|| std::env::temp_dir().join(format!("dancegen-fuzz-{}.npz", std::process::id())))
}

fuzz_target!(|data: &[u8]| {
    let path = scratch();
    std::fs::write(path, data).expect("write the scratch file");
    if let Ok(members) = read_npz(path) {
        for (_, a) in &members {
            let n = a.shape.iter().try_fold(1usize, |n, &d| n.checked_mul(d));
            assert_eq!(n, Some(a.data.len()));
        }
    }
    let _ = read_npz_text(path, "dancegen_record");
});
