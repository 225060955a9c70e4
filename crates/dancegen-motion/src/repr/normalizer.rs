//! Per-dimension MinMax normaliser to `[−1, 1]`, EDGE / LODGE semantics
//! (`Stanford-TML/EDGE:dataset/preprocess.py`, `li-ronghui/LODGE:dld/data/utils/preprocess.py`;
//! anchors.md C.2).
//!
//! - fit: per-dimension `min`, `max` over all rows (statistics in `f64`);
//! - `range = max − min`, replaced by 1 where `range < 10·f32::EPSILON` (sklearn
//!   `_handle_zeros_in_scale`); `scale = 2 / range`, `offset = −1 − min·scale`;
//! - [`MinMaxNormalizer::transform`]: `x·scale + offset`, clipped to `[−1, 1]` (`clip=True`);
//! - [`MinMaxNormalizer::inverse`]: clips the input to `[−1, 1]` first, then
//!   `(x − offset) / scale`; [`MinMaxNormalizer::inverse_tail`] inverts only the trailing `w`
//!   dims with the statistics sliced from the end, as EDGE's `unnormalize` does.
//!
//! Saved as JSON `{"dims": D, "min": [...], "max": [...]}` (not EDGE's pickled torch object).

use super::{ReprError, frames_of};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Fitted MinMax(−1, 1) statistics; see the module documentation.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MinMaxNormalizer {
    pub dims: usize,
    pub min: Vec<f64>,
    pub max: Vec<f64>,
}

impl MinMaxNormalizer {
    /// Fits on `(N, dims)` rows.
    pub fn fit(data: &[f32], dims: usize) -> Result<Self, ReprError> {
        Self::fit_chunks(std::iter::once(data), dims)
    }

    /// Fits on several `(N_i, dims)` arrays (e.g. one per clip) as if concatenated.
    pub fn fit_chunks<'a>(
        chunks: impl IntoIterator<Item = &'a [f32]>,
        dims: usize,
    ) -> Result<Self, ReprError> {
        if dims == 0 {
            return Err(ReprError::Invalid(
                "normalizer needs at least one dim".into(),
            ));
        }
        let mut min = vec![f64::INFINITY; dims];
        let mut max = vec![f64::NEG_INFINITY; dims];
        let mut rows = 0usize;
        for c in chunks {
            rows += frames_of("MinMaxNormalizer::fit", c, dims)?;
            for row in c.chunks_exact(dims) {
                for (d, &v) in row.iter().enumerate() {
                    min[d] = min[d].min(v as f64);
                    max[d] = max[d].max(v as f64);
                }
            }
        }
        if rows == 0 {
            return Err(ReprError::Invalid("normalizer fitted on no rows".into()));
        }
        Ok(MinMaxNormalizer { dims, min, max })
    }

    /// `(scale, offset)` of dim `d`.
    pub fn scale_offset(&self, d: usize) -> (f64, f64) {
        let mut range = self.max[d] - self.min[d];
        if range < 10.0 * f32::EPSILON as f64 {
            range = 1.0;
        }
        let scale = 2.0 / range;
        (scale, -1.0 - self.min[d] * scale)
    }

    /// Normalises `(N, dims)` rows in place, clipping to `[−1, 1]`.
    pub fn transform(&self, x: &mut [f32]) -> Result<(), ReprError> {
        frames_of("MinMaxNormalizer::transform", x, self.dims)?;
        let so: Vec<_> = (0..self.dims).map(|d| self.scale_offset(d)).collect();
        for row in x.chunks_exact_mut(self.dims) {
            for (v, &(s, o)) in row.iter_mut().zip(&so) {
                *v = (*v as f64 * s + o).clamp(-1.0, 1.0) as f32;
            }
        }
        Ok(())
    }

    /// Inverts `(N, dims)` rows in place (input clipped to `[−1, 1]` first).
    pub fn inverse(&self, x: &mut [f32]) -> Result<(), ReprError> {
        self.inverse_tail(x, self.dims)
    }

    /// Inverts `(N, width)` rows holding only the **last** `width` dims in place.
    pub fn inverse_tail(&self, x: &mut [f32], width: usize) -> Result<(), ReprError> {
        if width == 0 || width > self.dims {
            return Err(ReprError::Invalid(format!(
                "inverse_tail width {width} not in 1..={}",
                self.dims
            )));
        }
        frames_of("MinMaxNormalizer::inverse", x, width)?;
        let so: Vec<_> = (self.dims - width..self.dims)
            .map(|d| self.scale_offset(d))
            .collect();
        for row in x.chunks_exact_mut(width) {
            for (v, &(s, o)) in row.iter_mut().zip(&so) {
                *v = (((*v).clamp(-1.0, 1.0) as f64 - o) / s) as f32;
            }
        }
        Ok(())
    }

    /// Writes the JSON form atomically.
    pub fn save(&self, path: impl AsRef<Path>) -> Result<(), ReprError> {
        let json = serde_json::to_vec(self).map_err(|e| ReprError::Invalid(e.to_string()))?;
        dancegen_io::write_atomic(path.as_ref(), |w| w.write_all(&json))?;
        Ok(())
    }

    /// Reads the JSON form written by [`MinMaxNormalizer::save`].
    pub fn load(path: impl AsRef<Path>) -> Result<Self, ReprError> {
        let path = path.as_ref();
        let bytes = std::fs::read(path)
            .map_err(|e| ReprError::Invalid(format!("{}: {e}", path.display())))?;
        let n: MinMaxNormalizer = serde_json::from_slice(&bytes)
            .map_err(|e| ReprError::Invalid(format!("{}: {e}", path.display())))?;
        if n.min.len() != n.dims || n.max.len() != n.dims {
            return Err(ReprError::Invalid(format!(
                "{}: dims {} but {} min / {} max",
                path.display(),
                n.dims,
                n.min.len(),
                n.max.len()
            )));
        }
        Ok(n)
    }
}

/// A per-dimension mean / std normaliser as `dancegen train` writes it (`normalizer.json`,
/// `{"kind": "mean_std", "mean": [...], "std": [...]}`): `x' = (x − mean) / std`. The model
/// bundles read it through here.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MeanStdNormalizer {
    pub kind: String,
    pub mean: Vec<f64>,
    pub std: Vec<f64>,
}

impl MeanStdNormalizer {
    /// Reads `path` and checks it has `dims` values. The error says what is wrong and leaves
    /// naming the file to the caller (every bundle error names it).
    pub fn load(path: &Path, dims: usize) -> Result<Self, ReprError> {
        let text = std::fs::read_to_string(path).map_err(|e| ReprError::Invalid(e.to_string()))?;
        let m: MeanStdNormalizer = serde_json::from_str(&text)
            .map_err(|e| ReprError::Invalid(format!("not a normaliser: {e}")))?;
        if m.kind != "mean_std" || m.mean.len() != dims || m.std.len() != dims {
            return Err(ReprError::Invalid(format!(
                "expected a {dims}-dim mean_std normaliser, got {} with {} dims",
                m.kind,
                m.mean.len()
            )));
        }
        Ok(m)
    }

    /// Data units → normalised, in place (rows of `mean.len()` values).
    pub fn transform(&self, x: &mut [f32]) {
        let d = self.mean.len();
        for (i, v) in x.iter_mut().enumerate() {
            *v = ((f64::from(*v) - self.mean[i % d]) / self.std[i % d]) as f32;
        }
    }

    /// Normalised → data units, in place.
    pub fn inverse(&self, x: &mut [f32]) {
        let d = self.mean.len();
        for (i, v) in x.iter_mut().enumerate() {
            *v = (f64::from(*v) * self.std[i % d] + self.mean[i % d]) as f32;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mean_std_reads_checks_and_round_trips() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("normalizer.json");
        std::fs::write(
            &p,
            r#"{"kind":"mean_std","mean":[1.0,-2.0],"std":[2.0,0.5]}"#,
        )
        .unwrap();
        let n = MeanStdNormalizer::load(&p, 2).unwrap();
        let mut x = vec![3.0f32, -1.0, 1.0, -2.0];
        n.transform(&mut x);
        assert_eq!(x, vec![1.0, 2.0, 0.0, 0.0]);
        n.inverse(&mut x);
        assert_eq!(x, vec![3.0, -1.0, 1.0, -2.0]);
        let e = MeanStdNormalizer::load(&p, 3).unwrap_err().to_string();
        assert!(e.contains("3-dim") && e.contains("2 dims"), "{e}");
        std::fs::write(&p, "[]").unwrap();
        let e = MeanStdNormalizer::load(&p, 2).unwrap_err().to_string();
        assert!(e.contains("not a normaliser"), "{e}");
    }
}
