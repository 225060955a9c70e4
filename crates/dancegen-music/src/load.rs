//! `librosa.load(path, sr=SR)`: decode, average to mono, resample with soxr HQ, fix the length.

use std::path::Path;

use rayon::prelude::*;

use crate::decode::{AudioSource, MonoDecoder};
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
    let mut v = load_many(&AudioSource::from(path), &[target_sr], |_| {})?;
    Ok(v.pop().expect("one output per requested rate"))
}

/// Loads `path` at several sample rates in one decoding pass (e.g. the feature rate and the
/// 22050 Hz rate of EDGE's tempo prior). `progress(fraction)` is called now and then.
/// `target_sr = 0` keeps the native rate (`librosa.load(sr=None)`).
///
/// Decoding runs on its own thread and hands ~1 s chunks to the resamplers, which run in
/// parallel, so a compressed song's decoding overlaps with its resampling.
pub fn load_many(
    source: &AudioSource,
    target_srs: &[u32],
    mut progress: impl FnMut(f64),
) -> Result<Vec<Audio>> {
    let path = source.label().to_path_buf();
    let mut dec = MonoDecoder::open_source(source)?;
    // The first block tells the native rate when the container does not.
    let mut first = Vec::with_capacity(1 << 16);
    if !dec.next_block(&mut first)? {
        return Err(MusicError::NoSamples { path });
    }
    let native = dec.sample_rate();
    if native == 0 {
        return Err(MusicError::BadSampleRate { path, rate: 0 });
    }
    let mut outs: Vec<Vec<f32>> = vec![Vec::new(); target_srs.len()];
    let mut resamplers: Vec<Option<Resampler>> = Vec::with_capacity(target_srs.len());
    for (out, &sr) in outs.iter_mut().zip(target_srs) {
        let rate = if sr == 0 { native } else { sr };
        // Reserve the final size up front when the container declares its length, so a long
        // song never pays for a doubling reallocation (2x peak memory).
        if let Some(total) = dec.total_frames() {
            out.reserve_exact(resampled_len(total as usize, native as f64, rate as f64) + 4096);
        }
        resamplers.push(if rate != native {
            Some(Resampler::new_hq(native as f64, rate as f64)?)
        } else {
            None
        });
    }
    // About one second of audio per chunk: large enough to amortise the thread hand-off,
    // small enough that the queue holds only a few MB.
    let chunk_len = (native as usize).max(4096);
    let mut n_in = 0usize;
    std::thread::scope(|scope| -> Result<()> {
        let (tx, rx) = std::sync::mpsc::sync_channel::<Result<(Vec<f32>, f64)>>(4);
        scope.spawn(move || {
            let mut chunk = first;
            loop {
                match dec.next_block(&mut chunk) {
                    Ok(true) if chunk.len() < chunk_len => continue,
                    Ok(more) => {
                        let full =
                            std::mem::replace(&mut chunk, Vec::with_capacity(chunk_len + 8192));
                        if !full.is_empty() && tx.send(Ok((full, dec.progress()))).is_err() {
                            return;
                        }
                        if !more {
                            return;
                        }
                    }
                    Err(e) => {
                        let _ = tx.send(Err(e));
                        return;
                    }
                }
            }
        });
        for msg in rx {
            let (chunk, frac) = msg?;
            n_in += chunk.len();
            let jobs: Vec<(&mut Option<Resampler>, &mut Vec<f32>)> =
                resamplers.iter_mut().zip(outs.iter_mut()).collect();
            jobs.into_par_iter().try_for_each(|(r, out)| match r {
                Some(r) => r.process(&chunk, out),
                None => {
                    out.extend_from_slice(&chunk);
                    Ok(())
                }
            })?;
            progress(frac);
        }
        Ok(())
    })?;
    if n_in == 0 {
        return Err(MusicError::NoSamples { path });
    }
    let mut result = Vec::with_capacity(target_srs.len());
    for ((r, mut out), &sr) in resamplers.into_iter().zip(outs).zip(target_srs) {
        let sample_rate = if sr == 0 { native } else { sr };
        if let Some(mut r) = r {
            r.finish(&mut out)?;
            out.resize(resampled_len(n_in, native as f64, sr as f64), 0.0);
        }
        // Give back a large over-reservation only (a shrink copies the buffer).
        if out.capacity() > out.len() + out.len() / 4 + 65536 {
            out.shrink_to_fit();
        }
        result.push(Audio {
            samples: out,
            sample_rate,
            native_rate: native,
        });
    }
    progress(1.0);
    Ok(result)
}
