//! FBX's Euler angles: `Lcl Rotation = (x, y, z)` degrees with `RotationOrder` XYZ
//! (`eEulerXYZ` = 0, FBX SDK `EFbxRotationOrder`) means the X rotation is applied first, i.e.
//! `R = Rz(z) · Ry(y) · Rx(x)` acting on column vectors ([`dancegen_motion::conventions`]) — in
//! [`Mat3::from_euler`]'s notation the order `"ZYX"` with angles `[z, y, x]`.
//!
//! Curves interpolate each angle linearly between keys, so consecutive keys must not jump by
//! ±360° (the joint would spin the long way round) nor switch between the two Euler triples of
//! one rotation. [`continuous_euler_xyz`] picks, per frame, the triple closest to the previous
//! frame's.

use dancegen_motion::rotation::Mat3;
use std::f64::consts::{PI, TAU};

/// `(x, y, z)` radians with `Rz(z) · Ry(y) · Rx(x) = m` (`y` in `[−π/2, π/2]`).
pub(crate) fn euler_xyz(m: &Mat3) -> [f64; 3] {
    let [z, y, x] = m.to_euler("ZYX").expect("\"ZYX\" is a valid Euler order");
    [x, y, z]
}

/// The Euler triple of `e`'s rotation closest to `prev`: either `e` or its twin
/// `(x + π, π − y, z + π)` (the same matrix), each angle shifted by whole turns.
pub(crate) fn closest_euler(e: [f64; 3], prev: [f64; 3]) -> [f64; 3] {
    let near = |a: f64, to: f64| a + TAU * ((to - a) / TAU).round();
    let a = [0, 1, 2].map(|k| near(e[k], prev[k]));
    let twin = [e[0] + PI, PI - e[1], e[2] + PI];
    let b = [0, 1, 2].map(|k| near(twin[k], prev[k]));
    let dist = |v: &[f64; 3]| (0..3).map(|k| (v[k] - prev[k]).powi(2)).sum::<f64>();
    if dist(&b) < dist(&a) { b } else { a }
}

/// Euler angles in degrees for a sequence of rotations, continuous from one to the next.
pub(crate) fn continuous_euler_xyz_degrees(
    rotations: impl IntoIterator<Item = Mat3>,
) -> Vec<[f64; 3]> {
    let mut out: Vec<[f64; 3]> = Vec::new();
    let mut prev: Option<[f64; 3]> = None;
    for m in rotations {
        let e = euler_xyz(&m);
        let e = match prev {
            Some(p) => closest_euler(e, p),
            None => e,
        };
        prev = Some(e);
        out.push(e.map(f64::to_degrees));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn from_xyz(e: [f64; 3]) -> Mat3 {
        Mat3::from_euler("ZYX", [e[2], e[1], e[0]]).unwrap()
    }

    fn max_diff(a: &Mat3, b: &Mat3) -> f64 {
        (0..3)
            .flat_map(|i| (0..3).map(move |j| (i, j)))
            .map(|(i, j)| (a.0[i][j] - b.0[i][j]).abs())
            .fold(0.0, f64::max)
    }

    #[test]
    fn xyz_order_applies_x_first() {
        // x = 90° then z = 90°: +Y goes to +Z under Rx, and +Z stays put under Rz.
        let m = from_xyz([PI / 2.0, 0.0, PI / 2.0]);
        let v = m.mul_vec([0.0, 1.0, 0.0]);
        assert!((v[2] - 1.0).abs() < 1e-12, "{v:?}");
        // The same angles applied z first would send +Y to −X and then leave it there.
        let e = euler_xyz(&m);
        assert!((e[0] - PI / 2.0).abs() < 1e-12 && (e[2] - PI / 2.0).abs() < 1e-12);
    }

    #[test]
    fn round_trips_including_gimbal_lock_and_half_turns() {
        let cases = [
            [0.3, -0.7, 1.1],
            [PI - 1e-3, 0.2, -PI + 1e-3],
            [0.4, PI / 2.0, -0.3],
            [0.4, -PI / 2.0, 0.9],
            [0.0, PI / 2.0 - 1e-7, 0.0],
            [3.0, 1.5, -3.1],
        ];
        for c in cases {
            let m = from_xyz(c);
            let e = euler_xyz(&m);
            assert!(max_diff(&from_xyz(e), &m) < 1e-8, "{c:?} -> {e:?}");
            let twin = [e[0] + PI, PI - e[1], e[2] + PI];
            assert!(max_diff(&from_xyz(twin), &m) < 1e-8, "twin of {c:?}");
        }
    }

    #[test]
    fn sequences_do_not_jump() {
        // A rotation about a tilted axis sweeping two full turns: raw Euler angles wrap at
        // ±180°, the continuous ones must move by less than 30° per step.
        let axis = [0.3f64, 0.8, -0.52];
        let n = (axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]).sqrt();
        let mats: Vec<Mat3> = (0..200)
            .map(|i| {
                let a = 4.0 * PI * i as f64 / 199.0;
                Mat3::from_axis_angle(axis.map(|v| v / n * a))
            })
            .collect();
        let e = continuous_euler_xyz_degrees(mats.iter().copied());
        for (k, w) in e.windows(2).enumerate() {
            let step = (0..3)
                .map(|c| (w[1][c] - w[0][c]).abs())
                .fold(0.0, f64::max);
            assert!(step < 30.0, "step {k}: {:?} -> {:?}", w[0], w[1]);
        }
        for (m, d) in mats.iter().zip(&e) {
            assert!(max_diff(&from_xyz(d.map(f64::to_radians)), m) < 1e-9);
        }
    }
}
