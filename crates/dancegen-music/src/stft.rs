//! Short-time Fourier transform with librosa's framing: `center=True`, zero (`constant`)
//! padding of `n_fft/2` on both sides, periodic window, `1 + len/hop` frames.
//!
//! Spectrograms are stored frame-major (`[frame][bin]`), the order they are produced in, so
//! per-frame consumers (mel, CQT, chroma) read contiguous memory.

use std::sync::Arc;

use rayon::prelude::*;
use realfft::num_complex::Complex32;
use realfft::{RealFftPlanner, RealToComplex};

/// A dense frame-major matrix: `rows` frames of `cols` values.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameMatrix {
    pub rows: usize,
    pub cols: usize,
    pub data: Vec<f32>,
}

impl FrameMatrix {
    pub fn zeros(rows: usize, cols: usize) -> Self {
        Self {
            rows,
            cols,
            data: vec![0.0; rows * cols],
        }
    }
    pub fn row(&self, r: usize) -> &[f32] {
        &self.data[r * self.cols..(r + 1) * self.cols]
    }
    pub fn row_mut(&mut self, r: usize) -> &mut [f32] {
        &mut self.data[r * self.cols..(r + 1) * self.cols]
    }
    pub fn get(&self, r: usize, c: usize) -> f32 {
        self.data[r * self.cols + c]
    }
    /// Fills the matrix in parallel blocks of `block` rows: `f(first_row..end_row, rows)` gets
    /// the block's rows as one slice and may return something per block (in block order).
    /// Every frame-wise analysis (mel, CQT, fused mel + pitch peaks) is built this way, so
    /// each worker reuses its FFT buffers across a block.
    pub fn par_row_blocks<R: Send>(
        &mut self,
        block: usize,
        f: impl Fn(std::ops::Range<usize>, &mut [f32]) -> R + Sync,
    ) -> Vec<R> {
        let (rows, cols) = (self.rows, self.cols);
        if rows == 0 || cols == 0 {
            return Vec::new();
        }
        self.data
            .par_chunks_mut(block.max(1) * cols)
            .enumerate()
            .map(|(bi, data)| {
                let start = bi * block.max(1);
                f(start..(start + block.max(1)).min(rows), data)
            })
            .collect()
    }

    /// The transpose, as a `(cols, rows)` row-major buffer (librosa's `(features, frames)` layout).
    pub fn transposed(&self) -> Vec<f32> {
        let mut out = vec![0.0; self.data.len()];
        for r in 0..self.rows {
            for c in 0..self.cols {
                out[c * self.rows + r] = self.data[r * self.cols + c];
            }
        }
        out
    }
}

/// `|c|` rounded once from float64, which equals numpy's complex64 `abs` (a correctly rounded
/// hypot) and is several times faster than libm's `hypotf` behind `Complex::norm`.
#[inline]
pub fn magnitude_of(c: Complex32) -> f32 {
    let (re, im) = (c.re as f64, c.im as f64);
    (re * re + im * im).sqrt() as f32
}

/// `|c|**2` as librosa computes a power spectrogram: the float32 magnitude, squared in float32.
#[inline]
pub fn power_of(c: Complex32) -> f32 {
    let m = magnitude_of(c);
    m * m
}

/// Number of frames librosa's centred STFT produces for `len` samples.
pub fn n_frames(len: usize, hop: usize) -> usize {
    1 + len / hop
}

/// Periodic Hann window of length `n` (`scipy.signal.get_window('hann', n, fftbins=True)`).
pub fn hann_periodic(n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| 0.5 - 0.5 * (2.0 * std::f64::consts::PI * i as f64 / n as f64).cos())
        .collect()
}

/// A planned STFT: window, FFT size and hop.
#[derive(Clone)]
pub struct Stft {
    n_fft: usize,
    hop: usize,
    window: Vec<f32>,
    fft: Arc<dyn RealToComplex<f32>>,
}

impl Stft {
    /// Hann-windowed STFT (librosa's default window).
    pub fn hann(n_fft: usize, hop: usize) -> Self {
        let w = hann_periodic(n_fft).into_iter().map(|v| v as f32).collect();
        Self::with_window(n_fft, hop, w)
    }

    /// Rectangular window (`window='ones'`), as the CQT's filter-bank transform uses.
    pub fn rectangular(n_fft: usize, hop: usize) -> Self {
        Self::with_window(n_fft, hop, vec![1.0; n_fft])
    }

    pub fn with_window(n_fft: usize, hop: usize, window: Vec<f32>) -> Self {
        assert_eq!(window.len(), n_fft, "window length must equal n_fft");
        assert!(hop > 0 && n_fft > 0);
        let fft = RealFftPlanner::<f32>::new().plan_fft_forward(n_fft);
        Self {
            n_fft,
            hop,
            window,
            fft,
        }
    }

    pub fn n_fft(&self) -> usize {
        self.n_fft
    }
    pub fn hop(&self) -> usize {
        self.hop
    }
    pub fn n_bins(&self) -> usize {
        self.n_fft / 2 + 1
    }

    /// Copies centred, zero-padded, windowed frame `t` of `y` into `buf` (length `n_fft`).
    /// Interior frames are one slice copy and a vectorised window multiply; only the frames
    /// that overhang the signal take the per-sample path (the CQT runs seven STFTs per output
    /// frame, so this matters).
    fn fill_frame(&self, y: &[f32], t: usize, buf: &mut [f32]) {
        let start = (t * self.hop) as isize - (self.n_fft / 2) as isize;
        if start >= 0 && start as usize + self.n_fft <= y.len() {
            let src = &y[start as usize..start as usize + self.n_fft];
            for ((b, &v), &w) in buf.iter_mut().zip(src).zip(&self.window) {
                *b = v * w;
            }
            return;
        }
        for (i, (b, w)) in buf.iter_mut().zip(&self.window).enumerate() {
            let idx = start + i as isize;
            *b = if idx >= 0 && (idx as usize) < y.len() {
                y[idx as usize] * w
            } else {
                0.0
            };
        }
    }

    /// Calls `f(t, spectrum)` for frames `range` of `y`, in order, reusing buffers.
    pub fn for_each_frame(
        &self,
        y: &[f32],
        range: std::ops::Range<usize>,
        mut f: impl FnMut(usize, &[Complex32]),
    ) {
        let mut input = self.fft.make_input_vec();
        let mut output = self.fft.make_output_vec();
        let mut scratch = self.fft.make_scratch_vec();
        for t in range {
            self.fill_frame(y, t, &mut input);
            self.fft
                .process_with_scratch(&mut input, &mut output, &mut scratch)
                .expect("buffer sizes come from the plan");
            f(t, &output);
        }
    }

    /// Computes one output row per frame in parallel: `f(spectrum, row, scratch)` fills a row of
    /// `cols`; `scratch` is a buffer reused across the frames of one worker.
    ///
    /// This is how every spectral feature is built without keeping the complex STFT around.
    pub fn map_frames(
        &self,
        y: &[f32],
        cols: usize,
        f: impl Fn(&[Complex32], &mut [f32], &mut Vec<f32>) + Sync,
    ) -> FrameMatrix {
        let mut out = FrameMatrix::zeros(n_frames(y.len(), self.hop), cols);
        out.par_row_blocks(256, |frames, rows| {
            let start = frames.start;
            let mut scratch = Vec::new();
            self.for_each_frame(y, frames, |ti, spec| {
                let r = ti - start;
                f(spec, &mut rows[r * cols..(r + 1) * cols], &mut scratch);
            });
        });
        out
    }

    /// Magnitude spectrogram `|X|` (frames × bins).
    pub fn magnitude(&self, y: &[f32]) -> FrameMatrix {
        self.map_frames(y, self.n_bins(), |spec, row, _| {
            for (o, &c) in row.iter_mut().zip(spec) {
                *o = magnitude_of(c);
            }
        })
    }

    /// Power spectrogram `|X|^2` (frames × bins).
    pub fn power(&self, y: &[f32]) -> FrameMatrix {
        self.map_frames(y, self.n_bins(), |spec, row, _| {
            for (o, &c) in row.iter_mut().zip(spec) {
                *o = power_of(c);
            }
        })
    }

    /// Complex spectrogram, frames × bins.
    pub fn complex(&self, y: &[f32]) -> Vec<Vec<Complex32>> {
        let t = n_frames(y.len(), self.hop);
        let mut out = Vec::with_capacity(t);
        self.for_each_frame(y, 0..t, |_, s| out.push(s.to_vec()));
        out
    }
}
