//! A made-up dance for the readers' round-trip tests ([`crate::glb_in`], [`crate::fbx_in`]).

use dancegen_motion::repr::motion::POSE_DIMS;

/// Local axis-angle rotations swinging every joint by up to `amplitude` radians per axis (far
/// past a half turn for the FBX's Euler curves to unwrap when large), and a travelling root:
/// `(rotations [frames, 72], root [frames, 3])`.
pub fn turning_dancer(seed: f32, frames: usize, amplitude: f32) -> (Vec<f32>, Vec<f32>) {
    let rot: Vec<f32> = (0..frames * POSE_DIMS)
        .map(|i| amplitude * ((i as f32 * 0.61 + seed).sin()))
        .collect();
    let trans: Vec<f32> = (0..frames * 3)
        .map(|i| seed + (i as f32 * 0.05).sin())
        .collect();
    (rot, trans)
}
