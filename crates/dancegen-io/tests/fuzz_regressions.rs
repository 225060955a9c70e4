//! Inputs the fuzzers in `fuzz/` found, each kept as it was found (`tests/fuzz_regressions/`),
//! with what the reader must do with it.

use dancegen_io::npy::{NPY_MAX_HEADER_BYTES, NPY_MAX_HEADER_NESTING, parse_npy};

/// `fuzz/`'s `npy` target, 2026-12-07: a 257-byte `.npy` whose header holds 28 nested `[`.
/// The header parser backtracks exponentially in the nesting: `dancegen convert` spent over two
/// minutes on it. It is now refused before parsing, naming the nesting.
#[test]
fn a_deeply_nested_header_is_refused_at_once() {
    let bytes = include_bytes!("fuzz_regressions/npy_header_nested_28.npy");
    let e = parse_npy(bytes).unwrap_err();
    assert!(e.contains("nests 29 brackets deep"), "{e}"); // the dict, then 28 `[`
    assert!(
        e.contains(&format!("at most {NPY_MAX_HEADER_NESTING}")),
        "{e}"
    );
}

/// A header as `np.save` writes it, padded to `len` bytes with spaces (version 2 for lengths
/// over 65535).
fn npy_with_header(dict: &str, len: usize, data: &[u8]) -> Vec<u8> {
    let mut header = dict.to_string();
    header.push_str(&" ".repeat(len - dict.len() - 1));
    header.push('\n');
    let mut out = b"\x93NUMPY".to_vec();
    if len <= u16::MAX as usize {
        out.extend([1, 0]);
        out.extend((len as u16).to_le_bytes());
    } else {
        out.extend([2, 0]);
        out.extend((len as u32).to_le_bytes());
    }
    out.extend(header.as_bytes());
    out.extend(data);
    out
}

#[test]
fn headers_are_bounded_in_length_and_nesting_but_normal_ones_read() {
    let dict = "{'descr': '<f4', 'fortran_order': False, 'shape': (2,), }";
    let data = [0u8, 0, 128, 63, 0, 0, 0, 64]; // 1.0, 2.0
    let ok = npy_with_header(dict, 118, &data);
    assert_eq!(parse_npy(&ok).unwrap().data, vec![1.0, 2.0]);
    // Padding to the limit is fine; one byte more is refused, and so is a v2 header of 70 kB.
    assert!(parse_npy(&npy_with_header(dict, NPY_MAX_HEADER_BYTES, &data)).is_ok());
    for len in [NPY_MAX_HEADER_BYTES + 1, 70_000] {
        let e = parse_npy(&npy_with_header(dict, len, &data)).unwrap_err();
        assert!(e.contains(&format!("header is {len} bytes")), "{e}");
    }
    // Brackets inside strings do not count; real nesting does.
    let quoted = "{'descr': '<f4', 'fortran_order': False, 'shape': (2,), 'x': '[[[[[[[[[[[['}";
    assert!(parse_npy(&npy_with_header(quoted, 118, &data)).is_ok());
    let nested = format!(
        "{{'descr': '<f4', 'fortran_order': False, 'shape': (2,), 'x': {}{}}}",
        "[".repeat(9),
        "]".repeat(9)
    );
    let e = parse_npy(&npy_with_header(&nested, 118, &data)).unwrap_err();
    assert!(e.contains("nests 10 brackets deep"), "{e}");
}
