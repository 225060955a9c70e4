//! MPJPE — mean per-joint position error after pelvis alignment (SoulDance).
//!
//! Reference: `xjli360/SoulDance-Official:utils/metrics.py::calculate_mpjpe(gt, pred)`: subtract
//! each pose's pelvis (joint 0) from all of its joints, separately for ground truth and
//! prediction; per-joint Euclidean distance; mean over the joints → one error per pose (metres).
//! The reference returns the per-pose vector; callers average it (`.mean()`), see [`mpjpe_mean`].
//!
//! Input: `(T, J, 3)` flat C-order joint positions, any up axis (the metric is rotation-free in
//! that sense — but not invariant to a global rotation of one of the two inputs), `J ≥ 1`
//! (SoulDance uses 22 body joints; the first `J` joints of a 24-joint array are `[:, :J]`).
//!
//! Degenerate cases: `T = 0` gives an empty per-pose vector and [`mpjpe_mean`] returns `None`
//! (the reference's `.mean()` of an empty tensor is `NaN`); the metric has no division by a data
//! value, so frozen clips are fine.

/// Per-pose pelvis-aligned MPJPE of two `(T, J, 3)` arrays (flat, C order).
///
/// # Panics
/// If the two slices differ in length (the reference asserts equal shapes), `num_joints` is 0, or
/// the length is not a multiple of `num_joints * 3`.
pub fn mpjpe_per_pose(gt: &[f64], pred: &[f64], num_joints: usize) -> Vec<f64> {
    assert_eq!(
        gt.len(),
        pred.len(),
        "MPJPE: shape mismatch between gt and pred"
    );
    assert!(num_joints > 0, "MPJPE needs at least one joint");
    let frame_len = num_joints * 3;
    assert!(
        gt.len().is_multiple_of(frame_len),
        "joint array of {} values is not a whole number of {num_joints}x3 frames",
        gt.len()
    );
    gt.chunks_exact(frame_len)
        .zip(pred.chunks_exact(frame_len))
        .map(|(g, q)| {
            let sum: f64 = (0..num_joints)
                .map(|j| {
                    let mut s = 0.0;
                    for c in 0..3 {
                        let gj = g[j * 3 + c] - g[c];
                        let pj = q[j * 3 + c] - q[c];
                        let d = pj - gj;
                        s += d * d;
                    }
                    s.sqrt()
                })
                .sum();
            sum / num_joints as f64
        })
        .collect()
}

/// Mean of [`mpjpe_per_pose`] over all poses; `None` for zero poses (reference: `NaN`).
///
/// # Panics
/// As [`mpjpe_per_pose`].
pub fn mpjpe_mean(gt: &[f64], pred: &[f64], num_joints: usize) -> Option<f64> {
    let per_pose = mpjpe_per_pose(gt, pred, num_joints);
    if per_pose.is_empty() {
        return None;
    }
    Some(per_pose.iter().sum::<f64>() / per_pose.len() as f64)
}
