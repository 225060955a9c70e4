//! Sample-rate conversion with libsoxr's "HQ" recipe — what librosa 0.11 uses by default
//! (`res_type='soxr_hq'`, via python-soxr). The fixtures show that any other high-quality
//! resampler moves MFCCs by several units, because the top mel bands sit in the transition band
//! (`shared/fixtures/music/README.md` §5), so matching librosa means running the same algorithm.
//!
//! libsoxr (LGPL-2.1) is linked dynamically from the system library (Debian `libsoxr0`).

use std::os::raw::c_void;
use std::ptr;

use libsoxr_sys as sys;

use crate::error::{MusicError, Result};

/// A streaming single-channel float32 resampler (libsoxr HQ, linear phase, delay-compensated).
///
/// Feeding the input in blocks gives the same output as a one-shot call, so long files are
/// resampled while they are decoded.
pub struct Resampler {
    soxr: sys::soxr_t,
    ratio: f64,
    out_buf: Vec<f32>,
}

// libsoxr's handle is a plain heap object with no thread affinity.
unsafe impl Send for Resampler {}

impl Resampler {
    /// A resampler from `in_rate` to `out_rate` Hz with the HQ (20-bit) recipe.
    pub fn new_hq(in_rate: f64, out_rate: f64) -> Result<Self> {
        if !(in_rate > 0.0 && out_rate > 0.0 && in_rate.is_finite() && out_rate.is_finite()) {
            return Err(MusicError::InvalidParameter(format!(
                "sample rates must be positive, got {in_rate} -> {out_rate}"
            )));
        }
        let mut err: sys::soxr_error_t = ptr::null();
        // SAFETY: plain FFI constructors of value types; soxr_create copies the specs.
        let soxr = unsafe {
            let io = sys::soxr_io_spec(sys::SOXR_FLOAT32_I, sys::SOXR_FLOAT32_I);
            let q = sys::soxr_quality_spec(sys::SOXR_HQ as _, 0);
            // One thread: libsoxr's OpenMP split only helps multi-channel audio.
            let rt = sys::soxr_runtime_spec(1);
            sys::soxr_create(in_rate, out_rate, 1, &mut err, &io, &q, &rt)
        };
        if !err.is_null() || soxr.is_null() {
            return Err(MusicError::Resample(soxr_error_string(err)));
        }
        Ok(Self {
            soxr,
            ratio: out_rate / in_rate,
            out_buf: Vec::new(),
        })
    }

    /// Resamples `input` (a block of the stream) and appends the output produced so far to `out`.
    pub fn process(&mut self, input: &[f32], out: &mut Vec<f32>) -> Result<()> {
        let mut consumed = 0usize;
        while consumed < input.len() {
            let rest = &input[consumed..];
            let idone = self.run(rest.as_ptr().cast(), rest.len(), out)?;
            consumed += idone;
        }
        Ok(())
    }

    /// Flushes the resampler's delay line at the end of the stream.
    pub fn finish(&mut self, out: &mut Vec<f32>) -> Result<()> {
        loop {
            let before = out.len();
            // A null input pointer tells libsoxr the stream has ended.
            self.run(ptr::null(), 0, out)?;
            if out.len() == before {
                return Ok(());
            }
        }
    }

    fn run(&mut self, input: *const c_void, ilen: usize, out: &mut Vec<f32>) -> Result<usize> {
        let olen = ((ilen as f64) * self.ratio).ceil() as usize + 1024;
        self.out_buf.resize(olen, 0.0);
        let mut idone = 0usize;
        let mut odone = 0usize;
        // SAFETY: `input` points to `ilen` f32 (or is null at end of stream); out_buf holds `olen`.
        let err = unsafe {
            sys::soxr_process(
                self.soxr,
                input,
                ilen,
                &mut idone,
                self.out_buf.as_mut_ptr().cast(),
                olen,
                &mut odone,
            )
        };
        if !err.is_null() {
            return Err(MusicError::Resample(soxr_error_string(err)));
        }
        out.extend_from_slice(&self.out_buf[..odone]);
        Ok(idone)
    }
}

impl Drop for Resampler {
    fn drop(&mut self) {
        // SAFETY: created by soxr_create, deleted once.
        unsafe { sys::soxr_delete(self.soxr) }
    }
}

fn soxr_error_string(err: sys::soxr_error_t) -> String {
    if err.is_null() {
        return "unknown libsoxr error".into();
    }
    // SAFETY: libsoxr error strings are static NUL-terminated C strings.
    unsafe { std::ffi::CStr::from_ptr(err) }
        .to_string_lossy()
        .into_owned()
}

/// Output length librosa gives a resampled signal: `ceil(n * out_rate / in_rate)`.
pub fn resampled_len(n: usize, in_rate: f64, out_rate: f64) -> usize {
    (n as f64 * out_rate / in_rate).ceil() as usize
}

/// `librosa.resample(y, orig_sr, target_sr, res_type='soxr_hq', fix=True, scale=...)`.
///
/// `scale` divides by `sqrt(target/orig)`, as the CQT's octave-halving does to keep energy.
pub fn resample_hq(y: &[f32], in_rate: f64, out_rate: f64, scale: bool) -> Result<Vec<f32>> {
    let n_out = resampled_len(y.len(), in_rate, out_rate);
    if in_rate == out_rate {
        return Ok(y.to_vec());
    }
    let mut r = Resampler::new_hq(in_rate, out_rate)?;
    let mut out = Vec::with_capacity(n_out + 64);
    r.process(y, &mut out)?;
    r.finish(&mut out)?;
    out.resize(n_out, 0.0);
    if scale {
        let s = (out_rate / in_rate).sqrt() as f32;
        for v in &mut out {
            *v /= s;
        }
    }
    Ok(out)
}
