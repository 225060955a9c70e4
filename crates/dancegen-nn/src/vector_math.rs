//! Branch-free `exp` and GELU that LLVM vectorises, and the inference GELU built on them.
//!
//! Why: burn-flex 0.22 evaluates `exp` and `erf` one element at a time through libm. In Lodge++
//! sampling (`perf record` of `dancegen generate`, 1024 frames) the softmax's `exp` took a third
//! of the run and GELU's `erf` another 9 %. These versions are plain Rust loops without branches
//! or calls, compiled for AVX-512 or AVX2 + FMA and picked at run time (`widest!`).

use burn::tensor::Tensor;
use rayon::prelude::*;

/// Defines `fn $name(args)` that calls the `#[inline(always)]` function `$body` from a copy
/// compiled for AVX-512 or for AVX2 + FMA when the CPU has them (checked at run time), so that
/// the loops inlined from `$body` are vectorised for the widest instruction set available.
macro_rules! widest {
    ($(#[$meta:meta])* $vis:vis fn $name:ident($($arg:ident: $ty:ty),*) => $body:path) => {
        $(#[$meta])*
        $vis fn $name($($arg: $ty),*) {
            #[cfg(target_arch = "x86_64")]
            {
                #[target_feature(enable = "avx512f")]
                fn avx512($($arg: $ty),*) {
                    $body($($arg),*)
                }
                #[target_feature(enable = "avx2,fma")]
                fn avx2($($arg: $ty),*) {
                    $body($($arg),*)
                }
                if std::arch::is_x86_feature_detected!("avx512f") {
                    // SAFETY: the CPU supports the features the function is compiled for.
                    return unsafe { avx512($($arg),*) };
                }
                if std::arch::is_x86_feature_detected!("avx2")
                    && std::arch::is_x86_feature_detected!("fma")
                {
                    // SAFETY: as above.
                    return unsafe { avx2($($arg),*) };
                }
            }
            $body($($arg),*)
        }
    };
}
pub(crate) use widest;

/// Below this `eˣ` rounds to 0 in `f32` (half the smallest subnormal is `e^−103.97`).
const EXP_LOW: f32 = -104.0;
/// Above this `eˣ` overflows `f32`: the result is +∞.
const EXP_MAX: f32 = 88.722_84;
/// `ln 2` split in a part exact in `f32` and the rest (Cephes `expf`: C1, C2).
const LN2_HI: f32 = 0.693_359_4;
const LN2_LO: f32 = -2.121_944_4e-4;
/// `1.5 · 2²³`: adding it to a float in `[−2²², 2²²]` rounds it to an integer held in the low
/// mantissa bits (round-to-nearest without a float → int conversion, which would not vectorise).
const ROUND_MAGIC: f32 = 12_582_912.0;

/// `eˣ = e · 2ⁿ` for `x` already clamped into `[EXP_LOW, EXP_MAX]`: Cephes' range reduction
/// and degree-7 polynomial, shared by [`exp`] and [`exp_nonpositive`].
#[inline(always)]
fn exp_reduced(xc: f32) -> (f32, i32) {
    // `mul_add`: one FMA instruction in the AVX2 + FMA and AVX-512 builds of `widest!` (plain
    // `a * b + c` is not fused, and was two instructions per term); only an x86 CPU without
    // FMA (before 2013) would fall back to libm's `fmaf`.
    let t = xc.mul_add(std::f32::consts::LOG2_E, ROUND_MAGIC);
    let n = t - ROUND_MAGIC;
    // n ∈ [−150, 128]: its two's complement sits in the low bits of t's mantissa.
    let n_int = t.to_bits().wrapping_sub(ROUND_MAGIC.to_bits()) as i32;
    let r = (-n).mul_add(LN2_LO, (-n).mul_add(LN2_HI, xc));
    let r2 = r * r;
    let p: f32 = 1.987_569_1e-4;
    let p = p.mul_add(r, 1.398_199_9e-3);
    let p = p.mul_add(r, 8.333_452e-3);
    let p = p.mul_add(r, 4.166_579_6e-2);
    let p = p.mul_add(r, 1.666_666_5e-1);
    let p = p.mul_add(r, 0.5);
    (p.mul_add(r2, r) + 1.0, n_int)
}

/// Below this `eˣ` is under `f32`'s smallest normal, and [`exp_nonpositive`] gives 0.
const EXP_NORMAL_LOW: f32 = -87.33;

/// `eˣ` for `x ≤ 0` (a softmax's `x − max`), with fewer steps than [`exp`]: no overflow to
/// handle, and results that would be subnormal (`x < −87.33`, under 1.2e-38) flushed to 0, so
/// `2ⁿ` is one power of two. −∞ gives 0, NaN stays NaN; positive `x` is outside its contract.
#[inline(always)]
pub fn exp_nonpositive(x: f32) -> f32 {
    // A comparison, not `max`, so that NaN passes through.
    let low = x < EXP_NORMAL_LOW;
    let xc = if low { EXP_NORMAL_LOW } else { x };
    let (e, n_int) = exp_reduced(xc);
    // n ∈ [−126, 0]: a normal power of two.
    let v = e * f32::from_bits(((n_int + 127) as u32) << 23);
    if low { 0.0 } else { v }
}

/// `eˣ`. Cephes `expf` (S. Moshier): `x = n ln2 + r`, `|r| ≤ ln2 / 2`, `eʳ` by its degree-7
/// minimax polynomial, `2ⁿ` as two powers of two built from exponent bits (so that subnormal
/// results and `n = 128` need no special case); relative error ≤ 2e-7 in the normal range.
/// −∞ gives 0, +∞ and overflow give +∞, NaN stays NaN.
#[inline(always)]
pub fn exp(x: f32) -> f32 {
    let xc = x.clamp(EXP_LOW, EXP_MAX);
    let (e, n_int) = exp_reduced(xc);
    let half = n_int >> 1;
    let pow2 = |k: i32| f32::from_bits(((k + 127) as u32) << 23);
    // x − x is 0 for finite x and NaN for NaN (and ±∞, handled by the selects).
    #[allow(clippy::eq_op)]
    let nan_if_nan = x - x;
    let v = e * pow2(half) * pow2(n_int - half) + nan_if_nan;
    let v = if x > EXP_MAX { f32::INFINITY } else { v };
    if x < EXP_LOW { 0.0 } else { v }
}

/// `erfc(z)` for `z ≥ 0`: Numerical Recipes' Chebyshev fit `t·exp(−z² + P(t))`,
/// `t = 1 / (1 + z/2)`, fractional error < 1.2e-7 (in exact arithmetic).
#[inline(always)]
#[allow(clippy::excessive_precision)] // the coefficients as published
fn erfc_nonneg(z: f32) -> f32 {
    let t = 1.0 / (1.0 + 0.5 * z);
    let p: f32 = 0.170_872_77;
    let p = p.mul_add(t, -0.822_152_23);
    let p = p.mul_add(t, 1.488_515_87);
    let p = p.mul_add(t, -1.135_203_98);
    let p = p.mul_add(t, 0.278_868_07);
    let p = p.mul_add(t, -0.186_288_06);
    let p = p.mul_add(t, 0.096_784_18);
    let p = p.mul_add(t, 0.374_091_96);
    let p = p.mul_add(t, 1.000_023_68);
    let p = p.mul_add(t, -1.265_512_23);
    t * exp((-z).mul_add(z, p))
}

/// Exact (erf) GELU, `x Φ(x) = ½ x erfc(−x/√2)`; for `x ≥ 0` through `2 − erfc(|x|/√2)`.
#[inline(always)]
pub fn gelu(x: f32) -> f32 {
    let c = erfc_nonneg(x.abs() * std::f32::consts::FRAC_1_SQRT_2);
    let erfc_neg = if x >= 0.0 { 2.0 - c } else { c };
    0.5 * x * erfc_neg
}

/// Elements per parallel task of the `*_tensor` activations.
const CHUNK: usize = 1 << 14;

/// `f` over the elements of `x` in parallel chunks, in its own buffer, when `x` is an inference
/// `f32` tensor on the flex backend; else `fallback` (Burn's op). The data is viewed as `f32`
/// where it lies: a `Vec<f32>` would copy Burn's byte buffer into a new allocation, which
/// profiling showed as page faults plus a memmove per call. A buffer something else still
/// holds is copied by `into_data` first, so the other holder never sees the change.
fn map_in_place<const D: usize>(
    x: Tensor<D>,
    f: fn(&mut [f32]),
    fallback: fn(Tensor<D>) -> Tensor<D>,
) -> Tensor<D> {
    if !crate::host_view::eligible(&x) {
        return fallback(x);
    }
    let device = x.device();
    let mut data = x.into_data();
    data.as_mut_slice::<f32>()
        .expect("eligible tensors are f32")
        .par_chunks_mut(CHUNK)
        .for_each(f);
    Tensor::from_data(data, &device)
}

/// Mish, `x·tanh(softplus(x))`, written with one exp: `tanh(ln(1 + e)) = n / (n + 2)` for
/// `n = e (e + 2)`, `e = eˣ`; `x` itself above 20, where that ratio is 1 in f32. Branch-free, so
/// the loop over a slice vectorises (libm's `log1pf`, `expm1f` and `tanhf`, which Burn's mish
/// calls per element, were a quarter of the duet sampler's time).
#[inline(always)]
pub fn mish(x: f32) -> f32 {
    let e = exp(x.min(20.0));
    let n = e * (e + 2.0);
    let r = x * n / (n + 2.0);
    if x > 20.0 { x } else { r }
}

/// The logistic function `1 / (1 + e⁻ˣ)` (−∞ → 0, +∞ → 1, NaN stays NaN).
#[inline(always)]
pub fn sigmoid(x: f32) -> f32 {
    1.0 / (1.0 + exp(-x))
}

/// For the scalar activation `$scalar`: `$slice`, the activation of every element of a slice in
/// place (a plain loop over `$scalar`, vectorised by [`widest!`] through `$portable`), and
/// `$tensor`, the activation of a tensor on the host when it is an inference `f32` tensor
/// ([`crate::host_view::eligible`]), else Burn's `$fallback` (autodiff, other backends).
macro_rules! elementwise {
    ($scalar:ident => $slice:ident, $portable:ident, $(#[$meta:meta])* $tensor:ident, $fallback:path) => {
        widest!(
            /// The activation of every element, in place.
            fn $slice(xs: &mut [f32]) => $portable
        );

        #[inline(always)]
        fn $portable(xs: &mut [f32]) {
            for v in xs {
                *v = $scalar(*v);
            }
        }

        $(#[$meta])*
        pub fn $tensor<const D: usize>(x: Tensor<D>) -> Tensor<D> {
            map_in_place(x, $slice, $fallback)
        }
    };
}

elementwise!(gelu => gelu_slice, gelu_slice_portable,
    /// Exact GELU ([`gelu`]) of a tensor.
    gelu_tensor, burn::tensor::activation::gelu);
elementwise!(mish => mish_slice, mish_slice_portable,
    /// Mish ([`mish`]) of a tensor.
    mish_tensor, burn::tensor::activation::mish);
elementwise!(sigmoid => sigmoid_slice, sigmoid_slice_portable,
    /// Sigmoid ([`sigmoid`]) of a tensor: vectorised and on the rayon workers where Burn's op
    /// calls libm's `expf` per element on the calling thread (3 % of group sampling's samples,
    /// with both workers idle).
    sigmoid_tensor, burn::tensor::activation::sigmoid);

#[cfg(test)]
mod tests {
    use super::*;
    use burn::tensor::{Device, TensorData};

    #[test]
    fn exp_matches_libm_over_the_whole_range() {
        let mut worst = 0f64;
        let mut x = -87.0f32;
        while x <= 88.5 {
            let got = f64::from(exp(x));
            let want = f64::from(x).exp();
            worst = worst.max(((got - want) / want).abs());
            x += 1.3e-3;
        }
        assert!(worst < 2.5e-7, "worst relative error {worst}");
        assert_eq!(exp(f32::NEG_INFINITY), 0.0);
        assert_eq!(exp(-110.0), 0.0);
        // Subnormal results: within the subnormal spacing.
        assert!((f64::from(exp(-100.0)) - (-100f64).exp()).abs() < 1.5e-45);
        assert_eq!(exp(100.0), f32::INFINITY);
        assert_eq!(exp(f32::INFINITY), f32::INFINITY);
        assert!(exp(f32::NAN).is_nan());
        assert_eq!(exp(0.0), 1.0);
        assert!((f64::from(exp(-87.3)) / f64::from(-87.3f32).exp() - 1.0).abs() < 1e-6);
    }

    #[test]
    fn mish_matches_burns_mish() {
        let xs: Vec<f32> = (0..60_001).map(|i| -30.0 + i as f32 * 1e-3).collect();
        let dev = Device::flex();
        let t = Tensor::<1>::from_data(TensorData::new(xs.clone(), [xs.len()]), &dev);
        let want: Vec<f32> = burn::tensor::activation::mish(t.clone())
            .into_data()
            .try_into_vec()
            .unwrap();
        let got: Vec<f32> = mish_tensor(t).into_data().try_into_vec().unwrap();
        for ((x, g), w) in xs.iter().zip(&got).zip(&want) {
            // A few f32 roundings of exp (≤ 2.5e-7 relative) and the ratio, times |x|.
            let tol = 1e-6 * (1.0 + x.abs());
            assert!((g - w).abs() <= tol, "mish({x}) = {g}, Burn {w}");
        }
        assert!(mish(f32::NAN).is_nan());
        assert_eq!(mish(f32::INFINITY), f32::INFINITY);
        assert_eq!(mish(1e30), 1e30);
        assert!(mish(-1e3).abs() < 1e-30);
    }

    #[test]
    fn exp_nonpositive_matches_libm() {
        let mut worst = 0f64;
        let mut x = -87.3f32;
        while x <= 0.0 {
            let got = f64::from(exp_nonpositive(x));
            let want = f64::from(x).exp();
            worst = worst.max(((got - want) / want).abs());
            x += 1.1e-3;
        }
        assert!(worst < 2.5e-7, "worst relative error {worst}");
        assert_eq!(exp_nonpositive(0.0), 1.0);
        assert_eq!(exp_nonpositive(-0.0), 1.0);
        assert_eq!(exp_nonpositive(-88.0), 0.0);
        assert_eq!(exp_nonpositive(f32::NEG_INFINITY), 0.0);
        assert!(exp_nonpositive(f32::NAN).is_nan());
    }

    #[test]
    fn gelu_matches_burns_exact_gelu() {
        let xs: Vec<f32> = (0..40_001).map(|i| -20.0 + i as f32 * 1e-3).collect();
        let dev = Device::flex();
        let t = Tensor::<1>::from_data(TensorData::new(xs.clone(), [xs.len()]), &dev);
        let want: Vec<f32> = burn::tensor::activation::gelu(t.clone())
            .into_data()
            .try_into_vec()
            .unwrap();
        let got: Vec<f32> = gelu_tensor(t).into_data().try_into_vec().unwrap();
        for ((x, g), w) in xs.iter().zip(&got).zip(&want) {
            // NR's fit is good to 1.2e-7 of erfc (≤ 2), evaluated in f32 (a few ulp of the
            // polynomial and exp), times |x|/2: 1e-6 per unit of |x| covers both.
            let tol = 1e-6 * (1.0 + x.abs());
            assert!((g - w).abs() <= tol, "gelu({x}) = {g}, Burn {w}");
        }
        assert!(gelu(f32::NAN).is_nan());
        assert_eq!(gelu(-1e30), 0.0);
        assert_eq!(gelu(f32::INFINITY), f32::INFINITY);
    }

    #[test]
    fn sigmoid_matches_burns() {
        let xs: Vec<f32> = (0..20_001).map(|i| -100.0 + i as f32 * 1e-2).collect();
        let dev = Device::flex();
        let t = Tensor::<1>::from_data(TensorData::new(xs.clone(), [xs.len()]), &dev);
        let want: Vec<f32> = burn::tensor::activation::sigmoid(t.clone())
            .into_data()
            .try_into_vec()
            .unwrap();
        let got: Vec<f32> = sigmoid_tensor(t).into_data().try_into_vec().unwrap();
        for ((x, g), w) in xs.iter().zip(&got).zip(&want) {
            assert!(
                (g - w).abs() <= 1e-6 * (1.0 + w.abs()),
                "sigmoid({x}) = {g}, Burn {w}"
            );
        }
        assert_eq!(sigmoid(f32::NEG_INFINITY), 0.0);
        assert_eq!(sigmoid(f32::INFINITY), 1.0);
        assert!(sigmoid(f32::NAN).is_nan());
    }

    #[test]
    fn in_place_map_leaves_a_shared_tensor_alone() {
        // The host ops write into the tensor's buffer; a clone that still holds it must see
        // the old values (Burn copies a shared buffer on `into_data`).
        let dev = Device::flex();
        let xs = vec![-1.0f32, 0.0, 2.0, 3.5];
        let t = Tensor::<1>::from_data(TensorData::new(xs.clone(), [4]), &dev);
        let kept = t.clone();
        let got: Vec<f32> = gelu_tensor(t).into_data().try_into_vec().unwrap();
        let kept: Vec<f32> = kept.into_data().try_into_vec().unwrap();
        assert_eq!(kept, xs);
        assert_eq!(got[2], gelu(2.0));
    }
}
