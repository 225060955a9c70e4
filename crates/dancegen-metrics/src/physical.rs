//! Physical plausibility: what a viewer sees before any distribution metric — feet on the
//! floor, feet that stay put while planted, smooth motion without teleports, legs that do not
//! pass through each other, and a human tempo. Our definitions (no published reference); every
//! threshold is a named constant with where it comes from.
//!
//! Input: world joints `(T, 24, 3)`, SMPL 24 order, **Y-up, metres, the floor at y = 0** (the
//! crate convention; planted toe joints at the floor height, as LODGE's grounding puts them), at
//! `fps` frames per second. The figures depend on the frame rate (jerk and single-frame steps
//! above all), so compare motions at the same rate: the reports use 30 fps.
//!
//! | key | what | unit |
//! |---|---|---|
//! | `floor_median`, `floor_p05`, `floor_p95` | height of the lowest foot joint (ankles 7/8, feet 10/11) per frame: median, 5th and 95th percentile | m |
//! | `float` | share of frames in which no foot joint is within [`CONTACT_HEIGHT_M`] of the floor | % |
//! | `foot_slide` | median horizontal speed of a foot joint while it is in contact (ankle within [`ANKLE_CONTACT_M`], toe within [`CONTACT_HEIGHT_M`]) | m/s |
//! | `jerk`, `jerk_p99` | third finite difference of every joint, `fps³·‖P[t+3] − 3P[t+2] + 3P[t+1] − P[t]‖`: mean and 99th percentile over joints and samples | m/s³ |
//! | `max_step` | largest single-frame displacement of any joint | m |
//! | `spikes` | frame steps in which some joint moves faster than [`SPIKE_SPEED_MS`] | count |
//! | `leg_cross` | share of frames with crossed legs ([`shins_crossed`]) | % |
//! | `lean` | share of frames whose pelvis is more than [`LEAN_M`] horizontally from the midpoint of the ankles | % |
//! | `joint_speed` | mean speed over joints and frame steps | m/s |
//! | `pelvis_speed` | mean horizontal speed of the pelvis | m/s |
//! | `step_rate` | foot steps of both feet per second ([`count_steps`]) | 1/s |

use crate::{FRAME_LEN, FeatureError, NUM_JOINTS, frame_count};
use dancegen_motion::capsule_body::{CAPSULES, segment_distance_sq};

/// Left / right ankle, left / right foot (toe) joints.
const L_ANKLE: usize = 7;
const R_ANKLE: usize = 8;
const L_TOE: usize = 10;
const R_TOE: usize = 11;
const L_HIP: usize = 1;
const R_HIP: usize = 2;
const L_KNEE: usize = 4;
const R_KNEE: usize = 5;
const PELVIS: usize = 0;
/// A pelvis further than this horizontally from the midpoint of its ankles leans: the legs
/// slant under a body the feet no longer carry (seen in the group model's controlled dances,
/// docs/group-collapse.md §21). Real dance leans too, in lunges and deep side steps: on the real
/// held-out tracks of docs/group-eval.md at their true rates (`dancegen eval --pred
/// target/group-eval/real --fps 30 --metrics lean` after `tools/group_eval.sh`), the four salsa
/// takes lean in 0-2.3 % of frames and CMU 05_07 (modern dance) in 11.4 %.
pub const LEAN_M: f64 = 0.3;
/// Foot joints whose lowest point is "the foot" for the floor figures.
pub const FOOT_JOINTS: [usize; 4] = [L_ANKLE, R_ANKLE, L_TOE, R_TOE];

/// Height above the floor within which a foot joint touches it: LODGE's toe contact height
/// (`foot_skating.py`, 5 cm; `crate::foot_skating::TOE_CONTACT_HEIGHT`). The lowest foot joint of
/// a standing SMPL body (the toe joint, at the ball of the foot) is this close to its sole.
pub const CONTACT_HEIGHT_M: f64 = 0.05;
/// Ankle height within which the ankle joint is in contact: LODGE's ankle contact height
/// (`foot_skating.py`, 8 cm; `crate::foot_skating::ANKLE_CONTACT_HEIGHT`).
pub const ANKLE_CONTACT_M: f64 = 0.08;
/// A joint moving faster than this over one frame step is a spike (a teleport, not a movement).
/// In the real takes at their true rates (30 fps), the fastest single-frame joint step of CMU
/// subject 05 is 0.46 m (13.8 m/s), of the breakdance takes 0.65 m (19.5 m/s, a flip), of AIST++
/// 0.51 m; the salsa takes have three steps over it (up to 0.83 m, 25 m/s: a salsa dancer's hand
/// does not move that fast, so we read them as capture glitches). `dancegen eval --fps 30
/// --metrics max_step,spikes` on the converted takes.
pub const SPIKE_SPEED_MS: f64 = 20.0;
/// A foot is at rest while its slower joint (ankle or toe) moves slower than this, and moving
/// once its slower joint moves faster than [`STEP_MOVE_SPEED_MS`] (hysteresis, so capture noise
/// on a planted foot does not count steps). In the real takes at their true rates (salsa, CMU 05
/// and 85, 30 fps) the slower foot joint's speed has its lower quartile at 0.04-0.15 m/s (resting
/// feet: capture noise, pivots) and its upper quartile at 0.8-2.7 m/s (stepping feet); 0.2 and
/// 0.4 m/s lie between the two (measured once with a numpy script on the converted takes).
pub const STEP_REST_SPEED_MS: f64 = 0.2;
/// See [`STEP_REST_SPEED_MS`].
pub const STEP_MOVE_SPEED_MS: f64 = 0.4;
/// A moving phase is a step when the ankle travels at least this far (path length) between two
/// rests: a small salsa step or a lift-and-replace tap (≈ 5 cm up and down) passes, a weight
/// shift that only rolls the foot does not.
pub const STEP_MIN_TRAVEL_M: f64 = 0.08;

/// Physical figures of one dancer, see the module table.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Physical {
    pub floor_median: f64,
    pub floor_p05: f64,
    pub floor_p95: f64,
    /// Share of frames, in percent.
    pub float_pct: f64,
    /// `None` when no foot joint is ever in contact.
    pub foot_slide: Option<f64>,
    pub jerk_mean: f64,
    pub jerk_p99: f64,
    pub max_step: f64,
    pub spikes: usize,
    /// Share of frames, in percent.
    pub leg_cross_pct: f64,
    /// Share of frames, in percent.
    pub lean_pct: f64,
    pub joint_speed: f64,
    pub pelvis_speed: f64,
    pub step_rate: f64,
}

impl Physical {
    /// `(key, value)` in [`KEYS`] order; `None` where undefined.
    pub fn entries(&self) -> [(&'static str, Option<f64>); 14] {
        let values = [
            Some(self.floor_median),
            Some(self.floor_p05),
            Some(self.floor_p95),
            Some(self.float_pct),
            self.foot_slide,
            Some(self.jerk_mean),
            Some(self.jerk_p99),
            Some(self.max_step),
            Some(self.spikes as f64),
            Some(self.leg_cross_pct),
            Some(self.lean_pct),
            Some(self.joint_speed),
            Some(self.pelvis_speed),
            Some(self.step_rate),
        ];
        std::array::from_fn(|i| (KEYS[i], values[i]))
    }
}

/// The keys of the figures, in the module table's order.
pub const KEYS: [&str; 14] = [
    "floor_median",
    "floor_p05",
    "floor_p95",
    "float",
    "foot_slide",
    "jerk",
    "jerk_p99",
    "max_step",
    "spikes",
    "leg_cross",
    "lean",
    "joint_speed",
    "pelvis_speed",
    "step_rate",
];

/// Frames [`physical`] needs: jerk takes four.
pub const MIN_FRAMES: usize = 4;

/// Every figure of one dancer's world joints at `fps`.
pub fn physical(joints: &[f64], fps: f64) -> Result<Physical, FeatureError> {
    let frames = frame_count(joints)?;
    if frames < MIN_FRAMES {
        return Err(FeatureError::TooShort {
            what: "physical plausibility",
            min: MIN_FRAMES,
            frames,
        });
    }
    if !(fps.is_finite() && fps > 0.0) {
        return Err(FeatureError::BadRate { fps });
    }
    let p = |t: usize, j: usize| -> [f64; 3] {
        let i = (t * NUM_JOINTS + j) * 3;
        [joints[i], joints[i + 1], joints[i + 2]]
    };

    let mut lowest: Vec<f64> = (0..frames)
        .map(|t| {
            FOOT_JOINTS
                .iter()
                .map(|&j| p(t, j)[1])
                .fold(f64::INFINITY, f64::min)
        })
        .collect();
    let floating = lowest.iter().filter(|&&h| h > CONTACT_HEIGHT_M).count();
    lowest.sort_by(f64::total_cmp);

    let mut slides = Vec::new();
    for t in 0..frames - 1 {
        for (j, limit) in [
            (L_ANKLE, ANKLE_CONTACT_M),
            (R_ANKLE, ANKLE_CONTACT_M),
            (L_TOE, CONTACT_HEIGHT_M),
            (R_TOE, CONTACT_HEIGHT_M),
        ] {
            let (a, b) = (p(t, j), p(t + 1, j));
            if a[1] <= limit {
                slides.push(fps * (b[0] - a[0]).hypot(b[2] - a[2]));
            }
        }
    }
    slides.sort_by(f64::total_cmp);

    let mut jerks = Vec::with_capacity((frames - 3) * NUM_JOINTS);
    let cube = fps * fps * fps;
    for t in 0..frames - 3 {
        for j in 0..NUM_JOINTS {
            let (a, b, c, d) = (p(t, j), p(t + 1, j), p(t + 2, j), p(t + 3, j));
            let v: [f64; 3] = std::array::from_fn(|k| d[k] - 3.0 * c[k] + 3.0 * b[k] - a[k]);
            jerks.push(cube * norm(v));
        }
    }
    let jerk_mean = jerks.iter().sum::<f64>() / jerks.len() as f64;
    jerks.sort_by(f64::total_cmp);

    let mut max_step = 0.0_f64;
    let mut spikes = 0;
    let mut speed_sum = 0.0;
    let mut pelvis_sum = 0.0;
    for t in 0..frames - 1 {
        let mut frame_max = 0.0_f64;
        for j in 0..NUM_JOINTS {
            let d = norm(sub(p(t + 1, j), p(t, j)));
            frame_max = frame_max.max(d);
            speed_sum += d;
        }
        max_step = max_step.max(frame_max);
        if frame_max * fps > SPIKE_SPEED_MS {
            spikes += 1;
        }
        let (a, b) = (p(t, PELVIS), p(t + 1, PELVIS));
        pelvis_sum += (b[0] - a[0]).hypot(b[2] - a[2]);
    }
    let steps_n = (frames - 1) as f64;

    let crossed = (0..frames)
        .filter(|&t| shins_crossed(&frame(joints, t)))
        .count();
    let leaning = (0..frames)
        .filter(|&t| {
            let (pelvis, l, r) = (p(t, PELVIS), p(t, L_ANKLE), p(t, R_ANKLE));
            (pelvis[0] - (l[0] + r[0]) / 2.0).hypot(pelvis[2] - (l[2] + r[2]) / 2.0) > LEAN_M
        })
        .count();
    let steps =
        count_steps(joints, fps, L_ANKLE, L_TOE)? + count_steps(joints, fps, R_ANKLE, R_TOE)?;

    Ok(Physical {
        floor_median: percentile(&lowest, 50.0),
        floor_p05: percentile(&lowest, 5.0),
        floor_p95: percentile(&lowest, 95.0),
        float_pct: 100.0 * floating as f64 / frames as f64,
        foot_slide: (!slides.is_empty()).then(|| percentile(&slides, 50.0)),
        jerk_mean,
        jerk_p99: percentile(&jerks, 99.0),
        max_step,
        spikes,
        leg_cross_pct: 100.0 * crossed as f64 / frames as f64,
        lean_pct: 100.0 * leaning as f64 / frames as f64,
        joint_speed: fps * speed_sum / (steps_n * NUM_JOINTS as f64),
        pelvis_speed: fps * pelvis_sum / steps_n,
        step_rate: steps as f64 * fps / steps_n,
    })
}

/// Whether the legs cross in one frame. Either
/// - the two shin segments (knee → ankle) come closer than one shin capsule radius (0.05 m,
///   `dancegen_motion::capsule_body`): their surfaces would sink into each other by more than
///   half a shin's thickness, which no leg can do; or
/// - the legs have swapped sides: along the horizontal hip axis (right hip → left hip), the
///   left knee is right of the right knee **and** the left ankle right of the right ankle.
///
/// Ankles alone crossing over is dance (a cross-body step, ballet's fifth position and
/// croisé): the ankle order along the hip axis is swapped in 14 % of the real salsa frames and
/// 47 % of CMU subject 05's, so it does not count. Knees and ankles both swapped: 0.1 % of the
/// salsa frames, 2.1 % of subject 05's, 2.4 % of the breakdance takes' (both measured once with
/// a numpy script on the takes converted at their true rates). With both tests, as
/// `dancegen eval --fps 30 --metrics leg_cross` computes it on those takes: salsa 2.0 % (one
/// take, 61_12, 16.5 %: its shin axes pass within 5 cm), subject 05 3.6 %, subject 85 2.7 %, AIST++
/// 1.0 %.
pub fn shins_crossed(j: &[[f64; 3]; 24]) -> bool {
    let radius = CAPSULES
        .iter()
        .find(|c| c.name == "left_shin")
        .map_or(0.05, |c| c.radius_m);
    if segment_distance_sq(j[L_KNEE], j[L_ANKLE], j[R_KNEE], j[R_ANKLE]) < radius * radius {
        return true;
    }
    let axis = sub(j[L_HIP], j[R_HIP]);
    let (ax, az) = (axis[0], axis[2]);
    let lateral = |a: [f64; 3]| a[0] * ax + a[2] * az;
    lateral(j[L_KNEE]) < lateral(j[R_KNEE]) && lateral(j[L_ANKLE]) < lateral(j[R_ANKLE])
}

/// Steps of one foot (its ankle and toe joints): the foot rests while its slower joint moves
/// under [`STEP_REST_SPEED_MS`] and moves once it goes over [`STEP_MOVE_SPEED_MS`]; a moving
/// phase between two rests (or from the start) in which the ankle travels at least
/// [`STEP_MIN_TRAVEL_M`] counts as one step when the foot comes to rest again. Speeds are 3D
/// and floor-independent, so a floating dancer's steps are still counted (the floor figures
/// report the floating).
pub fn count_steps(
    joints: &[f64],
    fps: f64,
    ankle: usize,
    toe: usize,
) -> Result<usize, FeatureError> {
    let frames = frame_count(joints)?;
    let at = |t: usize, j: usize| -> [f64; 3] {
        let i = (t * NUM_JOINTS + j) * 3;
        [joints[i], joints[i + 1], joints[i + 2]]
    };
    let mut moving = false;
    let mut travel = 0.0;
    let mut steps = 0;
    for t in 0..frames.saturating_sub(1) {
        let da = norm(sub(at(t + 1, ankle), at(t, ankle)));
        let dt = norm(sub(at(t + 1, toe), at(t, toe)));
        let speed = fps * da.min(dt);
        if moving {
            travel += da;
            if speed < STEP_REST_SPEED_MS {
                if travel >= STEP_MIN_TRAVEL_M {
                    steps += 1;
                }
                moving = false;
            }
        } else if speed > STEP_MOVE_SPEED_MS {
            moving = true;
            travel = da;
        }
    }
    Ok(steps)
}

fn frame(joints: &[f64], t: usize) -> [[f64; 3]; 24] {
    let f = &joints[t * FRAME_LEN..(t + 1) * FRAME_LEN];
    std::array::from_fn(|j| [f[j * 3], f[j * 3 + 1], f[j * 3 + 2]])
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn norm(v: [f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

/// Linear-interpolation percentile (numpy's default) of sorted values.
fn percentile(sorted: &[f64], q: f64) -> f64 {
    let pos = q / 100.0 * (sorted.len() - 1) as f64;
    let (lo, hi) = (pos.floor() as usize, pos.ceil() as usize);
    sorted[lo] + (sorted[hi] - sorted[lo]) * (pos - lo as f64)
}
