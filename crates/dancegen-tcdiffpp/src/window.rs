//! A raw training window in the network's coordinates ([`crate::layout`]): the same
//! re-sorting and re-basing LGDS applies to every window it samples, so training windows and
//! sampled windows look alike.

use dancegen_nn::edge151::DIMS;

use crate::layout::{GROUP_DIMS, N_MAX, STAGE_X, centroid, channel, shift_roots};
use crate::sampler::{permute, sorted_slots};
use crate::swap::swap_code;

/// `raw` (`[frames, N_MAX·151]`, raw EDGE-151 per slot, dancers in slots `0..n`) with slots
/// sorted left to right at frame 0, roots relative to the frame-0 centroid, then normalised
/// by the model's per-channel `(scale, shift)` (`GroupDenoiser::denorm`, one dancer's 151
/// channels; zero shift on the horizontal root), empty slots zero. Also returns the window's
/// swap code (start order → order at the last frame).
pub fn training_window(
    raw: &[f32],
    frames: usize,
    n: usize,
    scale: &[f32],
    shift: &[f32],
) -> (Vec<f32>, Vec<f32>) {
    assert!((1..=N_MAX).contains(&n) && raw.len() == frames * GROUP_DIMS && frames > 0);
    let perm = sorted_slots(&raw[..GROUP_DIMS], n);
    let mut x = permute(raw, &perm, false);
    let c = centroid(&x[..GROUP_DIMS], n);
    shift_roots(&mut x, n, [-c[0], -c[1]]);
    let last = &x[(frames - 1) * GROUP_DIMS..];
    let end_x: Vec<f32> = (0..n).map(|s| last[channel(s, STAGE_X)]).collect();
    let swap = swap_code(&end_x);
    for f in x.chunks_exact_mut(GROUP_DIMS) {
        for (i, v) in f.iter_mut().enumerate() {
            let (s, ch) = (i / DIMS, i % DIMS);
            *v = if s < n {
                (*v - shift[ch]) / scale[ch]
            } else {
                0.0
            };
        }
    }
    (x, swap)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::layout::N_MAX;
    use dancegen_nn::edge151::ROOT_HORIZONTAL;

    #[test]
    fn windows_are_sorted_rebased_and_carry_their_swap() {
        let frames = 3;
        let mut raw = vec![0f32; frames * GROUP_DIMS];
        // Dancer 0 starts right (x = 2) and ends left; dancer 1 the other way round.
        for f in 0..frames {
            let t = f as f32 / (frames - 1) as f32;
            raw[f * GROUP_DIMS + channel(0, ROOT_HORIZONTAL[0])] = 2.0 - 4.0 * t;
            raw[f * GROUP_DIMS + channel(1, ROOT_HORIZONTAL[0])] = -2.0 + 4.0 * t;
            raw[f * GROUP_DIMS + channel(0, 10)] = 7.0;
        }
        let scale = vec![2.0f32; DIMS];
        let mut shift = vec![1.0f32; DIMS];
        for &c in &ROOT_HORIZONTAL {
            shift[c] = 0.0;
        }
        let (x, swap) = training_window(&raw, frames, 2, &scale, &shift);
        // Slot 0 is the dancer on the left at frame 0 (dancer 1), at x = −2 → −1 normalised.
        assert_eq!(x[channel(0, ROOT_HORIZONTAL[0])], -1.0);
        assert_eq!(x[channel(1, 10)], (7.0 - 1.0) / 2.0);
        assert_eq!(x[channel(0, 10)], (0.0 - 1.0) / 2.0);
        // They swap: slot 0 ends second from the left.
        assert_eq!(swap[1], 1.0);
        assert_eq!(swap[N_MAX], 1.0);
        assert!(x[2 * DIMS..GROUP_DIMS].iter().all(|&v| v == 0.0));
    }
}
