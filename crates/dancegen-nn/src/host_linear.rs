//! `Linear` for inference (no autodiff), computed on the host with one GEMM.
//!
//! Why this exists: in group sampling (`perf record` of `benches/group_sampling.rs`) a quarter
//! of the samples ran on the main thread while the two rayon workers idled, and most of that
//! was burn-flex 0.22's matmul output buffer: `FlexTensor::empty` allocates a zeroed `Vec<u8>`
//! and `Bytes::from_bytes_vec` then copies it into a second, 16-byte-aligned allocation (the
//! alignment it checks is the `Vec<u8>`'s layout's, 1, not the pointer's), so every Linear
//! paid page faults on two fresh buffers plus a memmove, and then a serial pass for the bias.
//! Burn has no hook for that; this path writes the bias rows into one `Vec<f32>` (handed to
//! Burn without a copy), accumulates `x · W` onto them with the `gemm` crate burn-flex itself
//! uses, and treats all leading dimensions as one tall matrix.
//!
//! Training (autodiff) and other backends keep Burn's op.

use burn::nn::Linear;
use burn::tensor::{Tensor, TensorData};
use gemm::Parallelism;
use rayon::prelude::*;

use crate::host_view::{HostF32, eligible};

/// Below this many multiply-adds one thread does the GEMM (rayon's hand-off costs more).
const PARALLEL_MIN_FLOPS: usize = 1 << 18;

/// Rows per task of [`repeat_rows`].
const FILL_ROWS: usize = 256;

/// `layer.forward(x)`, on the host when `x` and the layer's parameters are inference `f32`
/// tensors on the flex CPU backend ([`eligible`]), else Burn's op.
pub fn forward<const D: usize>(layer: &Linear, x: Tensor<D>) -> Tensor<D> {
    let weight = layer.weight.val();
    let bias = layer.bias.as_ref().map(|b| b.val());
    if !eligible(&x) || !eligible(&weight) || bias.as_ref().is_some_and(|b| !eligible(b)) {
        return layer.forward(x);
    }
    let device = x.device();
    let mut shape = x.dims();
    let [d_in, d_out] = layer.weight.dims();
    assert_eq!(
        shape[D - 1],
        d_in,
        "Linear of width {d_in} given inputs of width {}",
        shape[D - 1]
    );
    let rows = shape[..D - 1].iter().product::<usize>();
    shape[D - 1] = d_out;
    let x = HostF32::new(&x);
    let x = x.as_slice();
    let w = HostF32::new(&weight);
    let w = w.as_slice();
    // The bias rows are the GEMM's starting value (no zeroing pass, no bias pass after).
    let (mut out, with_bias) = match &bias {
        Some(b) => (repeat_rows(HostF32::new(b).as_slice(), rows), true),
        None => (repeat_rows(&vec![0.0; d_out], rows), false),
    };
    if rows > 0 && d_out > 0 {
        let parallelism = if rows * d_in * d_out >= PARALLEL_MIN_FLOPS {
            Parallelism::Rayon(rayon::current_num_threads())
        } else {
            Parallelism::None
        };
        // out[rows, d_out] (+)= x[rows, d_in] · W[d_in, d_out], all row-major.
        // SAFETY: each pointer/stride pair addresses exactly its row-major buffer: `out` is
        // rows × d_out, `x` rows × d_in, `w` d_in × d_out, as checked above.
        unsafe {
            gemm::gemm(
                rows,
                d_out,
                d_in,
                out.as_mut_ptr(),
                1,
                d_out as isize,
                with_bias,
                x.as_ptr(),
                1,
                d_in as isize,
                w.as_ptr(),
                1,
                d_out as isize,
                1.0,
                1.0,
                false,
                false,
                false,
                parallelism,
            );
        }
    }
    Tensor::from_data(TensorData::new(out, shape), &device)
}

/// `rows` copies of `row`, one after another, written by the rayon workers: a fill on the
/// calling thread (or `vec![0.0; n]`'s memset) kept both workers waiting, and took the new
/// buffer's page faults one at a time.
pub fn repeat_rows(row: &[f32], rows: usize) -> Vec<f32> {
    let n = rows * row.len();
    let mut out: Vec<f32> = Vec::with_capacity(n);
    out.spare_capacity_mut()[..n]
        .par_chunks_mut(FILL_ROWS * row.len().max(1))
        .for_each(|block| {
            for (dst, &src) in block.iter_mut().zip(row.iter().cycle()) {
                dst.write(src);
            }
        });
    // SAFETY: the loop above wrote all `n` elements (every block is whole rows, and `cycle`
    // repeats the row along them).
    unsafe { out.set_len(n) };
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use burn::nn::LinearConfig;
    use burn::tensor::{Device, Distribution};

    fn max_abs_diff<const D: usize>(a: Tensor<D>, b: Tensor<D>) -> f32 {
        (a - b).abs().max().into_scalar::<f32>()
    }

    #[test]
    fn matches_burns_linear_for_any_rank_with_and_without_bias() {
        let dev = Device::flex();
        dev.seed(7);
        let n = Distribution::Normal(0.0, 1.0);
        for bias in [true, false] {
            let layer = LinearConfig::new(24, 40).with_bias(bias).init(&dev);
            let x3 = Tensor::<3>::random([3, 50, 24], n, &dev);
            let x2 = Tensor::<2>::random([7, 24], n, &dev);
            // A transposed (non-contiguous) input.
            let xt = Tensor::<3>::random([3, 24, 50], n, &dev).swap_dims(1, 2);
            let big = Tensor::<3>::random([4, 300, 24], n, &dev);
            assert!(max_abs_diff(forward(&layer, x3.clone()), layer.forward(x3)) < 1e-5);
            assert!(max_abs_diff(forward(&layer, x2.clone()), layer.forward(x2)) < 1e-5);
            assert!(max_abs_diff(forward(&layer, xt.clone()), layer.forward(xt)) < 1e-5);
            assert!(max_abs_diff(forward(&layer, big.clone()), layer.forward(big)) < 1e-5);
        }
    }

    #[test]
    fn repeat_rows_fills_every_row() {
        let row = [1.0, -2.0, 3.5];
        let out = repeat_rows(&row, 2 * FILL_ROWS + 5);
        assert_eq!(out.len(), 3 * (2 * FILL_ROWS + 5));
        assert!(out.chunks_exact(3).all(|r| r == row));
        assert!(repeat_rows(&[], 7).is_empty());
        assert!(repeat_rows(&row, 0).is_empty());
    }

    #[test]
    fn empty_batches_and_tracked_inputs_fall_back_cleanly() {
        let dev = Device::flex();
        let layer = LinearConfig::new(4, 3).init(&dev);
        let empty = forward(&layer, Tensor::<3>::zeros([2, 0, 4], &dev));
        assert_eq!(empty.dims(), [2, 0, 3]);
        let ad = dev.autodiff();
        let layer = LinearConfig::new(4, 3).init(&ad);
        let x = Tensor::<2>::ones([2, 4], &ad).require_grad();
        let y = forward(&layer, x.clone());
        assert!(y.is_autodiff());
        let grads = y.sum().backward();
        assert!(
            x.grad(&grads).is_some(),
            "autodiff keeps Burn's differentiable op"
        );
    }
}
