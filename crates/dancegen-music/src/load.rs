//! `librosa.load(path, sr=SR)`: decode, average to mono, resample with soxr HQ, fix the length.

use std::path::Path;

use crate::decode::MonoDecoder;
use crate::error::{MusicError, Result};
use crate::resample::{Resampler, resampled_len};

/// Mono float32 audio at a known sample rate.
#[derive(Clone, Debug)]
pub struct Audio {
    pub samples: Vec<f32>,
    pub sample_rate: u32,
    /// Sample rate of the file before resampling.
    pub native_rate: u32,
}

impl Audio {
    pub fn duration_secs(&self) -> f64 {
        self.samples.len() as f64 / self.sample_rate as f64
    }
}

/// Loads `path` as librosa 0.11 does with `librosa.load(path, sr=target_sr)`.
///
/// Decoding and resampling are streamed block by block, so peak memory is the output signal plus
/// a few decoder blocks, whatever the length and channel count of the file. A file already at
/// `target_sr` is returned untouched, as librosa does.
pub fn load(path: &Path, target_sr: u32) -> Result<Audio> {
    load_with_progress(path, target_sr, |_| {})
}

/// [`load`], calling `progress(fraction)` now and then (for a progress bar on long files).
pub fn load_with_progress(
    path: &Path,
    target_sr: u32,
    mut progress: impl FnMut(f64),
) -> Result<Audio> {
    if target_sr == 0 {
        return Err(MusicError::InvalidParameter("target sample rate 0".into()));
    }
    let mut dec = MonoDecoder::open(path)?;
    let mut block = Vec::with_capacity(1 << 16);
    let mut out = Vec::new();
    let mut n_in = 0usize;
    let mut resampler: Option<Resampler> = None;
    let mut native = 0u32;
    let mut blocks = 0usize;
    loop {
        block.clear();
        if !dec.next_block(&mut block)? {
            break;
        }
        if native == 0 {
            native = dec.sample_rate();
            if native == 0 {
                return Err(MusicError::BadSampleRate {
                    path: path.to_path_buf(),
                    rate: 0,
                });
            }
            if native != target_sr {
                resampler = Some(Resampler::new_hq(native as f64, target_sr as f64)?);
            }
        }
        n_in += block.len();
        match resampler.as_mut() {
            Some(r) => r.process(&block, &mut out)?,
            None => out.extend_from_slice(&block),
        }
        blocks += 1;
        if blocks % 256 == 0 {
            progress(dec.progress());
        }
    }
    if n_in == 0 {
        return Err(MusicError::NoSamples {
            path: path.to_path_buf(),
        });
    }
    if let Some(r) = resampler.as_mut() {
        r.finish(&mut out)?;
        out.resize(resampled_len(n_in, native as f64, target_sr as f64), 0.0);
    }
    out.shrink_to_fit();
    progress(1.0);
    Ok(Audio {
        samples: out,
        sample_rate: target_sr,
        native_rate: native,
    })
}
