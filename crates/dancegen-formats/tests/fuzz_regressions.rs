//! Regressions found by the cargo-fuzz targets in `fuzz/` (see `fuzz/README.md`).

use dancegen_formats::bvh::{BvhReadOptions, BvhWriteOptions, parse_bvh, write_bvh};

/// A one-joint BVH whose ROOT name is `name`, with one frame.
fn one_joint(name: &str) -> String {
    format!(
        "HIERARCHY\nROOT {name}\n{{\n\tOFFSET 0 0 0\n\tCHANNELS 3 Xposition Yposition Zposition\n\
         \tEnd Site\n\t{{\n\t\tOFFSET 0 1 0\n\t}}\n}}\nMOTION\nFrames: 1\nFrame Time: 0.033333\n1 2 3\n"
    )
}

/// fuzz/bvh crash-ff2a1ca2 (minimised by hand): the lexer splits tokens with
/// `split_ascii_whitespace`, which does not treat U+000B (vertical tab) or non-ASCII Unicode
/// whitespace (U+0085, U+00A0, U+3000, ...) as separators, so such characters stay at the
/// ends of a joint name. `Bvh::validate` then rejects the name via `str::trim` (Unicode
/// whitespace), so `write_bvh` fails on a file that `parse_bvh` accepted.
#[test]
fn bvh_name_with_non_ascii_whitespace_round_trips() {
    for name in [
        "hip\u{b}",
        "\u{b}hip",
        "hip\u{a0}",
        "\u{3000}hip",
        "hip\u{85}",
    ] {
        let text = one_joint(name);
        let Ok(bvh) = parse_bvh(&text, &BvhReadOptions::default()) else {
            continue; // rejecting the name at parse time is also a valid fix
        };
        let out = write_bvh(&bvh, &BvhWriteOptions { precision: None }).unwrap_or_else(|e| {
            panic!("parse_bvh accepted joint name {name:?} but write_bvh rejects it: {e}")
        });
        let back = parse_bvh(&out, &BvhReadOptions::default()).expect("re-parse");
        assert_eq!(bvh, back, "round trip changed the file for name {name:?}");
    }
}
