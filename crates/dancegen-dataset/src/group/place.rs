//! Putting a member's motion on its formation path (group.md §4.6): the source root is split
//! into a low-pass path (≈ 0.5 Hz) and a sway clamped to ±0.3 m; the new root is the planned
//! path plus the sway. A solo dancer is turned to face the audience (±15°); a couple keeps its
//! partners' real offsets about their common low-pass midpoint, turned as one so the partners
//! stand side by side across the stage.

use dancegen_motion::repr::duet::heading;
use dancegen_motion::repr::motion::SmplMotion;
use dancegen_motion::rotation::{Mat3, wrap_angle};
use dancegen_motion::smoothing::{Ends, gaussian_smooth};
use dancegen_refine::formation::StagePos;

/// Gaussian σ (frames at 30 fps) of the low-pass path: a Gaussian's half-power frequency is
/// `√ln2 / (2π σ)`, so σ = 8 frames (0.27 s) puts it at 0.5 Hz (group.md §4.6).
pub(crate) const LOW_PASS_SIGMA_FRAMES: f64 = 8.0;
/// Sway clamp (group.md §4.6: ±0.3 m).
pub(crate) const MAX_SWAY_M: f64 = 0.3;
/// Facing jitter about the audience direction (group.md §4.3: ±15°).
pub(crate) const FACING_JITTER_RAD: f64 = std::f64::consts::PI / 12.0;

/// Root `[x, z]` of every frame.
pub(crate) fn root_xz(m: &SmplMotion) -> Vec<StagePos> {
    m.trans
        .chunks_exact(3)
        .map(|p| [f64::from(p[0]), f64::from(p[2])])
        .collect()
}

/// The low-pass path of `xz` (σ = [`LOW_PASS_SIGMA_FRAMES`], ends held).
pub(crate) fn low_pass(xz: &[StagePos]) -> Vec<StagePos> {
    let x: Vec<f64> = xz.iter().map(|p| p[0]).collect();
    let z: Vec<f64> = xz.iter().map(|p| p[1]).collect();
    let (x, z) = (
        gaussian_smooth(&x, LOW_PASS_SIGMA_FRAMES, Ends::Hold),
        gaussian_smooth(&z, LOW_PASS_SIGMA_FRAMES, Ends::Hold),
    );
    x.into_iter().zip(z).map(|(x, z)| [x, z]).collect()
}

/// `v` turned by yaw `angle` (the rotation about +Y that [`yawed`] applies to the body).
pub(crate) fn rotate_xz(v: StagePos, angle: f64) -> StagePos {
    let (s, c) = angle.sin_cos();
    [c * v[0] + s * v[1], -s * v[0] + c * v[1]]
}

/// Circular mean of the root's heading (yaw of its forward axis, 0 = facing +Z).
pub(crate) fn mean_heading(m: &SmplMotion) -> f64 {
    let (mut s, mut c) = (0.0, 0.0);
    for f in 0..m.frames() {
        let h = heading(&Mat3::from_axis_angle(m.joint_aa(f, 0).map(f64::from)));
        s += h.sin();
        c += h.cos();
    }
    s.atan2(c)
}

/// `m` turned about the vertical axis by `angle`: root orientation and root path.
pub(crate) fn yawed(m: &SmplMotion, angle: f64) -> SmplMotion {
    let r = Mat3::from_axis_rotation(1, angle);
    let mut out = m.clone();
    let frames = m.frames();
    let pose_dims = out.poses.len() / frames.max(1);
    for f in 0..frames {
        let root = Mat3::from_axis_angle(m.joint_aa(f, 0).map(f64::from));
        let aa = r.mul(&root).to_axis_angle();
        for (dst, v) in out.poses[f * pose_dims..f * pose_dims + 3]
            .iter_mut()
            .zip(aa)
        {
            *dst = v as f32;
        }
        let p = &mut out.trans[f * 3..f * 3 + 3];
        let xz = rotate_xz([f64::from(p[0]), f64::from(p[2])], angle);
        p[0] = xz[0] as f32;
        p[2] = xz[1] as f32;
    }
    out
}

fn clamp_norm(v: StagePos, max: f64) -> StagePos {
    let n = v[0].hypot(v[1]);
    if n > max {
        [v[0] * max / n, v[1] * max / n]
    } else {
        v
    }
}

fn set_xz(m: &mut SmplMotion, xz: &[StagePos]) {
    for (p, q) in m.trans.chunks_exact_mut(3).zip(xz) {
        p[0] = q[0] as f32;
        p[2] = q[1] as f32;
    }
}

/// The yaw that turns a solo dancer to face the audience, with `jitter` (radians) added.
pub(crate) fn solo_yaw(m: &SmplMotion, jitter: f64) -> f64 {
    wrap_angle(jitter - mean_heading(m))
}

/// The yaw that turns a couple so that the mean line from `a` to `b` runs across the stage
/// (towards +x or −x, whichever is the smaller turn), with `jitter` added.
pub(crate) fn couple_yaw(a: &SmplMotion, b: &SmplMotion, jitter: f64) -> f64 {
    let (pa, pb) = (root_xz(a), root_xz(b));
    let n = pa.len().min(pb.len()).max(1) as f64;
    let dx: f64 = pa.iter().zip(&pb).map(|(p, q)| q[0] - p[0]).sum::<f64>() / n;
    let dz: f64 = pa.iter().zip(&pb).map(|(p, q)| q[1] - p[1]).sum::<f64>() / n;
    // rotate_xz turns direction angle atan2(z, x) by −angle.
    let dir = dz.atan2(dx);
    let to_plus = dir;
    let to_minus = wrap_angle(dir - std::f64::consts::PI);
    let turn = if to_plus.abs() <= to_minus.abs() {
        to_plus
    } else {
        to_minus
    };
    wrap_angle(turn + jitter)
}

/// A solo dancer on `path` (one position per frame), turned by `yaw`.
pub(crate) fn place_solo(m: &SmplMotion, path: &[StagePos], yaw: f64) -> SmplMotion {
    let mut out = yawed(m, yaw);
    let xz = root_xz(&out);
    let lp = low_pass(&xz);
    let placed: Vec<StagePos> = (0..out.frames())
        .map(|t| {
            let sway = clamp_norm([xz[t][0] - lp[t][0], xz[t][1] - lp[t][1]], MAX_SWAY_M);
            [path[t][0] + sway[0], path[t][1] + sway[1]]
        })
        .collect();
    set_xz(&mut out, &placed);
    out
}

/// A couple on `path` (their midpoint's), turned by `yaw`, partners' offsets about their
/// low-pass midpoint kept as recorded (not clamped: that is their real relative placement).
pub(crate) fn place_couple(
    a: &SmplMotion,
    b: &SmplMotion,
    path: &[StagePos],
    yaw: f64,
) -> (SmplMotion, SmplMotion) {
    let (mut ya, mut yb) = (yawed(a, yaw), yawed(b, yaw));
    let (pa, pb) = (root_xz(&ya), root_xz(&yb));
    let mid: Vec<StagePos> = pa
        .iter()
        .zip(&pb)
        .map(|(p, q)| [(p[0] + q[0]) / 2.0, (p[1] + q[1]) / 2.0])
        .collect();
    let lp = low_pass(&mid);
    let put = |p: &[StagePos]| -> Vec<StagePos> {
        (0..p.len())
            .map(|t| {
                [
                    path[t][0] + p[t][0] - lp[t][0],
                    path[t][1] + p[t][1] - lp[t][1],
                ]
            })
            .collect()
    };
    set_xz(&mut ya, &put(&pa));
    set_xz(&mut yb, &put(&pb));
    (ya, yb)
}

/// Mean horizontal speed (m/frame) at which a planted foot would slide if a source whose
/// low-pass path is `lp` (unturned) were put on `path` after turning it by `yaw`: the planned
/// velocity minus the source's own travel (group.md §4.6: retrieve segments whose travel
/// matches the path rather than sliding a clip).
pub(crate) fn travel_mismatch(path: &[StagePos], lp: &[StagePos], yaw: f64) -> f64 {
    let n = path.len().min(lp.len());
    if n < 2 {
        return 0.0;
    }
    let mut sum = 0.0;
    for t in 1..n {
        let v = rotate_xz([lp[t][0] - lp[t - 1][0], lp[t][1] - lp[t - 1][1]], yaw);
        let p = [path[t][0] - path[t - 1][0], path[t][1] - path[t - 1][1]];
        sum += (p[0] - v[0]).hypot(p[1] - v[1]);
    }
    sum / (n - 1) as f64
}

#[cfg(test)]
mod tests {
    use super::*;
    use dancegen_motion::repr::motion::POSE_DIMS;

    /// A motion turned by `h` radians walking along its own forward axis.
    fn walker(h: f64, frames: usize) -> SmplMotion {
        let mut poses = vec![0.0f32; frames * POSE_DIMS];
        let mut trans = vec![0.0f32; frames * 3];
        for f in 0..frames {
            poses[f * POSE_DIMS + 1] = h as f32;
            trans[f * 3] = (0.01 * f as f64 * h.sin()) as f32;
            trans[f * 3 + 1] = 0.9;
            trans[f * 3 + 2] = (0.01 * f as f64 * h.cos()) as f32;
        }
        SmplMotion::new(30.0, poses, trans).unwrap()
    }

    #[test]
    fn a_solo_dancer_ends_up_facing_the_audience_on_its_path() {
        let m = walker(1.2, 60);
        let yaw = solo_yaw(&m, 0.0);
        assert!((mean_heading(&yawed(&m, yaw))).abs() < 1e-6);
        let path = vec![[1.0, -0.5]; 60];
        let placed = place_solo(&m, &path, yaw);
        for (t, p) in root_xz(&placed).iter().enumerate() {
            assert!(
                (p[0] - 1.0).hypot(p[1] + 0.5) <= MAX_SWAY_M + 1e-6,
                "frame {t}"
            );
        }
        // The walk is steady, so after low-pass removal only the held ends sway a little.
        assert!((root_xz(&placed)[30][0] - 1.0).abs() < 0.01);
    }

    #[test]
    fn travel_mismatch_is_zero_when_the_path_matches_the_turned_travel() {
        let m = walker(0.7, 90);
        let yaw = solo_yaw(&m, 0.0);
        let lp = low_pass(&root_xz(&m));
        // After the turn the walker goes straight towards +z at 1 cm per frame.
        let path: Vec<StagePos> = (0..90).map(|f| [0.0, 0.01 * f as f64]).collect();
        assert!(travel_mismatch(&path[10..80], &lp[10..80], yaw) < 1e-3);
        let still = vec![[0.0, 0.0]; 90];
        assert!((travel_mismatch(&still[10..80], &lp[10..80], yaw) - 0.01).abs() < 1e-3);
    }

    #[test]
    fn a_couple_keeps_its_partner_distance_and_stands_across_the_stage() {
        let mut a = walker(0.0, 30);
        let mut b = walker(0.0, 30);
        for f in 0..30 {
            a.trans[f * 3] = 0.3;
            a.trans[f * 3 + 2] = 0.2;
            b.trans[f * 3] = 0.3;
            b.trans[f * 3 + 2] = 1.2;
        }
        let yaw = couple_yaw(&a, &b, 0.0);
        let path = vec![[2.0, 0.0]; 30];
        let (pa, pb) = place_couple(&a, &b, &path, yaw);
        let (qa, qb) = (root_xz(&pa)[10], root_xz(&pb)[10]);
        assert!(((qa[0] - qb[0]).hypot(qa[1] - qb[1]) - 1.0).abs() < 1e-5);
        assert!(
            (qa[1] - qb[1]).abs() < 1e-5,
            "across the stage: {qa:?} {qb:?}"
        );
        assert!(((qa[0] + qb[0]) / 2.0 - 2.0).abs() < 1e-5);
    }
}
