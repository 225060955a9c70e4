//! FLAME face parameters to and from ARKit weights through a user-supplied linear map.
//!
//! SoulNet defines the FLAME face as `flame = b · W`: `b` the 52 ARKit weights, `W` a 52 × 103
//! matrix fitted from hand-made templates, whose 103 columns are 100 expression values and 3 jaw
//! values (`../shared/reference/holistic.md` §5). `W` is not released and FLAME is
//! non-commercial, so nothing here ships one: users who have a `W` pass it as a `(52, 103)`
//! `.npy` file. Going from FLAME back to ARKit is the box-constrained least-squares problem
//! `min ‖b · W − flame‖²` over `0 ≤ b ≤ 1`, solved by cyclic coordinate descent (each step is
//! the exact minimiser along one weight, clamped, so the objective never rises).
//!
//! SoulNet's released code models only the 100 expression values and drops the jaw, so a
//! frame of 100 values is matched against `W`'s first 100 columns.

use std::path::Path;

use super::arkit::{ARKIT_COUNT, FaceError};

/// Columns of `W`: 100 FLAME expression values, then 3 jaw values.
pub const FLAME_DIMS: usize = 103;
/// FLAME expression values (the part SoulNet models).
pub const FLAME_EXPRESSION_DIMS: usize = 100;

/// Coordinate-descent sweeps at most, and the largest weight change that ends them.
const MAX_SWEEPS: usize = 500;
const TOLERANCE: f64 = 1e-7;

/// A 52 × 103 ARKit → FLAME map.
#[derive(Debug, Clone)]
pub struct FlameMapping {
    /// Row-major `(52, 103)`.
    w: Vec<f64>,
}

impl FlameMapping {
    /// From a row-major `(52, 103)` matrix; `shape` and `source` name what is wrong otherwise.
    pub fn new(w: Vec<f64>, shape: &[usize], source: &str) -> Result<Self, FaceError> {
        if shape != [ARKIT_COUNT, FLAME_DIMS] || w.len() != ARKIT_COUNT * FLAME_DIMS {
            return Err(FaceError::File {
                path: source.to_string(),
                reason: format!(
                    "a FLAME mapping must be a ({ARKIT_COUNT}, {FLAME_DIMS}) matrix (52 ARKit \
                     weights to 100 FLAME expression + 3 jaw values), got shape {shape:?}"
                ),
            });
        }
        if let Some(i) = w.iter().position(|v| !v.is_finite()) {
            return Err(FaceError::File {
                path: source.to_string(),
                reason: format!(
                    "value [{}, {}] is not finite",
                    i / FLAME_DIMS,
                    i % FLAME_DIMS
                ),
            });
        }
        Ok(FlameMapping { w })
    }

    /// Reads a `(52, 103)` `.npy` file.
    pub fn read(path: &Path) -> Result<Self, FaceError> {
        let a = dancegen_io::npy::read_npy(path).map_err(|e| FaceError::File {
            path: path.display().to_string(),
            reason: e.reason,
        })?;
        Self::new(a.data, &a.shape, &path.display().to_string())
    }

    /// `b · W`: one frame's 103 FLAME values from its 52 ARKit weights.
    pub fn to_flame(&self, arkit: &[f32]) -> Vec<f32> {
        let mut out = vec![0.0f64; FLAME_DIMS];
        for (i, &b) in arkit.iter().enumerate().take(ARKIT_COUNT) {
            for (o, &w) in out
                .iter_mut()
                .zip(&self.w[i * FLAME_DIMS..(i + 1) * FLAME_DIMS])
            {
                *o += b as f64 * w;
            }
        }
        out.into_iter().map(|v| v as f32).collect()
    }

    /// The ARKit weights in [0, 1] whose FLAME values are nearest `flame` (100 expression values,
    /// or 103 with the jaw).
    pub fn to_arkit(&self, flame: &[f32]) -> Result<Vec<f32>, FaceError> {
        let d = flame.len();
        if d != FLAME_DIMS && d != FLAME_EXPRESSION_DIMS {
            return Err(FaceError::Shape(format!(
                "a FLAME frame has {FLAME_EXPRESSION_DIMS} or {FLAME_DIMS} values, got {d}"
            )));
        }
        let row = |i: usize| &self.w[i * FLAME_DIMS..i * FLAME_DIMS + d];
        // Normal equations: Q = W Wᵀ (52 × 52), c = W · flame.
        let mut q = vec![0.0f64; ARKIT_COUNT * ARKIT_COUNT];
        let mut c = vec![0.0f64; ARKIT_COUNT];
        for i in 0..ARKIT_COUNT {
            c[i] = row(i).iter().zip(flame).map(|(w, &f)| w * f as f64).sum();
            for j in 0..=i {
                let v: f64 = row(i).iter().zip(row(j)).map(|(a, b)| a * b).sum();
                q[i * ARKIT_COUNT + j] = v;
                q[j * ARKIT_COUNT + i] = v;
            }
        }
        let mut b = vec![0.0f64; ARKIT_COUNT];
        // Gradient Q b − c, kept up to date as weights change.
        let mut g: Vec<f64> = c.iter().map(|v| -v).collect();
        for _ in 0..MAX_SWEEPS {
            let mut moved = 0.0f64;
            for i in 0..ARKIT_COUNT {
                let qii = q[i * ARKIT_COUNT + i];
                if qii <= 0.0 {
                    continue; // a blendshape that moves no FLAME value stays at 0
                }
                let new = (b[i] - g[i] / qii).clamp(0.0, 1.0);
                let step = new - b[i];
                if step != 0.0 {
                    for (gk, qk) in g.iter_mut().zip(&q[i * ARKIT_COUNT..(i + 1) * ARKIT_COUNT]) {
                        *gk += step * qk;
                    }
                    b[i] = new;
                    moved = moved.max(step.abs());
                }
            }
            if moved < TOLERANCE {
                break;
            }
        }
        Ok(b.into_iter().map(|v| v as f32).collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

    fn random_mapping(seed: u64) -> FlameMapping {
        let mut r = SplitMix64(seed);
        let w = (0..ARKIT_COUNT * FLAME_DIMS)
            .map(|_| r.next_f64() * 2.0 - 1.0)
            .collect();
        FlameMapping::new(w, &[52, 103], "test").unwrap()
    }

    #[test]
    fn flame_of_arkit_weights_maps_back_to_them() {
        let m = random_mapping(3);
        let mut r = SplitMix64(9);
        // Some weights at the bounds, as real faces at rest or fully blinking are.
        let b: Vec<f32> = (0..ARKIT_COUNT)
            .map(|i| match i % 5 {
                0 => 0.0,
                1 => 1.0,
                _ => r.next_f64() as f32,
            })
            .collect();
        let flame = m.to_flame(&b);
        assert_eq!(flame.len(), 103);
        for d in [103, 100] {
            let back = m.to_arkit(&flame[..d]).unwrap();
            let err = back
                .iter()
                .zip(&b)
                .map(|(x, y)| (x - y).abs())
                .fold(0.0, f32::max);
            assert!(err < 1e-4, "{d} values: {err}");
        }
    }

    #[test]
    fn targets_outside_the_box_are_clamped_to_the_nearest_face() {
        let m = random_mapping(5);
        // Twice a valid face: the unconstrained solution has weights above 1.
        let b = vec![0.8f32; ARKIT_COUNT];
        let flame: Vec<f32> = m.to_flame(&b).iter().map(|v| v * 2.0).collect();
        let back = m.to_arkit(&flame).unwrap();
        assert!(back.iter().all(|v| (0.0..=1.0).contains(v)));
        // No feasible point does better: the all-ones face is feasible.
        let cost = |x: &[f32]| -> f64 {
            m.to_flame(x)
                .iter()
                .zip(&flame)
                .map(|(a, b)| ((a - b) as f64).powi(2))
                .sum()
        };
        assert!(cost(&back) <= cost(&vec![1.0; ARKIT_COUNT]) + 1e-6);
        assert!(cost(&back) <= cost(&b) + 1e-6);
    }

    #[test]
    fn wrong_shapes_are_named() {
        let e = FlameMapping::new(vec![0.0; 100 * 52], &[52, 100], "w.npy")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("w.npy") && e.contains("(52, 103)") && e.contains("[52, 100]"),
            "{e}"
        );
        let e = FlameMapping::new(vec![0.0; 52 * 103], &[103, 52], "t.npy")
            .unwrap_err()
            .to_string();
        assert!(e.contains("[103, 52]"), "{e}");
        let mut w = vec![0.0; 52 * 103];
        w[104] = f64::NAN;
        let e = FlameMapping::new(w, &[52, 103], "n.npy")
            .unwrap_err()
            .to_string();
        assert!(e.contains("[1, 1]"), "{e}");
        let m = random_mapping(1);
        assert!(m.to_arkit(&[0.0; 52]).is_err());
        // From a file: the file and its shape are named.
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("flame_map.npy");
        dancegen_io::npy::write_npy_f32(&p, &[52, 100], &[0.5; 5200]).unwrap();
        let e = FlameMapping::read(&p).unwrap_err().to_string();
        assert!(
            e.contains("flame_map.npy") && e.contains("[52, 100]"),
            "{e}"
        );
        dancegen_io::npy::write_npy_f32(&p, &[52, 103], &[0.5; 52 * 103]).unwrap();
        assert!(FlameMapping::read(&p).is_ok());
        let e = FlameMapping::read(&dir.path().join("none.npy"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("none.npy"), "{e}");
    }
}
