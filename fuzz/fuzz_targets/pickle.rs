//! Arbitrary bytes → `pickle::parse`: must return `Ok`/`Err`, never panic, hang or abort.
#![no_main]

use dancegen_formats::pickle::{PickleValue, parse};
use libfuzzer_sys::fuzz_target;

/// Touches every value so that lazily-wrong arrays (shape/data mismatches) would trip.
fn walk(v: &PickleValue, depth: usize) -> usize {
    if depth > 64 {
        return 0;
    }
    let _ = v.type_name();
    let _ = v.as_f64();
    match v {
        PickleValue::List(items) | PickleValue::Tuple(items) => {
            items.iter().map(|x| walk(x, depth + 1)).sum::<usize>() + 1
        }
        PickleValue::Dict(entries) => {
            entries
                .iter()
                .map(|(k, x)| walk(k, depth + 1) + walk(x, depth + 1))
                .sum::<usize>()
                + 1
        }
        PickleValue::NdArray(a) => {
            // Invariant: the element count matches the shape.
            let expected = a.shape.iter().try_fold(1usize, |n, &d| n.checked_mul(d));
            assert_eq!(expected, Some(a.len()), "ndarray shape {:?} vs {} elements", a.shape, a.len());
            let c = a.to_c_order();
            assert_eq!(c.len(), a.len());
            c.to_f64_vec().len() + a.to_f32_vec().len()
        }
        _ => 1,
    }
}

fuzz_target!(|data: &[u8]| {
    if let Ok(v) = parse(data) {
        std::hint::black_box(walk(&v, 0));
    }
});
