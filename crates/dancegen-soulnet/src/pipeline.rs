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
use crate::layout::{MUSIC_DIMS, PART_DIMS, TOTAL_DIMS};

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
    /// Windows the masked transformer sampled (fewer than `windows` where an edit knows every
    /// token of some).
    pub sampled: usize,
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
    generate_known(model, music, None, opts, device, hook)
}

/// [`generate`] around tokens that are already known (an edit, [`known_tokens`]):
/// `known[(part · n + t) · q + level]`, negative where unknown. Known tokens are given to the
/// masked transformer of every window that covers them, as the overlap of the window before
/// is, and keep all their residual levels; a window with nothing unknown is not sampled.
pub fn generate_known(
    model: &HolisticModel,
    music: &[f32],
    known: Option<&[i64]>,
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
    let given = |part: usize, t: usize| known.is_some_and(|k| k[(part * n + t) * q] >= 0);
    if let Some(k) = known {
        if k.len() != tokens.len() {
            return Err(GenerateError::Invalid(format!(
                "{} known token values for {n} tokens of 3 parts with {q} levels",
                k.len()
            )));
        }
        tokens.copy_from_slice(k);
    }
    let mut made = 0usize;
    let mut sampled = 0usize;
    let mut joins = Vec::new();
    for (k, &s) in starts.iter().enumerate() {
        if k > 0 {
            joins.push(made);
        }
        let seed = opts
            .seed
            .wrapping_mul(0x9E37_79B9_7F4A_7C15)
            .wrapping_add(k as u64);
        let fixed = |p: usize| {
            let t = s + p % w;
            t < made || given(p / w, t)
        };
        if (0..3 * w).all(fixed) {
            made = s + w;
            step(hook, TOKENS, k + 1, starts.len())?;
            continue;
        }
        sampled += 1;
        let cond = window_condition(model, music, frames, s * fpt, w * fpt, device);
        let known: Vec<i64> = (0..3 * w)
            .map(|p| {
                if fixed(p) {
                    tokens[((p / w) * n + s + p % w) * q]
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
            if fixed(p) {
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
        sampled,
        joins,
    })
}

/// The tokens of what is known of a dance, for [`generate_known`]: `rows` are `(frames, 675)`
/// split rows in data units (anything where unknown), `known[f][part]` whether frame `f`'s
/// body, hands or face is known. Each stretch of frames with something known is encoded on
/// its own (what lies outside it is never seen), the unknown parts of its frames at the data
/// mean; a part's token is known when every frame it covers has that part known.
pub fn known_tokens(
    model: &HolisticModel,
    rows: &[f32],
    known: &[[bool; 3]],
    device: &Device,
) -> Vec<i64> {
    let frames = known.len();
    assert_eq!(rows.len(), frames * TOTAL_DIMS, "one row per frame");
    let fpt = model.config.vq.frames_per_token();
    let q = model.config.vq.levels();
    let n = frames.div_ceil(fpt);
    let mut out = vec![-1i64; 3 * n * q];
    let any = |f: usize| known[f].iter().any(|&k| k);
    let offsets = [0, PART_DIMS[0], PART_DIMS[0] + PART_DIMS[1]];
    let mut f = 0;
    while f < frames {
        if !any(f) {
            f += 1;
            continue;
        }
        let a = f;
        while f < frames && any(f) {
            f += 1;
        }
        let (ta, tb) = (a / fpt, f.div_ceil(fpt));
        let len = (tb - ta) * fpt;
        let mut x = vec![0f32; len * TOTAL_DIMS];
        for i in 0..len {
            let g = (ta * fpt + i).clamp(a, f - 1);
            let row = &mut x[i * TOTAL_DIMS..(i + 1) * TOTAL_DIMS];
            row.copy_from_slice(&rows[g * TOTAL_DIMS..(g + 1) * TOTAL_DIMS]);
            model.norm.transform(row);
            for part in 0..3 {
                if !known[g][part] {
                    row[offsets[part]..offsets[part] + PART_DIMS[part]].fill(0.0);
                }
            }
        }
        let x = Tensor::<3>::from_data(TensorData::new(x, [1, len, TOTAL_DIMS]), device);
        let idx: Vec<i64> = model
            .vq
            .encode(x)
            .into_data()
            .convert::<i64>()
            .try_into_vec::<i64>()
            .expect("int tokens");
        let m = tb - ta;
        for part in [0usize, 1, 2] {
            for t in ta..tb {
                let covered = (t * fpt..((t + 1) * fpt).min(frames)).all(|g| known[g][part]);
                if covered {
                    let from = (part * m + t - ta) * q;
                    let to = (part * n + t) * q;
                    out[to..to + q].copy_from_slice(&idx[from..from + q]);
                }
            }
        }
    }
    out
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
