//! The key-motion library (D.3: Lodge++ retrieves every 8-frame primitive from a library of
//! real motion by its similarity to the coarse dance): 8-frame clips of the training motion
//! around its motion beats, keyed by the 6D rotations of the hips, shoulders and elbows.
//!
//! Clips are stored normalised like the PDDM's input, with the root's horizontal position
//! relative to the clip's frame [`PRIMITIVE_FRAMES`]` / 2` (the first frame of the next window
//! when the clip sits on a window boundary).

use std::path::Path;

use dancegen_io::npy::NpyData;

use crate::config::PRIMITIVE_FRAMES;
use crate::layout::{DIMS, MAIN_JOINTS, RETRIEVAL_MAIN, ROOT_HORIZONTAL, main_channels, rot6d};
use crate::primitives::{motion_beats, speed};

/// Key width: 6 joints × 6D × 8 frames.
pub const KEY_DIMS: usize = RETRIEVAL_MAIN.len() * 6 * PRIMITIVE_FRAMES;

/// See the module documentation.
#[derive(Clone, Debug)]
pub struct PrimitiveLibrary {
    /// `[K, 8, 151]`.
    pub clips: Vec<f32>,
    /// `[K, KEY_DIMS]`.
    pub keys: Vec<f32>,
}

/// PDDM channels of the retrieval joints, in [`RETRIEVAL_MAIN`] order.
pub fn retrieval_channels() -> Vec<usize> {
    RETRIEVAL_MAIN
        .iter()
        .flat_map(|&m| (0..6).map(move |k| rot6d(MAIN_JOINTS[m], k)))
        .collect()
}

impl PrimitiveLibrary {
    pub fn len(&self) -> usize {
        self.keys.len() / KEY_DIMS
    }

    pub fn is_empty(&self) -> bool {
        self.keys.is_empty()
    }

    /// Clips around the motion beats of `motions` (normalised `[T, 151]` each, absolute root).
    pub fn build<'a>(motions: impl IntoIterator<Item = &'a [f32]>) -> Self {
        let half = PRIMITIVE_FRAMES / 2;
        let chans = main_channels();
        let keys_c = retrieval_channels();
        let mut lib = Self {
            clips: Vec::new(),
            keys: Vec::new(),
        };
        for m in motions {
            let t = m.len() / DIMS;
            for c in motion_beats(&speed(m, DIMS, &chans)) {
                if c < half || c + half > t {
                    continue;
                }
                let clip = &m[(c - half) * DIMS..(c + half) * DIMS];
                lib.keys.extend(key_of(clip, DIMS, &keys_c));
                let mut v = clip.to_vec();
                relative_root(&mut v, half);
                lib.clips.extend(v);
            }
        }
        lib
    }

    /// The clip `[8, 151]` whose key is nearest to `key`.
    pub fn nearest(&self, key: &[f32]) -> &[f32] {
        assert!(!self.is_empty(), "empty primitive library");
        let best = self
            .keys
            .chunks(KEY_DIMS)
            .enumerate()
            .map(|(i, k)| {
                let d: f32 = k.iter().zip(key).map(|(a, b)| (a - b) * (a - b)).sum();
                (i, d)
            })
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(i, _)| i)
            .unwrap_or(0);
        let n = PRIMITIVE_FRAMES * DIMS;
        &self.clips[best * n..(best + 1) * n]
    }

    pub fn save(&self, path: &Path) -> Result<(), dancegen_io::atomic::WriteError> {
        let k = self.len();
        dancegen_io::npz::write_npz(
            path,
            &[
                (
                    "clips",
                    &[k, PRIMITIVE_FRAMES, DIMS],
                    NpyData::F32(&self.clips),
                ),
                ("keys", &[k, KEY_DIMS], NpyData::F32(&self.keys)),
            ],
        )
    }

    pub fn load(path: &Path) -> Result<Self, String> {
        let members = dancegen_io::npz::read_npz(path).map_err(|e| e.to_string())?;
        let get = |name: &str, width: usize| -> Result<Vec<f32>, String> {
            let a = members
                .iter()
                .find(|(n, _)| n == name)
                .map(|(_, a)| a)
                .ok_or_else(|| format!("{}: no `{name}` array", path.display()))?;
            if a.shape.iter().skip(1).product::<usize>() != width {
                return Err(format!(
                    "{}: `{name}` has shape {:?}, rows of {width} expected",
                    path.display(),
                    a.shape
                ));
            }
            Ok(a.data.iter().map(|&v| v as f32).collect())
        };
        let lib = Self {
            clips: get("clips", PRIMITIVE_FRAMES * DIMS)?,
            keys: get("keys", KEY_DIMS)?,
        };
        if lib.clips.len() / (PRIMITIVE_FRAMES * DIMS) != lib.len() || lib.is_empty() {
            return Err(format!(
                "{}: clips and keys disagree or are empty",
                path.display()
            ));
        }
        Ok(lib)
    }
}

/// The retrieval key of a clip `[8, width]` whose retrieval channels are `channels`.
pub fn key_of(clip: &[f32], width: usize, channels: &[usize]) -> Vec<f32> {
    clip.chunks(width)
        .flat_map(|f| channels.iter().map(move |&c| f[c]))
        .collect()
}

/// Makes the root's horizontal position of `clip` `[8, 151]` relative to frame `origin`.
pub fn relative_root(clip: &mut [f32], origin: usize) {
    for &c in &ROOT_HORIZONTAL {
        let o = clip[origin * DIMS + c];
        for f in clip.chunks_mut(DIMS) {
            f[c] -= o;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearest_finds_the_matching_clip() {
        let t = 200;
        let mut m = vec![0f32; t * DIMS];
        let ch = retrieval_channels();
        for f in 0..t {
            let v = (f as f32 * std::f32::consts::TAU / 40.0).sin();
            for &c in &ch {
                m[f * DIMS + c] = v;
            }
            m[f * DIMS + 4] = f as f32 * 0.1;
        }
        let lib = PrimitiveLibrary::build([m.as_slice()]);
        assert!(lib.len() >= 4, "{} clips", lib.len());
        let clip = lib.nearest(&lib.keys[..KEY_DIMS]).to_vec();
        assert_eq!(&clip[..], &lib.clips[..PRIMITIVE_FRAMES * DIMS]);
        // Root horizontal relative to frame 4.
        assert!(clip[4 * DIMS + 4].abs() < 1e-6);
        assert!((clip[5 * DIMS + 4] - 0.1).abs() < 1e-5);
    }
}
