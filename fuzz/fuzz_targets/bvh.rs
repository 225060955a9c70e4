//! Arbitrary bytes → `parse_bvh_bytes`; every accepted file must survive `write_bvh` and parse
//! back. With lossless writing (`precision: None`) the re-parsed file must equal the original.
#![no_main]

use dancegen_formats::bvh::{BvhReadOptions, BvhWriteOptions, parse_bvh, parse_bvh_bytes, write_bvh};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let read = BvhReadOptions::default();
    let Ok(bvh) = parse_bvh_bytes(data, &read) else {
        return;
    };

    // Lossless round trip: identical structure and values.
    let text = write_bvh(&bvh, &BvhWriteOptions { precision: None })
        .expect("write_bvh (lossless) failed on a file parse_bvh accepted");
    let back = parse_bvh(&text, &read).expect("lossless write_bvh output does not parse");
    assert_eq!(bvh, back, "lossless BVH round trip changed the file");

    // Default (6 decimal places) output must at least parse, with the same shape.
    let text6 = write_bvh(&bvh, &BvhWriteOptions::default())
        .expect("write_bvh (precision 6) failed on a file parse_bvh accepted");
    let back6 = parse_bvh(&text6, &read).expect("write_bvh output (precision 6) does not parse");
    assert_eq!(bvh.joints.len(), back6.joints.len());
    assert_eq!(bvh.frames, back6.frames);
    assert_eq!(bvh.data.len(), back6.data.len());
});
