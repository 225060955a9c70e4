//! Music → holistic dance of any length.
//!
//! The song's tokens are made window by window (`[generator] window_tokens` per part). Each
//! window after the first starts `[sampling] overlap_tokens` tokens (per part) before the end of
//! what is made, and those tokens are given to the masked transformer as known (inpainting), so
//! the window continues the dance instead of starting a new one; the last window is moved back to
//! end at the song's end (its known part is then longer). SoulNet has no long form; this is the
//! masked-transformer inpainting issue 19 asks for. The residual levels of the known positions
//! are kept from the window that made them. All tokens are decoded at once by the part
//! autoencoder's conv decoder, which smooths across the joins.

use dancegen_nn::burn::tensor::{Device, Int, Tensor, TensorData};
use dancegen_nn::progress::{Cancelled, StepHook, step};

use crate::bundle::HolisticModel;
use crate::config::SamplingDefaults;
use crate::generator::{Condition, music_tokens};
use crate::layout::{MUSIC_DIMS, TOTAL_DIMS};

/// The part name progress is reported under (one unit per window).
pub const TOKENS: &str = "tokens";

/// Settings of one generation.
#[derive(Clone, Debug)]
pub struct GenerateOptions {
    pub sampling: SamplingDefaults,
    pub seed: u64,
}

impl GenerateOptions {
    /// The model's defaults.
    pub fn defaults(model: &HolisticModel, seed: u64) -> Self {
        Self {
            sampling: model.config.sampling.clone(),
            seed,
        }
    }
}

/// What [`generate`] made.
#[derive(Clone, Debug)]
pub struct Generated {
    /// `(frames, 675)` holistic rows in data units (not normalised).
    pub rows: Vec<f32>,
    pub frames: usize,
    pub windows: usize,
    /// Token index (per part) where each window after the first starts being new.
    pub joins: Vec<usize>,
}

/// Why [`generate`] stopped.
#[derive(Debug, thiserror::Error)]
pub enum GenerateError {
    #[error("{0}")]
    Invalid(String),
    #[error(transparent)]
    Cancelled(#[from] Cancelled),
}

/// The window starts (in tokens) for `n` tokens: windows of `w` tokens, each new one starting
/// `overlap` before the end of the last, the last one ending at `n`.
pub fn window_starts(n: usize, w: usize, overlap: usize) -> Vec<usize> {
    if n <= w {
        return vec![0];
    }
    let mut starts = vec![0];
    let step = w - overlap.min(w - 1);
    loop {
        let last = *starts.last().expect("one start");
        if last + w >= n {
            break;
        }
        starts.push((last + step).min(n - w));
    }
    starts
}

/// `music` `(frames, 35)` → a dance of the same number of frames.
pub fn generate(
    model: &HolisticModel,
    music: &[f32],
    opts: &GenerateOptions,
    device: &Device,
    hook: &dyn StepHook,
) -> Result<Generated, GenerateError> {
    if music.is_empty() || !music.len().is_multiple_of(MUSIC_DIMS) {
        return Err(GenerateError::Invalid(format!(
            "music features must be whole {MUSIC_DIMS}-value frames (got {} values)",
            music.len()
        )));
    }
    let frames = music.len() / MUSIC_DIMS;
    let cfg = &model.config;
    let fpt = cfg.vq.frames_per_token();
    let q = cfg.vq.levels();
    let n = frames.div_ceil(fpt);
    let w = cfg.generator.window_tokens.min(n);
    let starts = window_starts(n, w, opts.sampling.overlap_tokens);
    // tokens[(part · n + t) · q + level]; negative = not made yet.
    let mut tokens = vec![-1i64; 3 * n * q];
    let mut made = 0usize;
    let mut joins = Vec::new();
    for (k, &s) in starts.iter().enumerate() {
        if k > 0 {
            joins.push(made);
        }
        let seed = opts
            .seed
            .wrapping_mul(0x9E37_79B9_7F4A_7C15)
            .wrapping_add(k as u64);
        let cond = window_condition(model, music, frames, s * fpt, w * fpt, device);
        let known: Vec<i64> = (0..3 * w)
            .map(|p| {
                let t = s + p % w;
                if t < made {
                    tokens[((p / w) * n + t) * q]
                } else {
                    -1
                }
            })
            .collect();
        let base = model.generator.masked.sample_with(
            cond.clip.clone(),
            cond.frames.clone(),
            3 * w,
            Some(&known),
            &opts.sampling.masked(seed),
        );
        let all: Vec<i64> = match &model.generator.residual {
            Some(r) => r
                .sample(
                    base,
                    cond.clip,
                    cond.frames,
                    &opts.sampling.residual(seed ^ 1),
                )
                .into_data()
                .convert::<i64>()
                .try_into_vec::<i64>()
                .expect("int tokens"),
            None => base
                .into_data()
                .convert::<i64>()
                .try_into_vec::<i64>()
                .expect("int tokens"),
        };
        for p in 0..3 * w {
            let t = s + p % w;
            if t < made {
                continue;
            }
            let g = ((p / w) * n + t) * q;
            tokens[g..g + q].copy_from_slice(&all[p * q..(p + 1) * q]);
        }
        made = s + w;
        step(hook, TOKENS, k + 1, starts.len())?;
    }
    let idx = Tensor::<3, Int>::from_data(TensorData::new(tokens, [1, 3 * n, q]), device);
    let decoded: Vec<f32> = model
        .vq
        .decode(idx)
        .into_data()
        .try_into_vec::<f32>()
        .expect("f32 motion");
    let mut rows = decoded[..frames * TOTAL_DIMS].to_vec();
    model.norm.inverse(&mut rows);
    Ok(Generated {
        rows,
        frames,
        windows: starts.len(),
        joins,
    })
}

/// The music condition of frames `[start, start + len)` (the song's last frame repeated past
/// its end).
fn window_condition(
    model: &HolisticModel,
    music: &[f32],
    frames: usize,
    start: usize,
    len: usize,
    device: &Device,
) -> Condition {
    let mut m = Vec::with_capacity(len * MUSIC_DIMS);
    for f in start..start + len {
        let f = f.min(frames - 1);
        m.extend_from_slice(&music[f * MUSIC_DIMS..(f + 1) * MUSIC_DIMS]);
    }
    let m = Tensor::<3>::from_data(TensorData::new(m, [1, len, MUSIC_DIMS]), device);
    let clip = model.mmr.music.forward(m.clone(), None);
    let fpt = model.config.vq.frames_per_token();
    let frames = (model.config.generator.d_frame(fpt) > 0).then(|| music_tokens(m, fpt));
    Condition { clip, frames }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn windows_cover_the_song_and_overlap() {
        assert_eq!(window_starts(10, 32, 8), vec![0]);
        assert_eq!(window_starts(32, 32, 8), vec![0]);
        assert_eq!(window_starts(60, 32, 8), vec![0, 24, 28]);
        let s = window_starts(450, 32, 8);
        assert_eq!(*s.last().unwrap(), 450 - 32);
        for w in s.windows(2) {
            assert!(w[1] > w[0] && w[1] <= w[0] + 24, "{s:?}");
        }
    }
}
