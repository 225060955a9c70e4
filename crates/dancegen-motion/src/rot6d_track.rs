//! Decoding a generated track of 6D rotations (one joint over time) where the network's rows
//! lose their length.
//!
//! Training data hold proper 6D rotations: two orthonormal rows, each of length 1. A network
//! that regresses 6D and is unsure between two orientations far apart (a follower half-way
//! through a turn in the duet model) can move its output along the straight line between them,
//! through the origin: the rows shrink to a tenth of their length and Gram–Schmidt
//! ([`Mat3::from_6d`]) turns their sign change into a 90–150° jump in one or two frames.
//! Measured on a held-out duet follower (leader `61_13_scaled`, seed 0, no post-processing):
//! the root's first row shrinks from 0.96 to 0.11 and back over six frames while the decoded
//! pelvis turns 89° and then 64° in two frames (models/reactdance-small/MODEL_CARD.md). A row
//! that short no longer says which way it points.
//!
//! The decoding keeps every frame whose rows are long enough as Gram–Schmidt gives it and
//! bridges each interior run of short-row frames by the spherical interpolation between the
//! last and the next well-defined frame: the turn the network made is kept, spread over the
//! frames in which it made it instead of the frame in which its sign flipped. A run at the
//! start or the end of the track has one side only and stays as Gram–Schmidt gives it. So does
//! a run holding a non-finite value: that is a broken output for the caller to report, not a
//! turn to smooth over.
//! Callers log the number of bridged frames: a model that needs many should be fixed.

use std::ops::Range;

use crate::rotation::{Mat3, Quat};
use crate::vec3::{dot, norm};

/// Shortest row (the first row, or the second row's part orthogonal to the first) of a
/// well-defined 6D rotation. Gram–Schmidt divides by this length, so below one half an error
/// in the row turns the rotation by more than twice as much as in a unit row. In the held-out
/// duet follower of the module docs, the root's first row was 0.64–0.97 long on the 20
/// frames around the flip and 0.11–0.41 in its three middle frames.
pub const MIN_ROW_LENGTH: f64 = 0.5;

/// Whether the 6D rotation `d` (pytorch3d's two rows) has both rows long enough (false for
/// non-finite values).
pub fn well_defined(d: &[f64; 6]) -> bool {
    let (a, b) = ([d[0], d[1], d[2]], [d[3], d[4], d[5]]);
    let na = norm(a);
    if na < MIN_ROW_LENGTH {
        return false;
    }
    let p = dot(a, b) / na;
    let ortho = (dot(b, b) - p * p).max(0.0).sqrt();
    ortho >= MIN_ROW_LENGTH
}

/// Interior runs of ill-defined, finite frames of `track`, each with a well-defined frame on
/// either side: the frames [`decode_6d_track`] bridges.
fn bridgeable_runs(track: &[[f64; 6]]) -> Vec<Range<usize>> {
    let mut runs = Vec::new();
    let mut i = 0;
    while i < track.len() {
        if well_defined(&track[i]) {
            i += 1;
            continue;
        }
        let start = i;
        while i < track.len() && !well_defined(&track[i]) {
            i += 1;
        }
        let finite = track[start..i].iter().flatten().all(|v| v.is_finite());
        if start > 0 && i < track.len() && finite {
            runs.push(start..i);
        }
    }
    runs
}

/// The rotations of a track of 6D values, with interior runs of ill-defined frames bridged (see
/// the module docs), and the number of frames bridged.
pub fn decode_6d_track(track: &[[f64; 6]]) -> (Vec<Mat3>, usize) {
    let mut rot: Vec<Mat3> = track.iter().map(Mat3::from_6d).collect();
    let mut bridged = 0;
    for run in bridgeable_runs(track) {
        let (before, after) = (run.start - 1, run.end);
        let (qa, qb) = (rot[before].to_quat(), rot[after].to_quat());
        for k in run {
            let s = (k - before) as f64 / (after - before) as f64;
            rot[k] = Mat3::from_quat(Quat::slerp(qa, qb, s));
            bridged += 1;
        }
    }
    (rot, bridged)
}

/// [`decode_6d_track`] for a track that stays in 6D (a pipeline with more steps on the raw
/// values): each bridged frame is rewritten as the 6D of its bridged rotation (unit rows), every
/// other frame is left exactly as it was. Returns the number of frames rewritten.
pub fn bridge_6d_track(track: &mut [[f64; 6]]) -> usize {
    let runs = bridgeable_runs(track);
    if runs.is_empty() {
        return 0;
    }
    let (rot, bridged) = decode_6d_track(track);
    for k in runs.into_iter().flatten() {
        track[k] = rot[k].to_6d();
    }
    bridged
}

#[cfg(test)]
mod tests {
    use super::*;

    fn angle_deg(a: &Mat3, b: &Mat3) -> f64 {
        let r = a.transpose().mul(b);
        let tr = r.0[0][0] + r.0[1][1] + r.0[2][2];
        ((tr - 1.0) / 2.0).clamp(-1.0, 1.0).acos().to_degrees()
    }

    fn yaw(deg: f64) -> Mat3 {
        Mat3::from_axis_rotation(1, deg.to_radians())
    }

    /// A 170° turn regressed as the straight line between its ends over 11 frames: Gram–Schmidt
    /// jumps in one frame, the bridged track turns evenly across the frames with short rows.
    #[test]
    fn a_turn_through_the_origin_is_spread_over_its_frames() {
        let (a, b) = (yaw(0.0).to_6d(), yaw(170.0).to_6d());
        let n = 11;
        let track: Vec<[f64; 6]> = (0..n)
            .map(|k| {
                let s = k as f64 / (n - 1) as f64;
                std::array::from_fn(|c| (1.0 - s) * a[c] + s * b[c])
            })
            .collect();
        let raw: Vec<Mat3> = track.iter().map(Mat3::from_6d).collect();
        let raw_max = raw
            .windows(2)
            .map(|w| angle_deg(&w[0], &w[1]))
            .fold(0.0, f64::max);
        assert!(raw_max > 60.0, "Gram–Schmidt jumps: {raw_max}");
        let (rot, bridged) = decode_6d_track(&track);
        assert!(bridged > 0 && bridged < n - 2, "bridged {bridged}");
        let steps: Vec<f64> = rot.windows(2).map(|w| angle_deg(&w[0], &w[1])).collect();
        let max = steps.iter().copied().fold(0.0, f64::max);
        assert!(max < raw_max / 2.0, "largest step {max} against {raw_max}");
        // The ends and the whole turn are kept.
        assert!(angle_deg(&rot[0], &yaw(0.0)) < 1e-6);
        assert!(angle_deg(&rot[n - 1], &yaw(170.0)) < 1e-6);
    }

    /// Unit rows are never touched; an ill-defined run at either end has one side only and
    /// stays as Gram–Schmidt gives it.
    #[test]
    fn proper_rotations_and_edge_runs_are_kept() {
        let track: Vec<[f64; 6]> = (0..30).map(|k| yaw(24.0 * k as f64).to_6d()).collect();
        let (rot, bridged) = decode_6d_track(&track);
        assert_eq!(bridged, 0);
        for (r, d) in rot.iter().zip(&track) {
            assert!(angle_deg(r, &Mat3::from_6d(d)) < 1e-9);
        }
        let mut edges = track.clone();
        edges[0] = [0.1, 0.0, 0.0, 0.0, 1.0, 0.0];
        edges[29] = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
        let (rot, bridged) = decode_6d_track(&edges);
        assert_eq!(bridged, 0);
        assert!(angle_deg(&rot[0], &Mat3::from_6d(&edges[0])) < 1e-9);
        assert!(!well_defined(&edges[29]));
        assert!(well_defined(&track[5]));
    }

    /// A non-finite frame is not smoothed into a rotation: it stays broken, so the caller's
    /// check for non-finite output still sees it.
    #[test]
    fn non_finite_frames_are_not_bridged() {
        let mut track: Vec<[f64; 6]> = (0..10).map(|k| yaw(10.0 * k as f64).to_6d()).collect();
        track[4] = [f64::NAN; 6];
        assert!(!well_defined(&track[4]));
        let (rot, bridged) = decode_6d_track(&track);
        assert_eq!(bridged, 0);
        assert!(rot[4].0.iter().flatten().any(|v| !v.is_finite()));
    }

    /// Bridging in place rewrites exactly the frames decoding bridges, as proper 6D of the
    /// decoded rotations, and leaves every other value untouched.
    #[test]
    fn bridging_in_place_rewrites_only_the_bridged_frames() {
        let (a, b) = (yaw(10.0).to_6d(), yaw(160.0).to_6d());
        let n = 9;
        let mut track: Vec<[f64; 6]> = (0..n)
            .map(|k| {
                let s = k as f64 / (n - 1) as f64;
                std::array::from_fn(|i| a[i] * (1.0 - s) + b[i] * s)
            })
            .collect();
        // A slightly long but well-defined row stays as it is (not renormalised).
        track[0] = a.map(|v| v * 1.2);
        let before = track.clone();
        let (rot, count) = decode_6d_track(&before);
        assert!(count > 0);
        assert_eq!(bridge_6d_track(&mut track), count);
        for k in 0..n {
            if well_defined(&before[k]) {
                assert_eq!(track[k], before[k], "frame {k} changed");
            } else {
                assert!(well_defined(&track[k]), "frame {k} still ill-defined");
                assert!(angle_deg(&Mat3::from_6d(&track[k]), &rot[k]) < 1e-9);
            }
        }
        assert_eq!(
            bridge_6d_track(&mut track),
            0,
            "a bridged track needs no more"
        );
    }
}
