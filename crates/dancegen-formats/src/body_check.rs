//! The body check of every motion file read ([`dancegen_motion::body_bounds`]), on the world
//! joint positions of whatever the file holds: SMPL rotations through forward kinematics, a
//! BVH through its own hierarchy, joint arrays as they are. The motion reader calls these for
//! each kind of motion it read.

use dancegen_motion::body_bounds::{BodyUnits, check_body};
use dancegen_motion::skeleton::{
    SMPL24_NAMES, SMPL24_PARENTS, SMPLH52_NAMES, SMPLH52_PARENTS, SMPLX55_NAMES, SMPLX55_PARENTS,
};

use crate::bvh::Bvh;
use crate::bvh_motion::{bvh_world_positions, bvh_world_transforms};

/// A standing person's height, metres: a BVH stores no unit, so its rest pose's tallest extent
/// is taken as this many metres to put the bounds in the file's units.
pub const REST_POSE_HEIGHT_M: f64 = 1.7;

/// SMPL 24 world joints `(T, 24, 3)`, metres.
pub fn smpl_joints(positions: &[f32]) -> Result<(), String> {
    check_body(
        positions,
        24,
        Some(&SMPL24_PARENTS),
        Some(&SMPL24_NAMES),
        BodyUnits::METRES,
    )
    .map_err(|e| e.to_string())
}

/// A joint array `(T, J, 3)` in metres: with its bones when `J` is a known SMPL layout (22, 24,
/// 52 or 55 joints), with the position bounds alone otherwise.
pub fn joint_array<T: Copy + Into<f64>>(positions: &[T], joints: usize) -> Result<(), String> {
    let (parents, names): (Option<&[i32]>, Option<&[&str]>) = match joints {
        22 | 24 => (
            Some(&SMPL24_PARENTS[..joints]),
            Some(&SMPL24_NAMES[..joints]),
        ),
        52 => (Some(&SMPLH52_PARENTS), Some(&SMPLH52_NAMES)),
        55 => (Some(&SMPLX55_PARENTS), Some(&SMPLX55_NAMES)),
        _ => (None, None),
    };
    check_body(positions, joints, parents, names, BodyUnits::METRES).map_err(|e| e.to_string())
}

/// A BVH's world joints, in its own units (scaled by its rest pose).
pub fn bvh(b: &Bvh) -> Result<(), String> {
    let (_, joints, positions) = bvh_world_positions(b, 1.0).map_err(|e| e.to_string())?;
    let parents: Vec<i32> = b
        .joints
        .iter()
        .map(|j| j.parent.map_or(-1, |p| p as i32))
        .collect();
    let names: Vec<&str> = b.joints.iter().map(|j| j.name.as_str()).collect();
    let units = BodyUnits {
        per_metre: bvh_units_per_metre(b),
    };
    check_body(&positions, joints, Some(&parents), Some(&names), units).map_err(|e| e.to_string())
}

/// File units per metre of a BVH: its rest pose's largest extent along any axis (the height of
/// a standing or T-posed person, or the arm span) over [`REST_POSE_HEIGHT_M`]; metres when the
/// rest pose has no extent.
fn bvh_units_per_metre(b: &Bvh) -> f64 {
    let mut rest = b.clone();
    rest.frames = 1;
    rest.data = vec![0.0; b.num_channels()];
    let Ok((_, points)) = bvh_world_transforms(&rest, 1.0) else {
        return 1.0;
    };
    let extent = (0..3)
        .map(|k| {
            let (lo, hi) = points.iter().fold((f64::MAX, f64::MIN), |(lo, hi), p| {
                (lo.min(p[k]), hi.max(p[k]))
            });
            hi - lo
        })
        .fold(0.0f64, f64::max);
    if extent.is_finite() && extent > 0.0 {
        extent / REST_POSE_HEIGHT_M
    } else {
        1.0
    }
}
