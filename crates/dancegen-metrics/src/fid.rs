//! Fréchet distance between feature sets (FID_k / FID_g), Bailando protocol.
//!
//! Reference: `lisiyao21/Bailando:utils/metrics_new.py` (`normalize`, `calc_fid`), same formula
//! as `google-research/mint:tools/calculate_scores.py`:
//!
//! `FD = ‖μ1 − μ2‖² + tr(Σ1) + tr(Σ2) − 2·tr(sqrtm(Σ1 Σ2))`, with μ the mean over samples and
//! Σ the sample covariance (`np.cov(rowvar=False)`, denominator N − 1).
//!
//! Differences from the reference, all below the 1e-6 relative target on the fixtures:
//! - everything is float64 (Bailando's normalised features, means and diffs are float32);
//! - `tr(sqrtm(Σ1 Σ2))` is computed as `Σ √λ_i` over the eigenvalues of the symmetric PSD matrix
//!   `Σ1^{1/2} Σ2 Σ1^{1/2}` (same spectrum as `Σ1 Σ2`), clamping round-off negatives to 0, instead
//!   of scipy's Schur-based `sqrtm`. On the rank-deficient fixture covariances scipy's trace carries
//!   ~5e-6 absolute noise (and a small imaginary part, which Bailando keeps and we drop: we return
//!   the real part only).

use nalgebra::{DMatrix, DVector, SymmetricEigen};

/// Offset added to both covariances when the matrix square root is not finite
/// (Bailando / LODGE).
pub const EPS_BAILANDO: f64 = 1e-5;

/// Offset used by mint / GCD.
pub const EPS_MINT: f64 = 1e-6;

/// Added to the GT standard deviation before dividing (no guard for zero std, as in the reference).
pub const NORMALIZE_STD_EPS: f64 = 1e-10;

/// Per-dimension mean and population standard deviation (ddof = 0) of a set of feature vectors.
///
/// # Panics
/// If `features` is empty or the vectors have different lengths.
pub fn mean_and_std(features: &[Vec<f64>]) -> (Vec<f64>, Vec<f64>) {
    let dim = check_rows(features);
    let n = features.len() as f64;
    let mut mean = vec![0.0; dim];
    for row in features {
        for (m, &v) in mean.iter_mut().zip(row) {
            *m += v;
        }
    }
    for m in &mut mean {
        *m /= n;
    }
    let mut var = vec![0.0; dim];
    for row in features {
        for ((s, &v), &m) in var.iter_mut().zip(row).zip(&mean) {
            *s += (v - m) * (v - m);
        }
    }
    let std = var.into_iter().map(|s| (s / n).sqrt()).collect();
    (mean, std)
}

/// Bailando `normalize`: z-scores **both** sets with the GT set's per-dimension mean and
/// population std, `(f − μ_gt) / (σ_gt + 1e−10)`. Returns `(gt_normalised, pred_normalised)`.
///
/// Dimensions with zero GT std are divided by 1e−10, as in the reference (values explode).
///
/// # Panics
/// If `gt` is empty or any vector's length differs from the GT dimension.
pub fn normalize_by_gt(gt: &[Vec<f64>], pred: &[Vec<f64>]) -> (Vec<Vec<f64>>, Vec<Vec<f64>>) {
    let (mean, std) = mean_and_std(gt);
    let dim = mean.len();
    let apply = |rows: &[Vec<f64>]| -> Vec<Vec<f64>> {
        rows.iter()
            .map(|row| {
                assert_eq!(row.len(), dim, "feature dimension mismatch");
                row.iter()
                    .zip(&mean)
                    .zip(&std)
                    .map(|((&v, &m), &s)| (v - m) / (s + NORMALIZE_STD_EPS))
                    .collect()
            })
            .collect()
    };
    (apply(gt), apply(pred))
}

/// Sample mean and covariance (`np.cov(rowvar=False)`, denominator N − 1).
///
/// With a single sample the covariance is NaN, as in numpy.
///
/// # Panics
/// If `features` is empty or the vectors have different lengths.
pub fn mean_and_cov(features: &[Vec<f64>]) -> (DVector<f64>, DMatrix<f64>) {
    let dim = check_rows(features);
    let n = features.len();
    let mut mean = DVector::<f64>::zeros(dim);
    for row in features {
        for (m, &v) in mean.iter_mut().zip(row) {
            *m += v;
        }
    }
    mean /= n as f64;
    let centered = DMatrix::from_fn(n, dim, |i, j| features[i][j] - mean[j]);
    let cov = centered.transpose() * &centered / (n as f64 - 1.0);
    (mean, cov)
}

/// `tr(sqrtm(Σ1 Σ2))` for symmetric PSD `Σ1`, `Σ2`: `Σ √max(λ_i, 0)` over the eigenvalues of
/// `Σ1^{1/2} Σ2 Σ1^{1/2}`, with `Σ1^{1/2}` from a symmetric eigendecomposition of `Σ1`
/// (negative round-off eigenvalues clamped to 0). NaN if an input is not finite.
pub fn trace_sqrt_product(sigma1: &DMatrix<f64>, sigma2: &DMatrix<f64>) -> f64 {
    assert!(sigma1.is_square() && sigma1.shape() == sigma2.shape());
    if !(sigma1.iter().all(|v| v.is_finite()) && sigma2.iter().all(|v| v.is_finite())) {
        return f64::NAN;
    }
    let root1 = psd_sqrt(sigma1);
    let s = &root1 * sigma2 * &root1;
    let s = (&s + s.transpose()) * 0.5;
    SymmetricEigen::new(s)
        .eigenvalues
        .iter()
        .map(|&l| l.max(0.0).sqrt())
        .sum()
}

/// Principal square root of a symmetric PSD matrix (negative eigenvalues clamped to 0).
fn psd_sqrt(m: &DMatrix<f64>) -> DMatrix<f64> {
    let sym = (m + m.transpose()) * 0.5;
    let eig = SymmetricEigen::new(sym);
    let roots = eig.eigenvalues.map(|l| l.max(0.0).sqrt());
    let v = &eig.eigenvectors;
    let scaled = DMatrix::from_fn(v.nrows(), v.ncols(), |i, j| v[(i, j)] * roots[j]);
    &scaled * v.transpose()
}

/// Fréchet distance from precomputed statistics. If the trace term is not finite, `eps·I` is
/// added to both covariances and it is recomputed (Bailando / mint fallback); with the
/// eigenvalue method this only happens for non-finite inputs, where the result stays NaN.
pub fn frechet_distance_from_stats(
    mu1: &DVector<f64>,
    sigma1: &DMatrix<f64>,
    mu2: &DVector<f64>,
    sigma2: &DMatrix<f64>,
    eps: f64,
) -> f64 {
    assert_eq!(mu1.len(), mu2.len(), "mean dimension mismatch");
    let diff = mu1 - mu2;
    let mut tr_covmean = trace_sqrt_product(sigma1, sigma2);
    if !tr_covmean.is_finite() {
        let offset = DMatrix::<f64>::identity(sigma1.nrows(), sigma1.ncols()) * eps;
        tr_covmean = trace_sqrt_product(&(sigma1 + &offset), &(sigma2 + &offset));
    }
    diff.dot(&diff) + sigma1.trace() + sigma2.trace() - 2.0 * tr_covmean
}

/// Fréchet distance between two sets of feature vectors (rows), float64 throughout.
/// `eps` is the fallback offset ([`EPS_BAILANDO`] or [`EPS_MINT`]).
///
/// Apply [`normalize_by_gt`] first to follow the Bailando / mint protocol. Bailando calls it as
/// `calc_fid(pred, gt)`; the distance is symmetric in its arguments.
///
/// # Panics
/// If a set is empty or the dimensions differ.
pub fn frechet_distance(a: &[Vec<f64>], b: &[Vec<f64>], eps: f64) -> f64 {
    let (mu1, sigma1) = mean_and_cov(a);
    let (mu2, sigma2) = mean_and_cov(b);
    frechet_distance_from_stats(&mu1, &sigma1, &mu2, &sigma2, eps)
}

fn check_rows(features: &[Vec<f64>]) -> usize {
    assert!(!features.is_empty(), "empty feature set");
    let dim = features[0].len();
    assert!(
        features.iter().all(|r| r.len() == dim),
        "feature vectors have different lengths"
    );
    dim
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identical_sets_have_zero_distance() {
        let a = vec![
            vec![1.0, 2.0, 0.5],
            vec![0.0, -1.0, 2.0],
            vec![3.0, 0.5, 1.0],
            vec![2.0, 2.0, -1.0],
        ];
        let d = frechet_distance(&a, &a, EPS_BAILANDO);
        assert!(d.abs() < 1e-12, "{d}");
    }

    #[test]
    fn diagonal_covariances_match_closed_form() {
        // Σ1 = diag(4, 1), Σ2 = diag(1, 9): FD = |Δμ|² + Σ (√a − √b)².
        let mu1 = DVector::from_vec(vec![1.0, 0.0]);
        let mu2 = DVector::from_vec(vec![0.0, 2.0]);
        let s1 = DMatrix::from_diagonal(&DVector::from_vec(vec![4.0, 1.0]));
        let s2 = DMatrix::from_diagonal(&DVector::from_vec(vec![1.0, 9.0]));
        let d = frechet_distance_from_stats(&mu1, &s1, &mu2, &s2, EPS_BAILANDO);
        let want = 5.0 + 1.0 + 4.0;
        assert!((d - want).abs() < 1e-12, "{d} vs {want}");
    }

    #[test]
    fn non_finite_input_takes_offset_path_and_stays_nan() {
        let mu = DVector::from_vec(vec![0.0]);
        let s1 = DMatrix::from_element(1, 1, f64::NAN);
        let s2 = DMatrix::from_element(1, 1, 1.0);
        assert!(frechet_distance_from_stats(&mu, &s1, &mu, &s2, EPS_MINT).is_nan());
    }

    #[test]
    fn normalisation_uses_gt_population_std() {
        let gt = vec![vec![1.0], vec![3.0]];
        let pred = vec![vec![4.0]];
        let (g, p) = normalize_by_gt(&gt, &pred);
        assert!((g[0][0] + 1.0).abs() < 1e-9 && (g[1][0] - 1.0).abs() < 1e-9);
        assert!((p[0][0] - 2.0).abs() < 1e-9);
    }
}
