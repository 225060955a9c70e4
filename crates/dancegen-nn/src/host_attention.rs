//! Multi-head attention for inference (no autodiff), computed on the host.
//!
//! Why this exists: profiling Lodge++ sampling (`perf record` on `dancegen generate`, 1024
//! frames) put a third of the whole run in burn-flex 0.22's attention, almost all of it in the
//! softmax between the two GEMMs: it calls the scalar libm `expf` per score through a function
//! pointer, with the running sum spilled to the stack between calls. Burn has no hook to swap
//! that kernel, so inference takes this path; training (autodiff) keeps Burn's op.
//!
//! What it does differently, and nothing else:
//! - the same two GEMMs per (batch, head) with the `gemm` crate burn-flex itself uses, reading
//!   the heads straight out of the `[B, T, d]` projections by stride and writing the output in
//!   `[B, Tq, d]` order, so the head split/merge transposes disappear;
//! - the softmax with [`crate::vector_math::exp`], which LLVM vectorises, compiled for
//!   AVX-512 / AVX2 and picked at run time.
//!
//! Semantics match Burn's attention: scale `1/√dh`, blocked scores are −∞, a fully blocked
//! row gives zeros; NaN scores propagate.

use burn::tensor::{Bool, Tensor, TensorData};
use gemm::Parallelism;
use rayon::prelude::*;

use crate::host_linear::repeat_rows;
use crate::host_view::HostF32;
use crate::vector_math::{exp_nonpositive, widest};

pub use crate::host_view::eligible;

/// Projected keys and values `[B, Tk, d]` on the host.
#[derive(Clone, Debug)]
pub struct HostKv {
    k: HostF32,
    v: HostF32,
    b: usize,
    tk: usize,
    d: usize,
}

impl HostKv {
    /// Views `k`, `v` `[B, Tk, d]` ([`eligible`] tensors) without copying them.
    pub fn new(k: Tensor<3>, v: Tensor<3>) -> HostKv {
        let [b, tk, d] = k.dims();
        assert_eq!(v.dims(), [b, tk, d], "keys and values disagree");
        HostKv {
            k: HostF32::new(&k),
            v: HostF32::new(&v),
            b,
            tk,
            d,
        }
    }
}

/// Attention of `q` `[B, Tq, d]` ([`eligible`]) over `kv` with `heads` heads, on the host.
/// `attn_mask` `[Tq, Tk]` and `key_padding` `[B, Tk]` are `true` where blocked.
pub fn attention(
    q: Tensor<3>,
    kv: &HostKv,
    heads: usize,
    attn_mask: Option<&Tensor<2, Bool>>,
    key_padding: Option<&Tensor<2, Bool>>,
) -> Tensor<3> {
    let [b, tq, d] = q.dims();
    assert_eq!(
        (kv.b, kv.d),
        (b, d),
        "queries [{b}, {tq}, {d}] and keys [{}, {}, {}] disagree",
        kv.b,
        kv.tk,
        kv.d
    );
    let device = q.device();
    let q = HostF32::new(&q);
    let shape = Shape {
        b,
        tq,
        tk: kv.tk,
        d,
        heads,
    };
    let bools = |m: &Tensor<2, Bool>| -> Vec<bool> {
        m.clone()
            .into_data()
            .convert::<bool>()
            .try_into_vec::<bool>()
            .expect("bool mask")
    };
    let masks = Masks {
        attn: attn_mask.map(bools),
        key_padding: key_padding.map(bools),
    };
    let out = attend(
        q.as_slice(),
        kv.k.as_slice(),
        kv.v.as_slice(),
        &shape,
        &masks,
    );
    Tensor::from_data(TensorData::new(out, [b, tq, d]), &device)
}

/// Sizes of one call.
struct Shape {
    b: usize,
    tq: usize,
    tk: usize,
    d: usize,
    heads: usize,
}

/// Host copies of the masks (`true` = blocked).
struct Masks {
    /// `[Tq, Tk]`.
    attn: Option<Vec<bool>>,
    /// `[B, Tk]`.
    key_padding: Option<Vec<bool>>,
}

/// Query rows per task, so that a batch of one or two sequences (LGDS denoises one window at
/// a time) still gives both cores work. Blocking does not speed up a tall batch: on the
/// parallel sampler's shape (46 × 750 tokens, d 128, 4 heads, 2 threads) one call took 88–90 ms
/// unblocked, 91 ms at 256 rows, 94 ms at 128 and 102 ms at 64 (a throwaway timing test,
/// 5 calls each, release build; the K and V panels are re-packed per block), so the block is
/// the largest that still splits a 750-token window three ways.
const QUERY_BLOCK: usize = 256;

/// The kernel on flat row-major `[B, T, d]` slices; output `[B, Tq, d]`.
fn attend(q: &[f32], k: &[f32], v: &[f32], s: &Shape, masks: &Masks) -> Vec<f32> {
    let Shape {
        b,
        tq,
        tk,
        d,
        heads,
    } = *s;
    assert_eq!(d % heads, 0, "d {d} not divisible by {heads} heads");
    let dh = d / heads;
    let scale = 1.0 / (dh as f32).sqrt();
    // Zeroed on the rayon workers (a memset on the calling thread left them idle).
    let mut out = repeat_rows(&vec![0f32; d], b * tq);
    if out.is_empty() || tk == 0 {
        return out;
    }
    // Batch elements whose keys are all unpadded skip the per-row masking.
    let padded: Vec<bool> = (0..b)
        .map(|bi| {
            masks
                .key_padding
                .as_ref()
                .is_some_and(|m| m[bi * tk..(bi + 1) * tk].iter().any(|&x| x))
        })
        .collect();
    // One task per (batch element, block of query rows); its heads write disjoint columns of
    // its rows of the output.
    let mut tasks: Vec<(usize, usize, &mut [f32])> = Vec::new();
    for (bi, out_b) in out.chunks_mut(tq * d).enumerate() {
        for (blk, rows) in out_b.chunks_mut(QUERY_BLOCK * d).enumerate() {
            tasks.push((bi, blk * QUERY_BLOCK, rows));
        }
    }
    tasks.into_par_iter().for_each_init(
        || (vec![0f32; QUERY_BLOCK * tk], vec![0f32; QUERY_BLOCK]),
        |(scores, inv), (bi, row0, out_rows)| {
            let rows = out_rows.len() / d;
            let scores = &mut scores[..rows * tk];
            let inv = &mut inv[..rows];
            for h in 0..heads {
                let q0 = (bi * tq + row0) * d + h * dh;
                let kv0 = bi * tk * d + h * dh;
                // scores[rows, tk] = scale · Q_h K_hᵀ
                // SAFETY: every pointer/stride pair stays inside its slice: rows
                // `row0..row0 + rows` (`0..tk`) of `dh` columns starting at column `h·dh` of a
                // `[T, d]` block; `scores` is `rows·tk`, `out_rows` is `rows·d`.
                unsafe {
                    gemm::gemm(
                        rows,
                        tk,
                        dh,
                        scores.as_mut_ptr(),
                        1,
                        tk as isize,
                        false,
                        q.as_ptr().add(q0),
                        1,
                        d as isize,
                        k.as_ptr().add(kv0),
                        d as isize,
                        1,
                        0.0,
                        scale,
                        false,
                        false,
                        false,
                        Parallelism::None,
                    );
                }
                if masks.attn.is_some() || padded[bi] {
                    for (i, row) in scores.chunks_exact_mut(tk).enumerate() {
                        block(row, row0 + i, bi, tk, masks);
                    }
                }
                softmax_rows(scores, inv, tk);
                // out[rows, h·dh..] = scores V_h
                unsafe {
                    gemm::gemm(
                        rows,
                        dh,
                        tk,
                        out_rows.as_mut_ptr().add(h * dh),
                        1,
                        d as isize,
                        false,
                        scores.as_ptr(),
                        1,
                        tk as isize,
                        v.as_ptr().add(kv0),
                        1,
                        d as isize,
                        0.0,
                        1.0,
                        false,
                        false,
                        false,
                        Parallelism::None,
                    );
                }
                scale_rows(out_rows, inv, d, h * dh, dh);
            }
        },
    );
    out
}

/// Sets blocked scores of query row `qi` of batch element `bi` to −∞.
fn block(row: &mut [f32], qi: usize, bi: usize, tk: usize, masks: &Masks) {
    if let Some(m) = &masks.attn {
        for (s, &blocked) in row.iter_mut().zip(&m[qi * tk..(qi + 1) * tk]) {
            if blocked {
                *s = f32::NEG_INFINITY;
            }
        }
    }
    if let Some(m) = &masks.key_padding {
        for (s, &blocked) in row.iter_mut().zip(&m[bi * tk..(bi + 1) * tk]) {
            if blocked {
                *s = f32::NEG_INFINITY;
            }
        }
    }
}

widest!(
    /// Softmax of every `tk`-long row of `scores` without the division: the rows become
    /// `exp(x − max)` and `inv` their reciprocal sums, applied to the much shorter output rows
    /// ([`scale_rows`]). A row that is all −∞ gives zeros (as in Burn); a row with a NaN gives
    /// NaN (Burn's zeroes a row whose scores are all NaN, hiding the fault).
    fn softmax_rows(scores: &mut [f32], inv: &mut [f32], tk: usize) => softmax_rows_portable
);

widest!(
    /// Multiplies the `width` columns from `col` of each `stride`-long row of `out` by `inv`.
    fn scale_rows(out: &mut [f32], inv: &[f32], stride: usize, col: usize, width: usize)
        => scale_rows_portable
);

/// Lanes of the partial maxima and sums (so that the reductions vectorise).
const LANES: usize = 16;

#[inline(always)]
fn softmax_rows_portable(scores: &mut [f32], inv: &mut [f32], tk: usize) {
    for (row, inv) in scores.chunks_exact_mut(tk).zip(inv) {
        let max = lane_reduce(row, f32::NEG_INFINITY, f32::max, f32::max);
        if max == f32::NEG_INFINITY {
            // All −∞ (fully blocked), or all NaN/−∞ (f32::max skips NaN).
            let fill = if row.iter().any(|x| x.is_nan()) {
                f32::NAN
            } else {
                0.0
            };
            row.fill(fill);
            *inv = fill;
            continue;
        }
        *inv = 1.0 / exp_sum(row, max);
    }
}

#[inline(always)]
fn scale_rows_portable(out: &mut [f32], inv: &[f32], stride: usize, col: usize, width: usize) {
    for (row, &s) in out.chunks_exact_mut(stride).zip(inv) {
        for x in &mut row[col..col + width] {
            *x *= s;
        }
    }
}

/// Replaces every `x` of `row` by `exp(x − max)` (`max` is the row's maximum, so the argument
/// is ≤ 0) and returns their sum, in one pass (with
/// `LANES` partial sums so that the loop vectorises).
#[inline(always)]
fn exp_sum(row: &mut [f32], max: f32) -> f32 {
    let mut acc = [0f32; LANES];
    let mut chunks = row.chunks_exact_mut(LANES);
    for c in &mut chunks {
        for (a, x) in acc.iter_mut().zip(c) {
            *x = exp_nonpositive(*x - max);
            *a += *x;
        }
    }
    // The tail as one more full vector, padded with −∞ (which gives 0): a scalar loop over
    // the 14 left of a 750-long row took a third of this function's time.
    let rest = chunks.into_remainder();
    let mut pad = [f32::NEG_INFINITY; LANES];
    pad[..rest.len()].copy_from_slice(rest);
    for (a, x) in acc.iter_mut().zip(&mut pad) {
        *x = exp_nonpositive(*x - max);
        *a += *x;
    }
    rest.copy_from_slice(&pad[..rest.len()]);
    acc.into_iter().fold(0.0, |a, b| a + b)
}

/// `fold` over `LANES` independent accumulators, then `merge`d: a reduction LLVM can keep in
/// vector registers.
#[inline(always)]
fn lane_reduce(
    row: &[f32],
    init: f32,
    fold: impl Fn(f32, f32) -> f32,
    merge: impl Fn(f32, f32) -> f32,
) -> f32 {
    let mut acc = [init; LANES];
    let mut chunks = row.chunks_exact(LANES);
    for c in &mut chunks {
        for (a, &x) in acc.iter_mut().zip(c) {
            *a = fold(*a, x);
        }
    }
    // The tail as one more full vector, padded with `init`.
    let rest = chunks.remainder();
    let mut pad = [init; LANES];
    pad[..rest.len()].copy_from_slice(rest);
    for (a, &x) in acc.iter_mut().zip(&pad) {
        *a = fold(*a, x);
    }
    acc.into_iter().fold(init, merge)
}

#[cfg(test)]
mod tests {
    use super::*;
    use burn::tensor::module::attention as burn_attention;
    use burn::tensor::ops::AttentionModuleOptions;
    use burn::tensor::{Device, Distribution};

    fn burn_reference(
        q: Tensor<3>,
        k: Tensor<3>,
        v: Tensor<3>,
        heads: usize,
        mask: Option<Tensor<4, Bool>>,
    ) -> Tensor<3> {
        let split = |x: Tensor<3>| {
            let [b, t, d] = x.dims();
            x.reshape([b, t, heads, d / heads]).swap_dims(1, 2)
        };
        let [b, tq, d] = q.dims();
        let out = burn_attention(
            split(q),
            split(k),
            split(v),
            mask,
            None,
            AttentionModuleOptions::default(),
        );
        out.swap_dims(1, 2).reshape([b, tq, d])
    }

    fn max_abs_diff(a: Tensor<3>, b: Tensor<3>) -> f32 {
        (a - b).abs().max().into_scalar::<f32>()
    }

    /// Seeded normal `q`, `k`, `v` `[b, t, d]` and a causal `[t, t]` mask (true = blocked).
    fn masked_case(
        seed: u64,
        b: usize,
        t: usize,
        d: usize,
    ) -> (Tensor<3>, Tensor<3>, Tensor<3>, Tensor<2, Bool>) {
        let dev = Device::flex();
        dev.seed(seed);
        let n = Distribution::Normal(0.0, 1.0);
        let q = Tensor::<3>::random([b, t, d], n, &dev);
        let k = Tensor::<3>::random([b, t, d], n, &dev);
        let v = Tensor::<3>::random([b, t, d], n, &dev);
        let causal: Vec<bool> = (0..t * t).map(|i| i % t > i / t).collect();
        let causal = Tensor::<2, Bool>::from_data(TensorData::new(causal, [t, t]), &dev);
        (q, k, v, causal)
    }

    /// The `[b, h, t, t]` mask Burn's reference takes: causal or padded key.
    fn both_masks(causal: &Tensor<2, Bool>, pad: &Tensor<2, Bool>, h: usize) -> Tensor<4, Bool> {
        let [b, t] = pad.dims();
        causal
            .clone()
            .reshape([1, 1, t, t])
            .expand([b, h, t, t])
            .bool_or(pad.clone().reshape([b, 1, 1, t]).expand([b, h, t, t]))
    }

    #[test]
    fn inference_tensors_take_the_host_path_and_tracked_ones_do_not() {
        let dev = Device::flex();
        assert!(eligible(&Tensor::<3>::zeros([1, 2, 3], &dev)));
        let tracked = Tensor::<3>::zeros([1, 2, 3], &dev.autodiff()).require_grad();
        assert!(!eligible(&tracked));
    }

    #[test]
    fn matches_burns_attention_without_masks() {
        let dev = Device::flex();
        dev.seed(3);
        let n = Distribution::Normal(0.0, 2.0);
        let q = Tensor::<3>::random([3, 37, 24], n, &dev);
        let k = Tensor::<3>::random([3, 41, 24], n, &dev);
        let v = Tensor::<3>::random([3, 41, 24], n, &dev);
        let want = burn_reference(q.clone(), k.clone(), v.clone(), 4, None);
        let got = attention(q, &HostKv::new(k, v), 4, None, None);
        assert!(max_abs_diff(got, want) < 1e-5);
    }

    #[test]
    fn query_blocks_cover_every_row_with_masks() {
        // Tq spans two whole query blocks and a partial one; the causal mask's row index must
        // follow each block's offset, and the padded batch element must be masked in all.
        let (b, t, d, h) = (2, 2 * QUERY_BLOCK + 7, 16, 2);
        let (q, k, v, causal) = masked_case(5, b, t, d);
        let dev = Device::flex();
        let pad: Vec<bool> = (0..b * t).map(|i| i / t == 0 && i % t >= t - 20).collect();
        let pad = Tensor::<2, Bool>::from_data(TensorData::new(pad, [b, t]), &dev);
        let full = both_masks(&causal, &pad, h);
        let want = burn_reference(q.clone(), k.clone(), v.clone(), h, Some(full));
        let got = attention(q, &HostKv::new(k, v), h, Some(&causal), Some(&pad));
        assert!(max_abs_diff(got, want) < 1e-5);
    }

    #[test]
    fn matches_burns_attention_with_causal_and_padding_masks() {
        let (b, t, d, h) = (2, 9, 12, 3);
        let (q, k, v, causal) = masked_case(4, b, t, d);
        let dev = Device::flex();
        // Batch element 1 pads its last 3 keys; its first query row is then fully blocked.
        let pad: Vec<bool> = (0..b * t).map(|i| i / t == 1 && i % t >= t - 3).collect();
        let pad = Tensor::<2, Bool>::from_data(TensorData::new(pad, [b, t]), &dev);
        let pad_first = {
            let mut p = vec![false; b * t];
            p[t] = true;
            Tensor::<2, Bool>::from_data(TensorData::new(p, [b, t]), &dev)
        };
        for pad in [pad, pad_first] {
            let full = both_masks(&causal, &pad, h);
            let want = burn_reference(q.clone(), k.clone(), v.clone(), h, Some(full));
            let kv = HostKv::new(k.clone(), v.clone());
            let got = attention(q.clone(), &kv, h, Some(&causal), Some(&pad));
            assert!(max_abs_diff(got, want) < 1e-5);
        }
    }

    #[test]
    fn nan_scores_propagate() {
        let dev = Device::flex();
        let mut qv = vec![0.5f32; 2 * 4];
        qv[0] = f32::NAN;
        let q = Tensor::<3>::from_data(TensorData::new(qv, [1, 2, 4]), &dev);
        let k = Tensor::<3>::ones([1, 3, 4], &dev);
        let v = Tensor::<3>::ones([1, 3, 4], &dev);
        let out: Vec<f32> = attention(q, &HostKv::new(k, v), 2, None, None)
            .into_data()
            .try_into_vec()
            .unwrap();
        // Head 0 of query 0 saw the NaN; head 1 and query 1 did not.
        assert!(out[..2].iter().all(|x| x.is_nan()));
        assert!(out[2..].iter().all(|x| (x - 1.0).abs() < 1e-6));
    }
}
