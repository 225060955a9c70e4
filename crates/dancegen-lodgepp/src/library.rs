//! The key-motion library (D.3: Lodge++ retrieves every 8-frame primitive from a library of
//! real motion by its similarity to the coarse dance): 8-frame clips of the training motion
//! around its motion beats, keyed by the 6D rotations of the hips, shoulders and elbows.
//!
//! Clips are stored normalised like the PDDM's input, with the root's horizontal position
//! relative to the clip's frame [`PRIMITIVE_FRAMES`]` / 2` (the first frame of the next window
//! when the clip sits on a window boundary).
//!
//! Each clip carries the genre of the take it was cut from, and retrieval for a genre searches
//! that genre's clips only (our choice; the paper says nothing of genre in retrieval). With
//! several genres in one library the nearest clip by pose alone may be another genre's, and
//! key motions are a large share of every window, so a retrieval blind to genre works against
//! the genre asked for. (It was one suspect for the v2 model's lost genre control in
//! docs/solo-data-v2.md; with it, the v3 model still did not follow `modern`.)

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
    /// `[K]`: the genre index (the bundle's `genres`) of each clip's take, [`NO_GENRE`] when
    /// unknown (libraries written before genres were stored: every clip matches every genre).
    pub genres: Vec<i64>,
}

/// The genre tag of a clip whose take had no genre.
pub const NO_GENRE: i64 = -1;

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

    /// Clips around the motion beats of `motions` (normalised `[T, 151]` each, absolute root),
    /// each with its take's genre index.
    pub fn build<'a>(motions: impl IntoIterator<Item = (&'a [f32], Option<usize>)>) -> Self {
        let half = PRIMITIVE_FRAMES / 2;
        let chans = main_channels();
        let keys_c = retrieval_channels();
        let mut lib = Self {
            clips: Vec::new(),
            keys: Vec::new(),
            genres: Vec::new(),
        };
        for (m, genre) in motions {
            let tag = genre.map_or(NO_GENRE, |g| g as i64);
            let t = m.len() / DIMS;
            for c in motion_beats(&speed(m, DIMS, &chans)) {
                if c < half || c + half > t {
                    continue;
                }
                let clip = &m[(c - half) * DIMS..(c + half) * DIMS];
                lib.keys.extend(key_of(clip, DIMS, &keys_c));
                lib.genres.push(tag);
                let mut v = clip.to_vec();
                relative_root(&mut v, half);
                lib.clips.extend(v);
            }
        }
        lib
    }

    /// Whether the library holds clips tagged with `genre`.
    pub fn has_genre(&self, genre: usize) -> bool {
        self.genres.contains(&(genre as i64))
    }

    /// The clip `[8, 151]` whose key is nearest to `key`, among the clips of `genre` when there
    /// are any (and of untagged takes), else among all.
    pub fn nearest(&self, key: &[f32], genre: Option<usize>) -> &[f32] {
        assert!(!self.is_empty(), "empty primitive library");
        let only = genre.filter(|&g| self.has_genre(g)).map(|g| g as i64);
        let best = self
            .keys
            .chunks(KEY_DIMS)
            .enumerate()
            .filter(|(i, _)| {
                only.is_none_or(|g| self.genres[*i] == g || self.genres[*i] == NO_GENRE)
            })
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
                ("genres", &[k], NpyData::I64(&self.genres)),
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
        let clips = get("clips", PRIMITIVE_FRAMES * DIMS)?;
        let keys = get("keys", KEY_DIMS)?;
        let k = keys.len() / KEY_DIMS;
        // Optional: libraries from before genre tags match every genre.
        let genres = match members.iter().find(|(n, _)| n == "genres") {
            Some((_, a)) => a.data.iter().map(|&v| v as i64).collect(),
            None => vec![NO_GENRE; k],
        };
        let lib = Self {
            clips,
            keys,
            genres,
        };
        if lib.clips.len() / (PRIMITIVE_FRAMES * DIMS) != k || lib.genres.len() != k || k == 0 {
            return Err(format!(
                "{}: clips, keys and genres disagree or are empty",
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
        let lib = PrimitiveLibrary::build([(m.as_slice(), None)]);
        assert!(lib.len() >= 4, "{} clips", lib.len());
        let clip = lib.nearest(&lib.keys[..KEY_DIMS], None).to_vec();
        assert_eq!(&clip[..], &lib.clips[..PRIMITIVE_FRAMES * DIMS]);
        // Root horizontal relative to frame 4.
        assert!(clip[4 * DIMS + 4].abs() < 1e-6);
        assert!((clip[5 * DIMS + 4] - 0.1).abs() < 1e-5);
    }

    /// Two takes of two genres, the second a slightly scaled copy of the first: the nearest
    /// clip by pose is the first take's, but asking for genre 1 gets the second take's; a genre
    /// with no clips falls back to all; tags survive save + load.
    #[test]
    fn retrieval_stays_in_the_requested_genre() {
        let t = 200;
        let ch = retrieval_channels();
        let take = |amp: f32| {
            let mut m = vec![0f32; t * DIMS];
            for f in 0..t {
                let v = amp * (f as f32 * std::f32::consts::TAU / 40.0).sin();
                for &c in &ch {
                    m[f * DIMS + c] = v;
                }
            }
            m
        };
        let (a, b) = (take(1.0), take(0.9));
        let lib = PrimitiveLibrary::build([(a.as_slice(), Some(0)), (b.as_slice(), Some(1))]);
        let first_b = lib.genres.iter().position(|&g| g == 1).unwrap();
        assert!(first_b > 0);
        let key = &lib.keys[..KEY_DIMS];
        let clip = |g: Option<usize>| lib.nearest(key, g).as_ptr();
        let start_of = |i: usize| lib.clips[i * PRIMITIVE_FRAMES * DIMS..].as_ptr();
        assert_eq!(clip(None), start_of(0));
        assert_eq!(clip(Some(0)), start_of(0));
        let got = lib.nearest(key, Some(1));
        let i = (got.as_ptr() as usize - lib.clips.as_ptr() as usize)
            / (PRIMITIVE_FRAMES * DIMS * std::mem::size_of::<f32>());
        assert_eq!(lib.genres[i], 1, "clip {i} is not of genre 1");
        assert_eq!(clip(Some(7)), start_of(0), "unknown genre: all clips");

        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("library.npz");
        lib.save(&p).unwrap();
        let back = PrimitiveLibrary::load(&p).unwrap();
        assert_eq!(back.genres, lib.genres);
        assert_eq!(back.keys, lib.keys);
    }
}
