//! Arbitrary bytes → `dancegen_io::npy::parse_npy` (every `.npy` dancegen reads, and every
//! member of a `.npz`): `Ok`/`Err`, never a panic, a hang or an allocation the bytes do not
//! justify; an accepted array holds exactly `shape.product()` values.
#![no_main]

use dancegen_io::npy::{parse_npy, parse_npy_text};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(a) = parse_npy(data) {
        let n = a.shape.iter().try_fold(1usize, |n, &d| n.checked_mul(d));
        assert_eq!(n, Some(a.data.len()), "shape {:?} vs {} values", a.shape, a.data.len());
        // Values come from the bytes: never more than the bytes can hold (1 byte each at least).
        assert!(a.data.len() <= data.len(), "{} values from {} bytes", a.data.len(), data.len());
    }
    let _ = parse_npy_text(data);
});
