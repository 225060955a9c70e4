//! The rotation that best carries one point set onto another (least squares, no translation):
//! Horn's closed form, "Closed-form solution of absolute orientation using unit quaternions"
//! (JOSA A 4(4), 1987). The optimal unit quaternion is the eigenvector of the largest
//! eigenvalue of a symmetric 4 × 4 matrix built from the cross-covariance of the two sets; the
//! eigenvector is found with cyclic Jacobi rotations, which converge for every symmetric
//! matrix, so a degenerate set (all points on a line) still gives a rotation, not NaN.
//!
//! Used where a body's orientation has to be read off noisy joint positions: fitting many
//! joints is stable where a frame built from two short bone vectors flips when one of them
//! swings (`repr::humanml263`'s root rotation).

use crate::rotation::{Mat3, Quat};

/// The rotation `R` minimising `Σ w_i ‖R a_i − b_i‖²` (`weights`: `None` = all 1). Points are
/// taken as they are (centre them first for a fit with translation). Identity for empty or
/// all-zero input.
pub fn best_fit_rotation(a: &[[f64; 3]], b: &[[f64; 3]], weights: Option<&[f64]>) -> Mat3 {
    fit_rotation(a, b, weights, None).rotation
}

/// A rotation fitted by [`fit_rotation`].
#[derive(Clone, Copy, Debug)]
pub struct RotationFit {
    pub rotation: Mat3,
    /// How well the data pins the rotation down: the gap between the two largest eigenvalues
    /// of Horn's matrix `N` over `S = Σ w_i |a_i| |b_i|`, which bounds them. 0 when a whole
    /// family of rotations fits equally well; for points that a rotation carries exactly it is
    /// `2 (σ₂ + σ₃) / (σ₁ + σ₂ + σ₃)` of the cross-covariance's singular values.
    pub margin: f64,
}

/// [`best_fit_rotation`] with an optional pull toward `near = (rotation, k)`: maximises Horn's
/// `qᵀ N q + k · S · (q · q_near)²`. Where the fit is well determined (margin ≫ `k`) the result
/// moves by a fraction of order `k / margin` of its distance to `rotation`; where rotations fit
/// almost equally (margin below `k`) the one nearest `rotation` wins instead of whichever is
/// marginally better. The margin reported is that of the fit without the pull.
pub fn fit_rotation(
    a: &[[f64; 3]],
    b: &[[f64; 3]],
    weights: Option<&[f64]>,
    near: Option<(&Mat3, f64)>,
) -> RotationFit {
    let mut s = [[0.0f64; 3]; 3];
    let mut bound = 0.0f64;
    for (i, (p, q)) in a.iter().zip(b).enumerate() {
        let w = weights.map_or(1.0, |w| w[i]);
        let norm = |v: &[f64; 3]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
        bound += w * norm(p) * norm(q);
        for (r, row) in s.iter_mut().enumerate() {
            for (c, cell) in row.iter_mut().enumerate() {
                *cell += w * p[r] * q[c];
            }
        }
    }
    let [[sxx, sxy, sxz], [syx, syy, syz], [szx, szy, szz]] = s;
    let mut n = [
        [sxx + syy + szz, syz - szy, szx - sxz, sxy - syx],
        [syz - szy, sxx - syy - szz, sxy + syx, szx + sxz],
        [szx - sxz, sxy + syx, -sxx + syy - szz, syz + szy],
        [sxy - syx, szx + sxz, syz + szy, -sxx - syy + szz],
    ];
    if n.iter().flatten().all(|v| v.abs() < 1e-300) {
        return RotationFit {
            rotation: Mat3::IDENTITY,
            margin: 0.0,
        };
    }
    let (mut q, values) = top_eigenvector(n);
    let margin = (values[0] - values[1]) / bound;
    if let Some((r, k)) = near {
        let p = r.to_quat();
        let p = [p.w, p.x, p.y, p.z];
        for (i, row) in n.iter_mut().enumerate() {
            for (j, cell) in row.iter_mut().enumerate() {
                *cell += k * bound * p[i] * p[j];
            }
        }
        q = top_eigenvector(n).0;
    }
    RotationFit {
        rotation: Mat3::from_quat(Quat::new(q[0], q[1], q[2], q[3]).normalize()),
        margin,
    }
}

/// Eigenvector of the largest eigenvalue of a symmetric 4 × 4 matrix (cyclic Jacobi), and the
/// two largest eigenvalues.
fn top_eigenvector(mut a: [[f64; 4]; 4]) -> ([f64; 4], [f64; 2]) {
    let mut v = [[0.0f64; 4]; 4];
    for (i, row) in v.iter_mut().enumerate() {
        row[i] = 1.0;
    }
    for _sweep in 0..50 {
        let off: f64 = (0..4)
            .flat_map(|p| ((p + 1)..4).map(move |q| (p, q)))
            .map(|(p, q)| a[p][q] * a[p][q])
            .sum();
        let scale: f64 = (0..4).map(|i| a[i][i] * a[i][i]).sum::<f64>() + off;
        if off <= 1e-30 * scale.max(1e-300) {
            break;
        }
        for p in 0..4 {
            for q in (p + 1)..4 {
                if a[p][q].abs() < 1e-300 {
                    continue;
                }
                // The rotation in the (p, q) plane that zeroes a[p][q].
                let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let t = if theta == 0.0 { 1.0 } else { t };
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                for row in a.iter_mut() {
                    let (akp, akq) = (row[p], row[q]);
                    row[p] = c * akp - s * akq;
                    row[q] = s * akp + c * akq;
                }
                let (rp, rq) = (a[p], a[q]);
                for k in 0..4 {
                    a[p][k] = c * rp[k] - s * rq[k];
                    a[q][k] = s * rp[k] + c * rq[k];
                }
                for row in v.iter_mut() {
                    let (vp, vq) = (row[p], row[q]);
                    row[p] = c * vp - s * vq;
                    row[q] = s * vp + c * vq;
                }
            }
        }
    }
    let mut order = [0usize, 1, 2, 3];
    order.sort_by(|&i, &j| a[j][j].total_cmp(&a[i][i]));
    let best = order[0];
    (
        std::array::from_fn(|r| v[r][best]),
        [a[order[0]][order[0]], a[order[1]][order[1]]],
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

    fn points(rng: &mut SplitMix64, n: usize) -> Vec<[f64; 3]> {
        (0..n)
            .map(|_| std::array::from_fn(|_| rng.next_f64() * 2.0 - 1.0))
            .collect()
    }

    fn angle_between(a: &Mat3, b: &Mat3) -> f64 {
        let d = a.transpose().mul(b).to_axis_angle();
        (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
    }

    #[test]
    fn recovers_a_rotation_exactly_including_half_turns() {
        let mut rng = SplitMix64(3);
        for k in 0..200 {
            let a = points(&mut rng, 8);
            // Every 10th a half turn: the quaternion's w is 0, the hardest case for closed forms.
            let aa: [f64; 3] = if k % 10 == 0 {
                let u = points(&mut rng, 1)[0];
                let n = (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]).sqrt();
                u.map(|x| x / n * std::f64::consts::PI)
            } else {
                points(&mut rng, 1)[0].map(|x| x * 3.0)
            };
            let r = Mat3::from_axis_angle(aa);
            let b: Vec<[f64; 3]> = a.iter().map(|p| r.mul_vec(*p)).collect();
            let fit = best_fit_rotation(&a, &b, None);
            assert!(angle_between(&fit, &r) < 1e-9, "case {k}: {:?}", fit);
            assert!((fit.determinant() - 1.0).abs() < 1e-9);
        }
    }

    #[test]
    fn noise_moves_the_fit_a_little_and_weights_count() {
        let mut rng = SplitMix64(5);
        let a = points(&mut rng, 21);
        let r = Mat3::from_axis_angle([0.3, -1.2, 0.7]);
        let noisy: Vec<[f64; 3]> = a
            .iter()
            .map(|p| {
                let q = r.mul_vec(*p);
                std::array::from_fn(|i| q[i] + 0.02 * (rng.next_f64() - 0.5))
            })
            .collect();
        assert!(angle_between(&best_fit_rotation(&a, &noisy, None), &r) < 0.02);
        // One point far off: with weight 0 it is ignored.
        let mut bad = noisy.clone();
        bad[0] = [5.0, -5.0, 5.0];
        let mut w = vec![1.0; a.len()];
        w[0] = 0.0;
        assert!(angle_between(&best_fit_rotation(&a, &bad, Some(&w)), &r) < 0.02);
    }

    #[test]
    fn degenerate_input_is_a_rotation() {
        assert_eq!(best_fit_rotation(&[], &[], None), Mat3::IDENTITY);
        let line = [[0.0, 1.0, 0.0], [0.0, 2.0, 0.0]];
        let fit = best_fit_rotation(&line, &line, None);
        assert!((fit.determinant() - 1.0).abs() < 1e-9);
        assert!((fit.mul_vec([0.0, 1.0, 0.0])[1] - 1.0).abs() < 1e-9);
    }

    #[test]
    fn a_tie_goes_to_the_rotation_near_the_given_one_and_a_clear_fit_barely_moves() {
        let mut rng = SplitMix64(11);
        // Targets mirrored through the xy plane: no rotation carries them, and every turn about
        // x fits them equally (Horn's top eigenvalue is double). The one nearest `near` wins.
        let a = [[2.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        let b = [[2.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, -1.0]];
        for angle in [0.4, 2.5, -1.9] {
            let want = Mat3::from_axis_angle([angle, 0.0, 0.0]);
            // The previous frame 5° off the family.
            let prev = want.mul(&Mat3::from_axis_angle([0.0, 0.087, 0.0]));
            let got = fit_rotation(&a, &b, None, Some((&prev, 0.02))).rotation;
            assert!(
                angle_between(&got, &want) < 0.01,
                "{angle}: {}",
                angle_between(&got, &want)
            );
        }
        let r = Mat3::from_axis_angle([0.3, -0.5, 0.2]);
        // A clear fit: the pull moves it by a small fraction of its distance to `near`.
        let a = points(&mut rng, 12);
        let b: Vec<[f64; 3]> = a.iter().map(|p| r.mul_vec(*p)).collect();
        let prev = r.mul(&Mat3::from_axis_angle([0.0, 0.1, 0.0]));
        let got = fit_rotation(&a, &b, None, Some((&prev, 0.02))).rotation;
        let moved = angle_between(&got, &r);
        // The margin: 0 for the mirrored set (any turn about x fits), 2(σ₂+σ₃)/(σ₁+σ₂+σ₃) for
        // points a rotation carries exactly.
        let mirrored = [[2.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, -1.0]];
        let m = fit_rotation(
            &[[2.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            &mirrored,
            None,
            None,
        );
        assert!(m.margin.abs() < 1e-9, "{}", m.margin);
        let e = [[3.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 1.0]];
        let carried: Vec<[f64; 3]> = e.iter().map(|p| r.mul_vec(*p)).collect();
        let m = fit_rotation(&e, &carried, None, None);
        assert!((m.margin - 2.0 * 5.0 / 14.0).abs() < 1e-9, "{}", m.margin);
        assert!(
            moved > 0.0 && moved < 0.1 * 0.05,
            "moved {moved} rad of 0.1"
        );
        assert!(angle_between(&best_fit_rotation(&a, &b, None), &r) < 1e-9);
    }
}
