//! Planted feet hold their place: two-bone leg IK on the frames where a foot is in contact.
//!
//! [`crate::foot_lock`] moves the root so the *support* foot stops gliding; the other foot can
//! still slide while it is planted, and a foot that is planted heel-first or toe-first can
//! drift as its ankle turns. This pass pins each planted joint (ankle and toe, separately) to
//! the mean position of its contact run and bends the hip and knee to reach it, keeping the
//! knee in the plane the generated leg bent in. With both ankle and toe planted the foot also
//! keeps the orientation that puts the toe on its spot. Raised-cosine ramps over
//! `blend_frames` frames before and after each run fade the correction in and out, so a step
//! lifts off and lands without a jump. The pelvis, spine and arms are never touched.
//!
//! Not part of any of the four published methods: the systems use it as a named
//! post-processing step (switched off together with the foot lock, `--no-foot-lock`).

use dancegen_motion::fk::{self, LocalRotations};
use dancegen_motion::rotation::{Mat3, Quat};
use dancegen_motion::skeleton::Skeleton;
use dancegen_motion::vec3::{add, dot, lerp, norm, scale, sub};

/// The joints of one leg (indices into the skeleton).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Leg {
    pub hip: usize,
    pub knee: usize,
    pub ankle: usize,
    pub toe: usize,
}

/// SMPL 24's legs: left (1, 4, 7, 10) and right (2, 5, 8, 11).
pub const SMPL_LEGS: [Leg; 2] = [
    Leg {
        hip: 1,
        knee: 4,
        ankle: 7,
        toe: 10,
    },
    Leg {
        hip: 2,
        knee: 5,
        ankle: 8,
        toe: 11,
    },
];

/// Where one leg's contacts are, per frame.
#[derive(Clone, Debug, PartialEq)]
pub struct LegContacts {
    /// `[T]`: the ankle (heel) is planted.
    pub ankle: Vec<bool>,
    /// `[T]`: the toe is planted.
    pub toe: Vec<bool>,
}

/// What the pass changed.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FootIkReport {
    /// Frames × legs that were adjusted.
    pub adjusted: usize,
    /// Largest distance (metres) a target lay beyond the leg's reach.
    pub max_unreached_m: f64,
}

/// How a contact run too long to plant becomes steps: a foot the body drags along a path
/// (a formation's dancer, whose root follows the path while its legs do not walk it) is
/// planted, swung to where the body has gone, and planted again.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stepping {
    /// Frames a foot takes to swing from one plant to the next.
    pub swing_frames: usize,
    /// Height of the swing's arc at its middle (the skeleton's units, along `up`).
    pub lift: f64,
    /// The skeleton's up direction (unit length).
    pub up: [f64; 3],
}

/// Pins planted feet (see the module documentation). `local` holds `[T, J]` local rotation
/// matrices (row-major frames), `root` the `[T]` root positions, both in the skeleton's units
/// and axes; `contacts` has one entry per leg in `legs`.
pub fn pin_planted_feet(
    skeleton: &Skeleton,
    local: &mut [Mat3],
    root: &[[f64; 3]],
    legs: &[Leg],
    contacts: &[LegContacts],
    blend_frames: usize,
    max_travel_m: f64,
) -> FootIkReport {
    pin_planted_feet_stepping(
        skeleton,
        local,
        root,
        legs,
        contacts,
        blend_frames,
        max_travel_m,
        None,
    )
}

/// [`pin_planted_feet`], where a run whose joint strays more than `max_travel_m` is, with
/// `stepping`, cut into plants that each stay within it, joined by swings of
/// [`Stepping::swing_frames`] frames (instead of being left to slide).
#[allow(clippy::too_many_arguments)]
pub fn pin_planted_feet_stepping(
    skeleton: &Skeleton,
    local: &mut [Mat3],
    root: &[[f64; 3]],
    legs: &[Leg],
    contacts: &[LegContacts],
    blend_frames: usize,
    max_travel_m: f64,
    stepping: Option<Stepping>,
) -> FootIkReport {
    let j = skeleton.len();
    let t = root.len();
    assert_eq!(local.len(), t * j, "one rotation per joint and frame");
    assert_eq!(legs.len(), contacts.len(), "one contact track per leg");
    let mut report = FootIkReport::default();
    for (leg, c) in legs.iter().zip(contacts) {
        assert!(
            c.ankle.len() == t && c.toe.len() == t,
            "one contact per frame"
        );
        let world = Pose::all(skeleton, local, root);
        let ankle_at = |f: usize| world[f].pos[leg.ankle];
        let toe_at = |f: usize| world[f].pos[leg.toe];
        let (ankle_runs, toe_runs) = match stepping {
            None => (
                joint_runs(&c.ankle, max_travel_m, ankle_at),
                joint_runs(&c.toe, max_travel_m, toe_at),
            ),
            Some(step) => foot_runs(c, max_travel_m, step, ankle_at, toe_at),
        };
        let ankle_pins = Pins::new(ankle_runs, t, blend_frames);
        let toe_pins = Pins::new(toe_runs, t, blend_frames);
        let toe_offset = skeleton.offsets()[leg.toe];
        for (f, pose) in world.iter().enumerate() {
            let (wa, pa) = ankle_pins.at(f);
            let (wt, pt) = toe_pins.at(f);
            if wa == 0.0 && wt == 0.0 {
                continue;
            }
            let ankle = pose.pos[leg.ankle];
            let r_ankle = pose.rot[leg.ankle];
            let toe_vec = r_ankle.mul_vec(toe_offset);
            let want_ankle = lerp(ankle, pa, wa);
            let want_toe = lerp(pose.pos[leg.toe], pt, wt);
            // Where the ankle must be for the toe to land on its spot with the foot as posed,
            // blended with the ankle's own pin.
            let target = lerp(sub(want_toe, toe_vec), want_ankle, wa);
            // Turn the foot (by the toe's weight) so that it points at the toe's spot.
            let turn = slerp_from_identity(Mat3::between(toe_vec, sub(want_toe, target)), wt);
            let r_ankle_new = turn * r_ankle;
            let frame = &mut local[f * j..(f + 1) * j];
            let unreached = reach(skeleton, frame, pose, *leg, target, r_ankle_new);
            report.max_unreached_m = report.max_unreached_m.max(unreached);
            report.adjusted += 1;
        }
    }
    report
}

/// World rotations and positions of one frame.
struct Pose {
    rot: Vec<Mat3>,
    pos: Vec<[f64; 3]>,
}

impl Pose {
    /// Every frame's pose, through the crate's FK.
    fn all(skeleton: &Skeleton, local: &[Mat3], root: &[[f64; 3]]) -> Vec<Pose> {
        let flat: Vec<f64> = local.iter().flat_map(|m| m.0.concat()).collect();
        let root_flat: Vec<f64> = root.concat();
        let out = fk::forward_kinematics(skeleton, LocalRotations::Matrix(&flat), &root_flat, true)
            .expect("one rotation per joint and frame, one root per frame");
        let world = out.world_rotations.expect("requested");
        let j = skeleton.len();
        (0..root.len())
            .map(|f| Pose {
                rot: (0..j)
                    .map(|k| {
                        let m = &world[(f * j + k) * 9..(f * j + k + 1) * 9];
                        Mat3([[m[0], m[1], m[2]], [m[3], m[4], m[5]], [m[6], m[7], m[8]]])
                    })
                    .collect(),
                pos: (0..j)
                    .map(|k| std::array::from_fn(|a| out.positions[(f * j + k) * 3 + a]))
                    .collect(),
            })
            .collect()
    }
}

/// A joint's target on each frame of a run.
type Targets = Vec<[f64; 3]>;

/// A contact run's pins: its first frame and the joint's target on each of its frames.
type Run = (usize, Targets);

/// The runs of planted frames, each as `[start, end)`.
fn planted_runs(planted: &[bool]) -> Vec<(usize, usize)> {
    let mut runs = Vec::new();
    let mut f = 0;
    while f < planted.len() {
        if !planted[f] {
            f += 1;
            continue;
        }
        let start = f;
        while f < planted.len() && planted[f] {
            f += 1;
        }
        runs.push((start, f));
    }
    runs
}

/// One joint's runs, each pinned to the joint's mean place in it; a run in which the joint
/// strays more than `max_travel` from that place makes a step or a slide, not a plant, and is
/// left alone.
fn joint_runs(planted: &[bool], max_travel: f64, pos: impl Fn(usize) -> [f64; 3]) -> Vec<Run> {
    planted_runs(planted)
        .into_iter()
        .filter_map(|(start, end)| {
            let (mean, travel) = place(start, end, &pos);
            (travel <= max_travel).then(|| (start, vec![mean; end - start]))
        })
        .collect()
}

/// The ankle's and the toe's runs of one leg with stepping. The foot is in contact while
/// either joint is planted; a contact in which either joint's run strays beyond `max_travel`
/// is stepped as one rigid foot ([`foot_steps`]): both joints planted and swung on the same
/// frames. Stepped apart, the heel's and the toe's plants were cut at different frames, and
/// the foot, turned to point from the ankle's target to the toe's, spun by up to 114 degrees
/// in a frame. Other contacts keep [`joint_runs`]' pins.
fn foot_runs(
    contacts: &LegContacts,
    max_travel: f64,
    step: Stepping,
    ankle: impl Fn(usize) -> [f64; 3],
    toe: impl Fn(usize) -> [f64; 3],
) -> (Vec<Run>, Vec<Run>) {
    let contact: Vec<bool> = contacts
        .ankle
        .iter()
        .zip(&contacts.toe)
        .map(|(&a, &t)| a || t)
        .collect();
    let (mut ankle_runs, mut toe_runs) = (Vec::new(), Vec::new());
    for (start, end) in planted_runs(&contact) {
        let own = |planted: &[bool], pos: &dyn Fn(usize) -> [f64; 3]| {
            planted_runs(&planted[start..end])
                .into_iter()
                .map(|(a, b)| (start + a, start + b, place(start + a, start + b, &pos)))
                .collect::<Vec<_>>()
        };
        let ankle_own = own(&contacts.ankle, &ankle);
        let toe_own = own(&contacts.toe, &toe);
        let travels = ankle_own
            .iter()
            .chain(&toe_own)
            .any(|(_, _, (_, travel))| *travel > max_travel);
        if !travels {
            let pinned = |runs: Vec<(usize, usize, ([f64; 3], f64))>| {
                runs.into_iter()
                    .map(|(a, b, (mean, _))| (a, vec![mean; b - a]))
            };
            ankle_runs.extend(pinned(ankle_own));
            toe_runs.extend(pinned(toe_own));
        } else if let Some((a, t)) = foot_steps(start, end, max_travel, step, &ankle, &toe) {
            ankle_runs.push((start, a));
            toe_runs.push((start, t));
        }
    }
    (ankle_runs, toe_runs)
}

/// Per-frame pin weight and position of one joint from its contact runs.
struct Pins {
    weight: Vec<f64>,
    target: Vec<[f64; 3]>,
}

impl Pins {
    /// Each run (sorted, not overlapping) pins the joint to its targets. Around each run the
    /// weight ramps over `blend` frames; where two runs' ramps meet, the target moves from the
    /// one run's place to the other's across the frames between them (taking the nearer run's
    /// place jumped the foot from one to the other in a single frame).
    fn new(runs: Vec<Run>, t: usize, blend: usize) -> Pins {
        // Raised cosine: 1 in the run, falling to 0 at `blend + 1` frames away.
        let ramp = |dist: usize| {
            if dist > blend {
                0.0
            } else {
                0.5 * (1.0 + (std::f64::consts::PI * dist as f64 / (blend + 1) as f64).cos())
            }
        };
        let first = |r: &(usize, Vec<[f64; 3]>)| r.1[0];
        let last = |r: &(usize, Vec<[f64; 3]>)| *r.1.last().expect("runs are not empty");
        let end_of = |r: &(usize, Vec<[f64; 3]>)| r.0 + r.1.len();
        let mut weight = vec![0.0; t];
        let mut target = vec![[0.0; 3]; t];
        // `next`: the first run that ends after frame g.
        let mut next = 0;
        for g in 0..t {
            while next < runs.len() && end_of(&runs[next]) <= g {
                next += 1;
            }
            if let Some(r) = runs.get(next).filter(|r| r.0 <= g) {
                weight[g] = 1.0;
                target[g] = r.1[g - r.0];
                continue;
            }
            let before = next.checked_sub(1).map(|i| &runs[i]);
            let after = runs.get(next);
            let w_before = before.map_or(0.0, |r| ramp(g + 1 - end_of(r)));
            let w_after = after.map_or(0.0, |r| ramp(r.0 - g));
            weight[g] = w_before.max(w_after);
            target[g] = match (before, after) {
                (Some(a), Some(b)) if w_before > 0.0 && w_after > 0.0 => {
                    let (e, s) = (end_of(a), b.0);
                    lerp(last(a), first(b), (g + 1 - e) as f64 / (s + 1 - e) as f64)
                }
                (Some(a), _) if w_before > 0.0 => last(a),
                (_, Some(b)) => first(b),
                _ => [0.0; 3],
            };
        }
        Pins { weight, target }
    }

    fn at(&self, f: usize) -> (f64, [f64; 3]) {
        (self.weight[f], self.target[f])
    }
}

/// The joint's mean place over frames `[start, end)` and how far it strays from it.
fn place(start: usize, end: usize, pos: &impl Fn(usize) -> [f64; 3]) -> ([f64; 3], f64) {
    let mut mean = [0.0; 3];
    for g in start..end {
        mean = add(mean, pos(g));
    }
    let mean = scale(mean, 1.0 / (end - start) as f64);
    let travel = (start..end)
        .map(|g| norm(sub(pos(g), mean)))
        .fold(0.0, f64::max);
    (mean, travel)
}

/// The ankle's and the toe's targets of a travelling contact `[start, end)` cut into steps:
/// plants, each as long as both joints stay within `max_travel` of their mean places in it,
/// with `step.swing_frames` frames between one plant and the next. In a swing the ankle
/// moves on a raised arc (smootherstep along the floor, a bump of `step.lift` along `up`) and
/// the toe rides with it, the foot turning from the one plant's heading to the next's. The
/// contact ends with its last plant (the frames after it, too few for a swing, follow the
/// joints' own places through the ramp); `None` when not even one plant fits.
fn foot_steps(
    start: usize,
    end: usize,
    max_travel: f64,
    step: Stepping,
    ankle: &impl Fn(usize) -> [f64; 3],
    toe: &impl Fn(usize) -> [f64; 3],
) -> Option<(Targets, Targets)> {
    let within =
        |a: usize, b: usize| place(a, b, ankle).1 <= max_travel && place(a, b, toe).1 <= max_travel;
    // Each plant: its frames [a, b), the ankle's place and the toe's.
    let mut plants: Vec<(usize, usize, [f64; 3], [f64; 3])> = Vec::new();
    let mut a = start;
    while a < end {
        let mut b = a + 1;
        while b < end && within(a, b + 1) {
            b += 1;
        }
        plants.push((a, b, place(a, b, ankle).0, place(a, b, toe).0));
        a = b.saturating_add(step.swing_frames);
    }
    let &(first_start, _, _, _) = plants.first()?;
    debug_assert_eq!(first_start, start);
    let stop = plants.last().map(|p| p.1)?;
    let mut ankles = Vec::with_capacity(stop - start);
    let mut toes = Vec::with_capacity(stop - start);
    for (i, &(a, b, ma, mt)) in plants.iter().enumerate() {
        ankles.extend(std::iter::repeat_n(ma, b - a));
        toes.extend(std::iter::repeat_n(mt, b - a));
        let Some(&(next_a, _, na, nt)) = plants.get(i + 1) else {
            continue;
        };
        let (from, to) = (sub(mt, ma), sub(nt, na));
        let turn = Mat3::between(from, to);
        let span = (next_a - b + 1) as f64;
        for g in b..next_a {
            let u = (g + 1 - b) as f64 / span;
            // Smootherstep along the floor and a bump 64 u³ (1 − u)³ (1 at the middle):
            // both start and end with zero speed and zero acceleration, so a swing adds no
            // jerk spike where it leaves or meets a plant (a smoothstep and a sine bump raised
            // the group's worst dancer's jerk from 373 to 486 m/s³).
            let along = u * u * u * (u * (6.0 * u - 15.0) + 10.0);
            let bump = step.lift * 64.0 * (u * (1.0 - u)).powi(3);
            let at = add(lerp(ma, na, along), scale(step.up, bump));
            // The foot turns (rather than its heel-to-toe vector being interpolated, which
            // shrinks through zero when the foot turns round).
            let length = norm(from) + (norm(to) - norm(from)) * along;
            let heading = slerp_from_identity(turn, along).mul_vec(from);
            ankles.push(at);
            toes.push(add(at, scale(heading, length / norm(from).max(1e-12))));
        }
    }
    Some((ankles, toes))
}

/// Two-bone IK: new local rotations of `leg`'s hip, knee and ankle in `local` (one frame) so
/// that the ankle reaches `target` with world rotation `r_ankle`; the knee stays in the plane
/// of hip, generated knee and target. Returns how far the target was out of reach (0 if not).
fn reach(
    skeleton: &Skeleton,
    local: &mut [Mat3],
    pose: &Pose,
    leg: Leg,
    target: [f64; 3],
    r_ankle: Mat3,
) -> f64 {
    let hip = pose.pos[leg.hip];
    let knee = pose.pos[leg.knee];
    let ankle = pose.pos[leg.ankle];
    let a = norm(sub(knee, hip));
    let b = norm(sub(ankle, knee));
    let to_target = sub(target, hip);
    let d_raw = norm(to_target);
    // Keep a sliver of bend so the knee's plane stays defined.
    let (lo, hi) = ((a - b).abs() + 1e-6, (a + b) * (1.0 - 1e-6));
    let d = d_raw.clamp(lo, hi);
    let unreached = (d_raw - hi).max(0.0);
    if d_raw < 1e-9 || a < 1e-9 || b < 1e-9 {
        return unreached;
    }
    let u = scale(to_target, 1.0 / d_raw);
    // The bend direction: the generated knee's offset from the hip-target line.
    let thigh = sub(knee, hip);
    let mut pole = sub(thigh, scale(u, dot(thigh, u)));
    if norm(pole) < 1e-9 {
        // A straight leg pointing at the target: bend the way the knee's own forward points.
        let fwd = pose.rot[leg.knee].mul_vec([0.0, 0.0, 1.0]);
        pole = sub(fwd, scale(u, dot(fwd, u)));
    }
    let pole = scale(pole, 1.0 / norm(pole).max(1e-12));
    let x = (a * a - b * b + d * d) / (2.0 * d);
    let h = (a * a - x * x).max(0.0).sqrt();
    let new_knee = add(hip, add(scale(u, x), scale(pole, h)));
    let new_ankle = add(hip, scale(u, d));

    let turn_hip = Mat3::between(thigh, sub(new_knee, hip));
    let r_hip = turn_hip * pose.rot[leg.hip];
    let r_knee_turned = turn_hip * pose.rot[leg.knee];
    let shin = r_knee_turned.mul_vec(skeleton.offsets()[leg.ankle]);
    let r_knee = Mat3::between(shin, sub(new_ankle, new_knee)) * r_knee_turned;
    let parent_of_hip = skeleton
        .parent(leg.hip)
        .map_or(Mat3::IDENTITY, |p| pose.rot[p]);
    local[leg.hip] = parent_of_hip.transpose() * r_hip;
    local[leg.knee] = r_hip.transpose() * r_knee;
    local[leg.ankle] = r_knee.transpose() * r_ankle;
    unreached
}

fn slerp_from_identity(r: Mat3, w: f64) -> Mat3 {
    if w >= 1.0 {
        return r;
    }
    Mat3::from_quat(Quat::slerp(Quat::IDENTITY, r.to_quat(), w))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A walk-like clip: the root glides forward along x while the left leg stays posed the
    /// same (so its foot slides with the root); the left foot is marked planted throughout.
    fn gliding(frames: usize) -> (Skeleton, Vec<Mat3>, Vec<[f64; 3]>) {
        let skel = Skeleton::smpl24();
        let bend = Mat3::from_axis_angle([0.3, 0.0, 0.0]);
        let mut local = vec![Mat3::IDENTITY; frames * 24];
        for f in 0..frames {
            local[f * 24 + 4] = bend;
            local[f * 24 + 1] = Mat3::from_axis_angle([-0.15, 0.0, 0.0]);
        }
        let root = (0..frames).map(|f| [0.01 * f as f64, 0.9, 0.0]).collect();
        (skel, local, root)
    }

    /// The tests' steps: 6-frame swings lifted 6 cm, Y up.
    const STEP: Stepping = Stepping {
        swing_frames: 6,
        lift: 0.06,
        up: [0.0, 1.0, 0.0],
    };

    /// Contacts of the left leg only: `ankle` and `toe` per frame; the right leg free.
    fn left_leg(ankle: Vec<bool>, toe: Vec<bool>) -> Vec<LegContacts> {
        let t = ankle.len();
        vec![
            LegContacts { ankle, toe },
            LegContacts {
                ankle: vec![false; t],
                toe: vec![false; t],
            },
        ]
    }

    /// Left leg planted (ankle and toe) on the frames `planted`.
    fn left_planted(planted: Vec<bool>) -> Vec<LegContacts> {
        left_leg(planted.clone(), planted)
    }

    fn positions(skel: &Skeleton, local: &[Mat3], root: &[[f64; 3]]) -> Vec<Pose> {
        Pose::all(skel, local, root)
    }

    #[test]
    fn a_planted_foot_holds_its_place_while_the_body_moves() {
        let t = 20;
        let (skel, mut local, root) = gliding(t);
        let before = positions(&skel, &local, &root);
        let contacts = left_planted(vec![true; t]);
        let report = pin_planted_feet(
            &skel,
            &mut local,
            &root,
            &SMPL_LEGS,
            &contacts,
            4,
            f64::INFINITY,
        );
        assert_eq!(report.adjusted, t);
        assert_eq!(report.max_unreached_m, 0.0);
        let after = positions(&skel, &local, &root);
        let (a0, t0) = (after[0].pos[7], after[0].pos[10]);
        // 1e-6: the IK leaves a 1e-6 relative sliver of reach (see `reach`).
        for p in &after {
            assert!(norm(sub(p.pos[7], a0)) < 1e-6, "ankle moved");
            assert!(norm(sub(p.pos[10], t0)) < 1e-6, "toe moved");
        }
        // The pin is the run's mean: the middle of the glide.
        let mid = lerp(before[0].pos[7], before[t - 1].pos[7], 0.5);
        assert!(norm(sub(a0, mid)) < 1e-6);
        // Bones keep their lengths; the right leg and the pelvis are untouched.
        for (p, q) in after.iter().zip(&before) {
            assert!((norm(sub(p.pos[4], p.pos[1])) - norm(sub(q.pos[4], q.pos[1]))).abs() < 1e-9);
            assert!((norm(sub(p.pos[7], p.pos[4])) - norm(sub(q.pos[7], q.pos[4]))).abs() < 1e-9);
            assert!(norm(sub(p.pos[8], q.pos[8])) < 1e-12);
            assert!(norm(sub(p.pos[0], q.pos[0])) < 1e-12);
        }
    }

    #[test]
    fn the_correction_fades_in_and_out_around_a_contact() {
        let t = 30;
        let (skel, mut local, root) = gliding(t);
        let before = positions(&skel, &local, &root);
        let planted: Vec<bool> = (0..t).map(|f| (10..20).contains(&f)).collect();
        let contacts = left_planted(planted);
        pin_planted_feet(
            &skel,
            &mut local,
            &root,
            &SMPL_LEGS,
            &contacts,
            4,
            f64::INFINITY,
        );
        let after = positions(&skel, &local, &root);
        let moved: Vec<f64> = (0..t)
            .map(|f| norm(sub(after[f].pos[7], before[f].pos[7])))
            .collect();
        // Untouched five or more frames away from the run.
        assert!(moved[..5].iter().chain(&moved[25..]).all(|&m| m < 1e-12));
        // Still inside the run; each step out of it moves the foot a little, never a jump.
        for f in 11..20 {
            assert!(norm(sub(after[f].pos[7], after[10].pos[7])) < 1e-6);
        }
        for f in 1..t {
            let step = norm(sub(after[f].pos[7], after[f - 1].pos[7]));
            // The free foot moves 1 cm per frame with the glide; over the 4-frame ramp it also
            // covers the gap to the pin (~4.5 cm at the run's start): 3 cm per frame at most.
            assert!(step < 0.03, "frame {f}: the ankle jumps {step} m");
        }
    }

    #[test]
    fn two_runs_one_frame_apart_hand_over_their_places_across_the_gap() {
        // Planted on 0-9 and 11-20 of a foot gliding 1 cm per frame: the two pins are 11 cm
        // apart. Taking the nearer run's place in the gap frame jumped the foot 11 cm in one
        // frame; moving the target across the gap takes two frames for it.
        let t = 21;
        let (skel, mut local, root) = gliding(t);
        let contacts = left_planted((0..t).map(|f| f != 10).collect());
        pin_planted_feet(
            &skel,
            &mut local,
            &root,
            &SMPL_LEGS,
            &contacts,
            4,
            f64::INFINITY,
        );
        let after = positions(&skel, &local, &root);
        let apart = norm(sub(after[20].pos[7], after[0].pos[7]));
        assert!((apart - 0.11).abs() < 1e-3, "pins {apart} m apart");
        for f in 1..t {
            let step = norm(sub(after[f].pos[7], after[f - 1].pos[7]));
            assert!(step < 0.6 * apart, "frame {f}: the ankle jumps {step} m");
        }
    }

    #[test]
    fn a_run_whose_foot_travels_is_left_alone() {
        // Planted throughout while gliding 1 cm per frame over 20 frames: the ankle strays up
        // to ~10 cm from its mean place. Bound 5 cm: not a plant, untouched; bound 20 cm:
        // pinned.
        let t = 20;
        let (skel, local, root) = gliding(t);
        let before = positions(&skel, &local, &root);
        let contacts = left_planted(vec![true; t]);
        for (bound, pinned) in [(0.05, false), (0.2, true)] {
            let mut l = local.clone();
            pin_planted_feet(&skel, &mut l, &root, &SMPL_LEGS, &contacts, 4, bound);
            let after = positions(&skel, &l, &root);
            let moved = (0..t)
                .map(|f| norm(sub(after[f].pos[7], before[f].pos[7])))
                .fold(0.0, f64::max);
            assert_eq!(moved > 0.05, pinned, "bound {bound}: moved {moved} m");
            assert_eq!(moved == 0.0, !pinned, "bound {bound}: moved {moved} m");
        }
    }

    #[test]
    fn a_foot_dragged_along_a_path_steps_instead_of_sliding() {
        // Planted for 90 frames while the body glides 1 cm per frame: 89 cm of slide. With
        // stepping (bound 5 cm, 6-frame swings lifted 6 cm) the foot stands still on most
        // frames, lifts in each swing, never jumps, and keeps up with the body.
        let t = 90;
        let (skel, mut local, root) = gliding(t);
        let before = positions(&skel, &local, &root);
        let contacts = left_planted(vec![true; t]);
        let bound = 0.05;
        pin_planted_feet_stepping(
            &skel,
            &mut local,
            &root,
            &SMPL_LEGS,
            &contacts,
            4,
            bound,
            Some(STEP),
        );
        let after = positions(&skel, &local, &root);
        let ankle = |f: usize| after[f].pos[7];
        let still = (1..t)
            .filter(|&f| norm(sub(ankle(f), ankle(f - 1))) < 1e-3)
            .count();
        assert!(
            still > t / 2,
            "the ankle stands still on {still} of {t} frames"
        );
        let floor = ankle(0)[1];
        let highest = (0..t).map(|f| ankle(f)[1] - floor).fold(0.0, f64::max);
        assert!(
            highest > 0.05,
            "the swings lift the ankle {highest} m at most"
        );
        for f in 1..t {
            let jump = norm(sub(ankle(f), ankle(f - 1)));
            assert!(jump < 0.05, "frame {f}: the ankle jumps {jump} m");
        }
        // The foot goes where the body goes: never further from the generated foot than a
        // plant's bound, plus the body's travel over a swing (7 frames at 1 cm), plus the lift.
        for (f, generated) in before.iter().enumerate() {
            let behind = norm(sub(ankle(f), generated.pos[7]));
            assert!(
                behind < bound + 0.01 * 7.0 + 0.06,
                "frame {f}: {behind} m off"
            );
        }
        // Without stepping the same run slides as generated (untouched).
        let (_, mut l2, _) = gliding(t);
        pin_planted_feet(&skel, &mut l2, &root, &SMPL_LEGS, &contacts, 4, bound);
        let plain = positions(&skel, &l2, &root);
        assert!((0..t).all(|f| norm(sub(plain[f].pos[7], before[f].pos[7])) == 0.0));
    }

    #[test]
    fn heel_and_toe_step_together_as_one_foot() {
        // The toe lands 5 frames before the heel, and the body yaws slowly as it glides, so
        // stepped separately the heel's and the toe's plants would be cut at different
        // frames: the foot, turned to point from the ankle's target to the toe's, spun in a
        // frame (60-114 degrees in held-out group dances). Stepped as one foot it turns
        // smoothly and neither joint jumps.
        let t = 90;
        let (skel, mut local, root) = gliding(t);
        for f in 0..t {
            local[f * 24] = Mat3::from_axis_angle([0.0, 0.004 * f as f64, 0.0]);
        }
        let mut ankle = vec![true; t];
        ankle[..5].fill(false);
        let contacts = left_leg(ankle, vec![true; t]);
        pin_planted_feet_stepping(
            &skel,
            &mut local,
            &root,
            &SMPL_LEGS,
            &contacts,
            4,
            0.05,
            Some(STEP),
        );
        let after = positions(&skel, &local, &root);
        let foot = |f: usize| sub(after[f].pos[10], after[f].pos[7]);
        for f in 1..t {
            for joint in [7, 10] {
                let jump = norm(sub(after[f].pos[joint], after[f - 1].pos[joint]));
                assert!(jump < 0.05, "frame {f}: joint {joint} jumps {jump} m");
            }
            let (a, b) = (foot(f - 1), foot(f));
            let turn = (dot(a, b) / (norm(a) * norm(b)))
                .clamp(-1.0, 1.0)
                .acos()
                .to_degrees();
            assert!(turn < 10.0, "frame {f}: the foot turns {turn} degrees");
        }
    }

    #[test]
    fn a_target_out_of_reach_is_reported_and_the_leg_stretches_towards_it() {
        let t = 40;
        let skel = Skeleton::smpl24();
        let mut local = vec![Mat3::IDENTITY; t * 24];
        // The body flies up and away while the left foot claims contact.
        let root: Vec<[f64; 3]> = (0..t).map(|f| [0.05 * f as f64, 0.9, 0.0]).collect();
        let contacts = left_leg(vec![true; t], vec![false; t]);
        let report = pin_planted_feet(
            &skel,
            &mut local,
            &root,
            &SMPL_LEGS,
            &contacts,
            2,
            f64::INFINITY,
        );
        assert!(report.max_unreached_m > 0.1);
        assert!(
            local
                .iter()
                .all(|m| m.0.iter().flatten().all(|v| v.is_finite()))
        );
    }
}
