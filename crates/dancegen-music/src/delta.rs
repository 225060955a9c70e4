//! `librosa.feature.delta`: Savitzky-Golay derivative along time.
//!
//! `delta(data, width, order, axis=-1, mode='interp')` is
//! `scipy.signal.savgol_filter(data, window_length=width, polyorder=order, deriv=order,
//! mode='interp')`: away from the edges each output is the `order`-th derivative, at the window
//! centre, of the least-squares polynomial of degree `order` through the `width` neighbouring
//! frames; within `width/2` frames of either end, scipy instead fits one polynomial to the first
//! (last) `width` frames and differentiates it at each edge position. Both are the same linear
//! operator: a dot product of the window with `savgol_coeffs(width, order, deriv, pos, use='dot')`
//! for the appropriate position `pos` inside the window, which is how it is computed here
//! (in float64, rounded to float32 like scipy's float32 output).

use crate::error::{MusicError, Result};
use crate::stft::FrameMatrix;

/// `scipy.signal.savgol_coeffs(window_length, polyorder, deriv, delta=1, pos, use='dot')`:
/// weights `c` such that `Σ_j c[j]·x[j]` is the `deriv`-th derivative at sample `pos` of the
/// least-squares polynomial of degree `polyorder` through `x[0..window_length]`.
///
/// The minimum-norm least-squares solution of `A c = e_deriv·deriv!` with
/// `A[k][j] = (j - pos)^k`, i.e. `c = Aᵀ (A Aᵀ)⁻¹ e_deriv·deriv!`; `A Aᵀ` is the small
/// `(polyorder+1)²` Gram matrix of power sums, solved by Gaussian elimination with pivoting.
pub fn savgol_coeffs(window_length: usize, polyorder: usize, deriv: usize, pos: usize) -> Vec<f64> {
    assert!(
        polyorder < window_length,
        "polyorder must be < window_length"
    );
    assert!(pos < window_length, "pos must be inside the window");
    if deriv > polyorder {
        return vec![0.0; window_length];
    }
    let m = polyorder + 1;
    let xs: Vec<f64> = (0..window_length).map(|j| j as f64 - pos as f64).collect();
    // Gram matrix G[k][l] = Σ_j x_j^(k+l), right-hand side e_deriv · deriv!.
    let mut g = vec![vec![0.0f64; m + 1]; m];
    for (k, row) in g.iter_mut().enumerate() {
        for (l, v) in row.iter_mut().take(m).enumerate() {
            *v = xs.iter().map(|&x| x.powi((k + l) as i32)).sum();
        }
        row[m] = if k == deriv {
            (1..=deriv).map(|i| i as f64).product()
        } else {
            0.0
        };
    }
    // Gaussian elimination with partial pivoting.
    for col in 0..m {
        let piv = (col..m)
            .max_by(|&a, &b| g[a][col].abs().total_cmp(&g[b][col].abs()))
            .expect("non-empty");
        g.swap(col, piv);
        let pivot_row = g[col].clone();
        for (r, row) in g.iter_mut().enumerate() {
            if r != col {
                let f = row[col] / pivot_row[col];
                if f != 0.0 {
                    for (v, &pv) in row.iter_mut().zip(&pivot_row).skip(col) {
                        *v -= f * pv;
                    }
                }
            }
        }
    }
    let z: Vec<f64> = (0..m).map(|k| g[k][m] / g[k][k]).collect();
    xs.iter()
        .map(|&x| {
            z.iter()
                .enumerate()
                .map(|(k, &zk)| zk * x.powi(k as i32))
                .sum()
        })
        .collect()
}

/// `librosa.feature.delta(data, width=width, order=order, axis=-1, mode='interp')` on a
/// frame-major matrix (time is the row axis, librosa's last axis).
///
/// Errors like librosa: `width` must be odd and ≥ 3, `order` ≥ 1, and in 'interp' mode the
/// signal must have at least `width` frames.
pub fn delta(data: &FrameMatrix, width: usize, order: usize) -> Result<FrameMatrix> {
    if width < 3 || width % 2 != 1 {
        return Err(MusicError::InvalidParameter(format!(
            "delta width must be an odd integer >= 3 (got {width})"
        )));
    }
    if order == 0 {
        return Err(MusicError::InvalidParameter(
            "delta order must be a positive integer".into(),
        ));
    }
    let n = data.rows;
    if width > n {
        return Err(MusicError::InvalidParameter(format!(
            "delta width {width} exceeds the number of frames {n} (mode='interp')"
        )));
    }
    // polyorder >= window_length is an error in scipy.
    if order >= width {
        return Err(MusicError::InvalidParameter(format!(
            "delta order {order} must be smaller than width {width}"
        )));
    }
    let half = width / 2;
    let coeffs: Vec<Vec<f64>> = (0..width)
        .map(|pos| savgol_coeffs(width, order, order, pos))
        .collect();
    let cols = data.cols;
    let mut out = FrameMatrix::zeros(n, cols);
    for t in 0..n {
        // Window start and position of frame t inside it.
        let (start, pos) = if t < half {
            (0, t)
        } else if t + half >= n {
            (n - width, t + width - n)
        } else {
            (t - half, half)
        };
        let c = &coeffs[pos];
        let row = out.row_mut(t);
        for (f, o) in row.iter_mut().enumerate() {
            let s: f64 = c
                .iter()
                .enumerate()
                .map(|(j, &w)| w * data.data[(start + j) * cols + f] as f64)
                .sum();
            *o = s as f32;
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: &[f64], b: &[f64], tol: f64) -> bool {
        a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() <= tol)
    }

    #[test]
    fn coefficients_match_scipy() {
        // scipy.signal.savgol_coeffs(3, 1, deriv=1, use='dot')
        assert!(close(&savgol_coeffs(3, 1, 1, 1), &[-0.5, 0.0, 0.5], 1e-12));
        // scipy.signal.savgol_coeffs(9, 2, deriv=2, use='dot')
        let want = [
            0.06060606060606061,
            0.015151515151515152,
            -0.017316017316017313,
            -0.03679653679653679,
            -0.04329004329004329,
            -0.03679653679653679,
            -0.017316017316017313,
            0.015151515151515155,
            0.0606060606060606,
        ];
        assert!(close(&savgol_coeffs(9, 2, 2, 4), &want, 1e-12));
        // scipy.signal.savgol_coeffs(5, 2, deriv=1, pos=0, use='dot')
        let want = [
            -0.7714285714285716,
            0.18571428571428716,
            0.5714285714285706,
            0.38571428571428545,
            -0.3714285714285711,
        ];
        assert!(close(&savgol_coeffs(5, 2, 1, 0), &want, 1e-12));
    }

    #[test]
    fn delta_matches_librosa_including_edges() {
        let col = |v: &[f32]| FrameMatrix {
            rows: v.len(),
            cols: 1,
            data: v.to_vec(),
        };
        // librosa.feature.delta(np.float32([1,4,2,8,3]), width=3) = [.5 .5 2 .5 .50000024]
        // (scipy's edge polyfit runs in float32; the exact value is 0.5).
        let d = delta(&col(&[1.0, 4.0, 2.0, 8.0, 3.0]), 3, 1).unwrap();
        assert_eq!(d.data, vec![0.5, 0.5, 2.0, 0.5, 0.5]);
        // librosa.feature.delta(np.float32([1,4,2,8,3,7,1,0,5]), width=5, order=2)
        let want = [
            -1.1428579, -1.1428579, -1.1428572, 0.14285715, -2.142857, -0.2857143, 1.0, 1.0000023,
            1.0000023,
        ];
        let d = delta(&col(&[1.0, 4.0, 2.0, 8.0, 3.0, 7.0, 1.0, 0.0, 5.0]), 5, 2).unwrap();
        for (a, b) in d.data.iter().zip(want) {
            assert!((a - b).abs() < 1e-5, "{:?}", d.data);
        }
        assert!(delta(&col(&[1.0, 2.0]), 3, 1).is_err());
        assert!(delta(&col(&[1.0, 2.0, 3.0, 4.0]), 4, 1).is_err());
    }
}
