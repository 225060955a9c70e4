//! Our vocabulary of hand poses for the synthetic finger motion (issue 19: no real finger dance
//! data can be had here). Each pose is a set of joint flexions within anatomical ranges, written
//! down here rather than taken from an asset, so anyone can check and change it.
//!
//! A finger has three flexion joints (SMPL-H `*1` = knuckle / MCP, `*2` = PIP, `*3` = DIP) and
//! one spread angle at the knuckle. The ranges (degrees) are the usual active ranges of motion:
//! MCP 0–90, PIP 0–100, DIP 0–70 (DIP follows PIP, about 2/3 of it, when not forced), thumb CMC
//! 0–45, MCP 0–55, IP 0–80. Spread is ±15° at the knuckle.
//!
//! Axes on our SMPL-H skeleton (`Skeleton::smplh52_approx`, Y-up, T-pose): the left hand points
//! +X with the palm down (−Y). Flexion toward the palm is a negative turn about +Z; spreading
//! the index away from the middle finger (toward +Z) is a negative turn about +Y. The thumb
//! flexes about its own tilted axis ([`thumb_axis`]), which carries its tip across the palm. The
//! right hand is the mirror image: axis-angle `(x, y, z)` becomes `(x, −y, −z)`.

/// Fingers in SMPL-H order within a hand: index, middle, pinky, ring, thumb.
pub const FINGERS: usize = 5;
/// Joints per finger.
pub const SEGMENTS: usize = 3;
/// Finger joints per hand.
pub const HAND_JOINTS: usize = FINGERS * SEGMENTS;
const THUMB: usize = 4;

/// Upper ends of the flexion ranges (degrees), per segment: fingers, thumb.
const FINGER_MAX_DEG: [f32; 3] = [90.0, 100.0, 70.0];
const THUMB_MAX_DEG: [f32; 3] = [45.0, 55.0, 80.0];
/// Largest knuckle spread (degrees).
const SPREAD_MAX_DEG: f32 = 15.0;

/// One hand shape: per finger (SMPL-H order) the flexion of its three joints as a fraction of
/// their range, and the knuckle spread as a fraction of ±15° (positive = away from the middle
/// finger; unused for the middle finger and the thumb).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HandPose {
    pub name: &'static str,
    pub flex: [[f32; 3]; FINGERS],
    pub spread: [f32; FINGERS],
}

const fn finger(mcp: f32, pip: f32, dip: f32) -> [f32; 3] {
    [mcp, pip, dip]
}

/// The vocabulary. The order is the pose id used in data labels.
pub const POSES: [HandPose; 10] = [
    // A hand at rest: the natural cascade, each finger a little more flexed toward the pinky.
    HandPose {
        name: "relaxed",
        flex: [
            finger(0.20, 0.25, 0.17),
            finger(0.25, 0.30, 0.20),
            finger(0.35, 0.40, 0.27),
            finger(0.30, 0.35, 0.23),
            finger(0.20, 0.15, 0.20),
        ],
        spread: [0.1, 0.0, 0.1, 0.05, 0.0],
    },
    // Flat, fingers together: a "blade" hand, typical of extended salsa arms.
    HandPose {
        name: "flat",
        flex: [
            finger(0.02, 0.03, 0.02),
            finger(0.02, 0.03, 0.02),
            finger(0.03, 0.04, 0.03),
            finger(0.02, 0.04, 0.03),
            finger(0.10, 0.05, 0.05),
        ],
        spread: [0.0; FINGERS],
    },
    // Jazz hands: fully open and spread.
    HandPose {
        name: "spread",
        flex: [
            finger(0.0, 0.0, 0.0),
            finger(0.0, 0.0, 0.0),
            finger(0.0, 0.0, 0.0),
            finger(0.0, 0.0, 0.0),
            finger(0.0, 0.0, 0.0),
        ],
        spread: [1.0, 0.0, 1.0, 0.5, 0.0],
    },
    // Fist, thumb wrapped over the middle phalanges.
    HandPose {
        name: "fist",
        flex: [
            finger(0.90, 1.00, 0.75),
            finger(0.90, 1.00, 0.75),
            finger(0.90, 1.00, 0.75),
            finger(0.90, 1.00, 0.75),
            finger(0.80, 0.60, 0.40),
        ],
        spread: [0.0; FINGERS],
    },
    // Pointing with the index, the others in a loose fist.
    HandPose {
        name: "point",
        flex: [
            finger(0.0, 0.02, 0.02),
            finger(0.85, 0.95, 0.65),
            finger(0.85, 0.95, 0.65),
            finger(0.85, 0.95, 0.65),
            finger(0.65, 0.50, 0.35),
        ],
        spread: [0.0; FINGERS],
    },
    // Index and middle extended and apart.
    HandPose {
        name: "peace",
        flex: [
            finger(0.0, 0.02, 0.02),
            finger(0.0, 0.02, 0.02),
            finger(0.85, 0.95, 0.65),
            finger(0.85, 0.95, 0.65),
            finger(0.70, 0.50, 0.35),
        ],
        spread: [0.8, 0.0, 0.0, 0.0, 0.0],
    },
    // Thumb and index meet; the other fingers loosely open.
    HandPose {
        name: "pinch",
        flex: [
            finger(0.50, 0.55, 0.35),
            finger(0.15, 0.20, 0.13),
            finger(0.25, 0.30, 0.20),
            finger(0.20, 0.25, 0.17),
            finger(0.70, 0.35, 0.25),
        ],
        spread: [0.0, 0.0, 0.3, 0.1, 0.0],
    },
    // Cupped: every joint half flexed, as if holding a ball.
    HandPose {
        name: "cupped",
        flex: [
            finger(0.40, 0.45, 0.30),
            finger(0.40, 0.45, 0.30),
            finger(0.45, 0.50, 0.33),
            finger(0.42, 0.48, 0.32),
            finger(0.40, 0.30, 0.30),
        ],
        spread: [0.2, 0.0, 0.2, 0.1, 0.0],
    },
    // Claw: knuckles straight, PIP and DIP bent hard.
    HandPose {
        name: "claw",
        flex: [
            finger(0.10, 0.80, 0.85),
            finger(0.10, 0.80, 0.85),
            finger(0.10, 0.80, 0.85),
            finger(0.10, 0.80, 0.85),
            finger(0.30, 0.40, 0.60),
        ],
        spread: [0.6, 0.0, 0.6, 0.3, 0.0],
    },
    // The ballet hand: middle finger lowered toward the thumb, index and pinky lifted.
    HandPose {
        name: "graceful",
        flex: [
            finger(0.10, 0.15, 0.10),
            finger(0.40, 0.35, 0.23),
            finger(0.05, 0.10, 0.07),
            finger(0.25, 0.25, 0.17),
            finger(0.45, 0.20, 0.15),
        ],
        spread: [0.3, 0.0, 0.5, 0.2, 0.0],
    },
];

/// Index of a pose by name.
pub fn pose_id(name: &str) -> Option<usize> {
    POSES.iter().position(|p| p.name == name)
}

/// The left thumb's flexion axis (unit): it turns the thumb's rest direction (out, down and
/// forward, `(0.60, −0.30, 0.74)` on our skeleton) toward the palm's centre under the middle
/// knuckle (`(0.40, −0.55, −0.73)`), so flexion carries the tip across the palm.
pub fn thumb_axis() -> [f32; 3] {
    let u = [0.60f32, -0.30, 0.74];
    let v = [0.40f32, -0.55, -0.73];
    let c = [
        u[1] * v[2] - u[2] * v[1],
        u[2] * v[0] - u[0] * v[2],
        u[0] * v[1] - u[1] * v[0],
    ];
    let n = (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt();
    c.map(|x| x / n)
}

/// Local axis-angle `(15, 3)` of the left hand's finger joints for flexion fractions `flex` and
/// spread fractions `spread` (values outside [0, 1] and [−1, 1] are clamped to the ranges).
pub fn left_hand_axis_angles(
    flex: &[[f32; 3]; FINGERS],
    spread: &[f32; FINGERS],
) -> [[f32; 3]; HAND_JOINTS] {
    let mut out = [[0.0f32; 3]; HAND_JOINTS];
    let thumb = thumb_axis();
    for f in 0..FINGERS {
        for s in 0..SEGMENTS {
            let frac = flex[f][s].clamp(0.0, 1.0);
            let j = f * SEGMENTS + s;
            if f == THUMB {
                let a = (frac * THUMB_MAX_DEG[s]).to_radians();
                out[j] = thumb.map(|x| x * a);
            } else {
                let bend = -(frac * FINGER_MAX_DEG[s]).to_radians();
                // Spread at the knuckle only: the index fans toward +Z (negative about Y), the
                // ring and pinky toward −Z.
                let side = match f {
                    0 => -1.0,
                    2 | 3 => 1.0,
                    _ => 0.0,
                };
                let fan = if s == 0 {
                    side * (spread[f].clamp(-1.0, 1.0) * SPREAD_MAX_DEG).to_radians()
                } else {
                    0.0
                };
                // Two small turns about orthogonal axes: combined as one axis-angle vector,
                // exact to second order, which is well inside the accuracy of the poses.
                out[j] = [0.0, fan, bend];
            }
        }
    }
    out
}

/// The right hand's axis-angles: the mirror image of the left's (`(x, y, z)` → `(x, −y, −z)`).
pub fn mirror_hand(left: &[[f32; 3]; HAND_JOINTS]) -> [[f32; 3]; HAND_JOINTS] {
    left.map(|a| [a[0], -a[1], -a[2]])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn poses_are_inside_the_ranges_and_named_once() {
        for (i, p) in POSES.iter().enumerate() {
            assert_eq!(pose_id(p.name), Some(i));
            for f in 0..FINGERS {
                for s in 0..SEGMENTS {
                    assert!((0.0..=1.0).contains(&p.flex[f][s]), "{} {f} {s}", p.name);
                }
                assert!((-1.0..=1.0).contains(&p.spread[f]), "{}", p.name);
            }
        }
        // The fist is the most flexed pose and the spread hand the least.
        let total = |p: &HandPose| p.flex.iter().flatten().sum::<f32>();
        let (fist, spread) = (
            &POSES[pose_id("fist").unwrap()],
            &POSES[pose_id("spread").unwrap()],
        );
        assert!(
            POSES
                .iter()
                .all(|p| total(p) <= total(fist) && total(p) >= total(spread))
        );
    }

    #[test]
    fn flexion_bends_toward_the_palm() {
        // Rotating the index's direction (+X) by its knuckle's flexion moves it toward −Y.
        let fist = &POSES[pose_id("fist").unwrap()];
        let aa = left_hand_axis_angles(&fist.flex, &fist.spread);
        let r = dancegen_motion::Mat3::from_axis_angle(aa[0].map(|v| v as f64));
        let d = r.mul_vec([1.0, 0.0, 0.0]);
        assert!(d[1] < -0.9, "{d:?}");
        // The thumb's tip direction moves toward the palm centre (−Z side, down).
        let t = dancegen_motion::Mat3::from_axis_angle(aa[12].map(|v| v as f64));
        let d = t.mul_vec([0.60, -0.30, 0.74]);
        assert!(d[2] < 0.74 && d[1] < -0.3, "{d:?}");
        // Mirror: the right index also bends toward −Y (its direction is −X).
        let r = dancegen_motion::Mat3::from_axis_angle(mirror_hand(&aa)[0].map(|v| v as f64));
        let d = r.mul_vec([-1.0, 0.0, 0.0]);
        assert!(d[1] < -0.9, "{d:?}");
    }
}
