//! Foot-skating ratio (LODGE).
//!
//! Reference: `li-ronghui/LODGE:metric/foot_skating.py::calc_foot_skating_ratio` (with the module
//! global `ground_height = 0` its `__main__` sets), Y-up, 30 fps (no frame time is used).
//!
//! The reference takes a 139-dim LODGE/FineDance vector (`[4 contacts, root position (3),
//! 22 × rot6d]`) and runs LODGE's SMPL-X forward kinematics (`dld/data/render_joints/smplfk.py`,
//! rest joints from `data/smplx_neu_J_1.npy`). Those SMPL-X neutral rest joints are under the
//! non-commercial SMPL-X licence and are **not shipped**: this port works on joint positions. To
//! reproduce LODGE numbers from 139-dim vectors, run that FK yourself with user-supplied rest
//! joints and pass the positions (SMPL/SMPL-X joints 0–21 share the order used here) to
//! [`foot_skating_ratio`], or the four grounded foot joints to [`foot_skating_from_grounded_feet`].
//!
//! Steps (joints: left ankle 7, right ankle 8, left toe 10, right toe 11; `y` is up):
//! 1. **grounding** (`set_on_ground_139`): from frame 0's toe heights `l`, `r`: `h = (l + r)/2` if
//!    `|l − r| < 0.02`, else `min(l, r)`; the reference subtracts `h` from the root `y` (column 5 of
//!    the 139 vector) and redoes FK, which shifts every joint's `y` by `−h` — done here directly
//!    on the positions ([`ground_height`]);
//! 2. **contact** per side and frame: ankle `y ≤ 0.08` **and** toe `y ≤ 0.05`;
//! 3. per-frame displacement `P[t+1] − P[t]` of ankle and toe (no frame time; the last frame's is
//!    0), zeroed on frames without contact of that side;
//! 4. "tangent velocity" `|(Δx + Δz) / 2|` — the absolute value of the **mean of the signed**
//!    horizontal components, not a norm (reference quirk, reproduced);
//! 5. a contact frame is *sliding* if the ankle's or the toe's value is `> 0.01`;
//! 6. ratio per side = sliding frames / contact frames, a float32 division in the reference
//!    (reproduced: the ratio is the f64 value of the f32 quotient); the per-file ratio is
//!    `(left + right) / 2`, the set value the means over files ([`mean_foot_skating`]).
//!
//! Thresholds are compared as the reference does, against float32 tensors: each constant is the
//! float32 rounding of the decimal (e.g. `0.05 → 0.0500000007…`), which matters only for inputs
//! exactly on a threshold.
//!
//! Degenerate cases: a side with no contact frame (e.g. a frozen clip with the foot in the air,
//! fixture `R2_frozen50`) gives `0/0` → the reference returns `NaN` for that side and for the
//! file's mean; this port returns `NaN` as well ([`FootSkating::left`] / [`FootSkating::right`]
//! give `None`), and [`mean_foot_skating`] propagates it like `np.mean`.
//!
//! Differences from the reference: positions are f64 and grounding is a subtraction instead of a
//! float32 re-run of FK, so inputs sitting within float32 rounding of a threshold can flip. On the
//! fixture intermediates (the exact positions the reference thresholds) the ratios match exactly.
//!
//! Duolando's "foot-skating duration" is a different measure: [`crate::foot_skating_duration`].

/// Left ankle joint index.
pub const L_ANKLE: usize = 7;
/// Right ankle joint index.
pub const R_ANKLE: usize = 8;
/// Left toe (foot) joint index.
pub const L_TOE: usize = 10;
/// Right toe (foot) joint index.
pub const R_TOE: usize = 11;

/// Up axis (`y`).
const UP: usize = 1;

/// Toe-height difference below which the ground is the mean of the two toes (else the minimum).
pub const GROUND_TOE_TOLERANCE: f64 = 0.02_f32 as f64;
/// Maximum ankle height of a contact frame (`ground_height + 0.08`).
pub const ANKLE_CONTACT_HEIGHT: f64 = 0.08_f32 as f64;
/// Maximum toe height of a contact frame (`ground_height + 0.05`).
pub const TOE_CONTACT_HEIGHT: f64 = 0.05_f32 as f64;
/// Per-frame tangent displacement above which a contact frame slides.
pub const SLIDE_THRESHOLD: f64 = 0.01_f32 as f64;

/// Per-clip foot-skating result.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FootSkating {
    /// Left sliding frames / left contact frames (`NaN` if no contact frame), float32 quotient.
    pub left_ratio: f64,
    /// Right sliding frames / right contact frames (`NaN` if no contact frame), float32 quotient.
    pub right_ratio: f64,
    /// Frames with the left foot in contact (reference `left_static_num`).
    pub left_contact: usize,
    /// Left contact frames that slide.
    pub left_sliding: usize,
    /// Frames with the right foot in contact (reference `right_static_num`).
    pub right_contact: usize,
    /// Right contact frames that slide.
    pub right_sliding: usize,
}

impl FootSkating {
    /// `(left + right) / 2` (`NaN` if either side is).
    pub fn ratio(&self) -> f64 {
        (self.left_ratio + self.right_ratio) / 2.0
    }

    /// Left ratio, `None` without left contact frames.
    pub fn left(&self) -> Option<f64> {
        (self.left_contact > 0).then_some(self.left_ratio)
    }

    /// Right ratio, `None` without right contact frames.
    pub fn right(&self) -> Option<f64> {
        (self.right_contact > 0).then_some(self.right_ratio)
    }
}

/// The float32 quotient `num / den` as the reference computes it (`0/0 → NaN`).
fn f32_ratio(num: usize, den: usize) -> f64 {
    f64::from(num as f32 / den as f32)
}

/// Ground height from frame 0's toe heights (`set_on_ground_139`, `ground_h = 0`): the mean of the
/// two toes' `y` if they differ by less than 0.02, else the lower one.
pub fn ground_height(left_toe_y: f64, right_toe_y: f64) -> f64 {
    if (left_toe_y - right_toe_y).abs() < GROUND_TOE_TOLERANCE {
        (left_toe_y + right_toe_y) / 2.0
    } else {
        left_toe_y.min(right_toe_y)
    }
}

/// Core: `feet(t) = [l_ankle, r_ankle, l_toe, r_toe]` positions, shifted down by `ground`.
fn skating(frames: usize, ground: f64, feet: impl Fn(usize) -> [[f64; 3]; 4]) -> FootSkating {
    let mut out = FootSkating {
        left_ratio: f64::NAN,
        right_ratio: f64::NAN,
        left_contact: 0,
        left_sliding: 0,
        right_contact: 0,
        right_sliding: 0,
    };
    // The reference's per-frame y after grounding (FK with the root shifted by −ground).
    let y = |q: [f64; 3]| q[UP] - ground;
    let slides = |a: [f64; 3], b: [f64; 3]| {
        let (dx, dz) = (b[0] - a[0], b[2] - a[2]);
        ((dx + dz) / 2.0).abs() > SLIDE_THRESHOLD
    };
    for t in 0..frames {
        let f = feet(t);
        let next = (t + 1 < frames).then(|| feet(t + 1));
        for (ankle, toe, contact, sliding) in [
            (0, 2, &mut out.left_contact, &mut out.left_sliding),
            (1, 3, &mut out.right_contact, &mut out.right_sliding),
        ] {
            if y(f[ankle]) <= ANKLE_CONTACT_HEIGHT && y(f[toe]) <= TOE_CONTACT_HEIGHT {
                *contact += 1;
                // The last frame's displacement is 0 in the reference and never slides.
                if let Some(n) = next
                    && (slides(f[ankle], n[ankle]) || slides(f[toe], n[toe]))
                {
                    *sliding += 1;
                }
            }
        }
    }
    out.left_ratio = f32_ratio(out.left_sliding, out.left_contact);
    out.right_ratio = f32_ratio(out.right_sliding, out.right_contact);
    out
}

/// Foot-skating ratio of a Y-up `(T, J, 3)` joint array (SMPL/SMPL-X order, `J ≥ 12`), grounded
/// first as the reference does (see the module docs). Empty input gives `NaN` ratios.
///
/// # Panics
/// If `num_joints < 12` or `joints.len()` is not a multiple of `num_joints * 3`.
pub fn foot_skating_ratio(joints: &[f64], num_joints: usize) -> FootSkating {
    assert!(
        num_joints >= 12,
        "foot skating needs at least 12 joints, got {num_joints}"
    );
    let frame_len = num_joints * 3;
    assert!(
        joints.len().is_multiple_of(frame_len),
        "joint array of {} values is not a whole number of {num_joints}x3 frames",
        joints.len()
    );
    let frames = joints.len() / frame_len;
    let pos = |t: usize, j: usize| {
        let o = t * frame_len + j * 3;
        [joints[o], joints[o + 1], joints[o + 2]]
    };
    let ground = if frames == 0 {
        0.0
    } else {
        ground_height(pos(0, L_TOE)[UP], pos(0, R_TOE)[UP])
    };
    skating(frames, ground, |t| {
        [
            pos(t, L_ANKLE),
            pos(t, R_ANKLE),
            pos(t, L_TOE),
            pos(t, R_TOE),
        ]
    })
}

/// Foot-skating ratio of already grounded foot positions `(T, 4, 3)` in the reference's order
/// `[l_ankle (7), r_ankle (8), l_toe (10), r_toe (11)]` — the positions the reference thresholds
/// after `set_on_ground_139` + FK (fixtures `*_feet_grounded_lodgefk.npy`). No grounding is done.
///
/// # Panics
/// If `feet.len()` is not a multiple of 12.
pub fn foot_skating_from_grounded_feet(feet: &[f64]) -> FootSkating {
    assert!(
        feet.len().is_multiple_of(12),
        "feet array of {} values is not a whole number of 4x3 frames",
        feet.len()
    );
    let pos = |t: usize, k: usize| {
        let o = t * 12 + k * 3;
        [feet[o], feet[o + 1], feet[o + 2]]
    };
    skating(feet.len() / 12, 0.0, |t| {
        [pos(t, 0), pos(t, 1), pos(t, 2), pos(t, 3)]
    })
}

/// Set value as the reference's `__main__` prints it: `(mean left, mean right, (left + right)/2)`
/// over files, `NaN` propagating like `np.mean` (and `NaN` for an empty set).
pub fn mean_foot_skating(results: &[FootSkating]) -> (f64, f64, f64) {
    let n = results.len() as f64;
    let left = results.iter().map(|r| r.left_ratio).sum::<f64>() / n;
    let right = results.iter().map(|r| r.right_ratio).sum::<f64>() / n;
    (left, right, (left + right) / 2.0)
}
