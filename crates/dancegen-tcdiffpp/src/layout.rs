//! How a group of dancers is laid out in tensors.
//!
//! - A **group window** is `[B, T, N_MAX · 151]`: frame-major, slot `s` in channels
//!   `s·151 .. (s+1)·151` (EDGE-151, `dancegen_nn::edge151`). Reshaped to `[B, T · N_MAX, 151]`
//!   it is the token sequence of the released code (token `k` = frame `k / N_MAX`, slot
//!   `k % N_MAX`; group.md "Corrections"), and reshaped to `[B, T, N_MAX · d]` the features of
//!   one frame's dancers are contiguous, which is what the Fusion Projection reads.
//! - **Slots** are ranks: slot 0 is the leftmost dancer as the audience sees them at frame 0
//!   (stage x ascending; TCDiff++ Eq. 5–7 sorts before noising, the released code's sort is
//!   dead code, group.md §1 row 1). A group of `n < N_MAX` dancers fills slots `0..n`; the
//!   others are zero and masked.
//! - **Roots** are relative to the active dancers' root centroid at the window's frame 0
//!   (Z-up x/y, `ROOT_HORIZONTAL`), in normalised units without the mean (group.md §5 P3), so
//!   windows can be chained and groups placed anywhere.

use dancegen_nn::burn;
use dancegen_nn::edge151::{DIMS, ROOT_HORIZONTAL};

use burn::tensor::{Bool, Device, Tensor, TensorData};

/// Most dancers one model serves (issue #17; GCD's `max_persons`, group.md §4 "Model size").
pub const N_MAX: usize = 5;
/// Fewest dancers of a group.
pub const N_MIN: usize = 2;
/// Channels of a group frame.
pub const GROUP_DIMS: usize = N_MAX * DIMS;

/// Channel `c` of slot `s` in a group frame.
pub fn channel(s: usize, c: usize) -> usize {
    s * DIMS + c
}

/// `[B, T, N_MAX·151]` → tokens `[B, T·N_MAX, 151]`.
pub fn to_tokens(x: Tensor<3>) -> Tensor<3> {
    let [b, t, _] = x.dims();
    x.reshape([b, t * N_MAX, DIMS])
}

/// Tokens `[B, T·N_MAX, c]` → `[B, T, N_MAX·c]`.
pub fn from_tokens(x: Tensor<3>) -> Tensor<3> {
    let [b, k, c] = x.dims();
    x.reshape([b, k / N_MAX, N_MAX * c])
}

/// 1 on the tokens of active slots, `[B, T·N_MAX, 1]`, for `dancers[b]` dancers in element `b`.
pub fn token_mask(dancers: &[usize], frames: usize, device: &Device) -> Tensor<3> {
    let b = dancers.len();
    let mut m = Vec::with_capacity(b * frames * N_MAX);
    for &n in dancers {
        for _ in 0..frames {
            m.extend((0..N_MAX).map(|s| f32::from(u8::from(s < n))));
        }
    }
    Tensor::from_data(TensorData::new(m, [b, frames * N_MAX, 1]), device)
}

/// Key padding of the self-attention over tokens: `true` on empty slots, `[B, T·N_MAX]`.
pub fn token_padding(dancers: &[usize], frames: usize, device: &Device) -> Tensor<2, Bool> {
    let b = dancers.len();
    let mut m = Vec::with_capacity(b * frames * N_MAX);
    for &n in dancers {
        for _ in 0..frames {
            m.extend((0..N_MAX).map(|s| s >= n));
        }
    }
    Tensor::from_data(TensorData::new(m, [b, frames * N_MAX]), device)
}

/// The group's root centroid (Z-up x/y, the units of `frame`) over the first `n` slots of one
/// group frame `[N_MAX·151]`.
pub fn centroid(frame: &[f32], n: usize) -> [f32; 2] {
    let mut c = [0f32; 2];
    for s in 0..n {
        for (k, &ch) in ROOT_HORIZONTAL.iter().enumerate() {
            c[k] += frame[channel(s, ch)];
        }
    }
    c.map(|v| v / n.max(1) as f32)
}

/// Adds `offset` to the root x/y of the first `n` slots of every frame of `frames`
/// (`[T, N_MAX·151]`, flat).
pub fn shift_roots(frames: &mut [f32], n: usize, offset: [f32; 2]) {
    for f in frames.chunks_exact_mut(GROUP_DIMS) {
        for s in 0..n {
            for (k, &ch) in ROOT_HORIZONTAL.iter().enumerate() {
                f[channel(s, ch)] += offset[k];
            }
        }
    }
}

/// Stage x of a Z-up root: EDGE keeps Y-up x as Z-up x (`conventions::yup_to_zup_point`), and
/// the stage's x is the world's (`dancegen_refine::formation`).
pub const STAGE_X: usize = ROOT_HORIZONTAL[0];

/// The slot order (`order[slot] = dancer`) that sorts dancers left to right by their stage x
/// (ties by index): the order of every training window's slots at its frame 0 (TCDiff++
/// Eq. 5-7), and so of every window the samplers make.
pub fn left_to_right(stage_x: &[f32]) -> Vec<usize> {
    let mut idx: Vec<usize> = (0..stage_x.len()).collect();
    idx.sort_by(|&a, &b| stage_x[a].total_cmp(&stage_x[b]).then(a.cmp(&b)));
    idx
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tokens_are_frame_major() {
        let dev = dancegen_nn::device::inference();
        let t = 3;
        let v: Vec<f32> = (0..t * GROUP_DIMS).map(|i| i as f32).collect();
        let x = Tensor::<3>::from_data(TensorData::new(v, [1, t, GROUP_DIMS]), &dev);
        let tok = to_tokens(x.clone())
            .into_data()
            .try_to_vec::<f32>()
            .unwrap();
        // Token k = (frame k / N_MAX, slot k % N_MAX); its channel c is frame f, slot s, c.
        for k in 0..t * N_MAX {
            let (f, s) = (k / N_MAX, k % N_MAX);
            assert_eq!(tok[k * DIMS + 5], (f * GROUP_DIMS + channel(s, 5)) as f32);
        }
        let back = from_tokens(to_tokens(x.clone()));
        assert_eq!(
            back.into_data().try_to_vec::<f32>().unwrap(),
            x.into_data().try_to_vec::<f32>().unwrap()
        );
    }

    #[test]
    fn masks_cover_the_active_slots() {
        let dev = dancegen_nn::device::inference();
        let m = token_mask(&[2, 5], 2, &dev)
            .into_data()
            .try_to_vec::<f32>()
            .unwrap();
        assert_eq!(&m[..N_MAX], &[1.0, 1.0, 0.0, 0.0, 0.0]);
        assert!(m[2 * N_MAX..].iter().all(|&v| v == 1.0));
        let p = token_padding(&[3], 1, &dev)
            .into_data()
            .try_to_vec::<bool>()
            .unwrap();
        assert_eq!(p, vec![false, false, false, true, true]);
    }

    #[test]
    fn sorting_and_centroids() {
        assert_eq!(left_to_right(&[1.0, -1.0]), vec![1, 0]);
        assert_eq!(left_to_right(&[0.5, -2.0, 0.5]), vec![1, 0, 2]);
        let mut frame = vec![0f32; GROUP_DIMS];
        frame[channel(0, 4)] = 1.0;
        frame[channel(1, 4)] = 3.0;
        frame[channel(1, 5)] = 4.0;
        frame[channel(2, 4)] = 100.0; // inactive slot
        assert_eq!(centroid(&frame, 2), [2.0, 2.0]);
        shift_roots(&mut frame, 2, [-2.0, -2.0]);
        assert_eq!(centroid(&frame, 2), [0.0, 0.0]);
        assert_eq!(frame[channel(2, 4)], 100.0);
    }
}
