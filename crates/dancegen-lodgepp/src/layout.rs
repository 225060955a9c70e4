//! Which channels of the EDGE-151 frame vector (`dancegen_motion::repr::Edge151`: contacts 4,
//! Z-up root position 3, 24 × 6D) each part of the system reads.
//!
//! Root horizontal position: every PDDM window stores its root x/y (Z-up horizontal plane)
//! relative to the window's first frame, so windows generated in parallel can be placed one
//! after another. In normalised units that is `(x − x_first) / std`, i.e. the normaliser's mean
//! is not added back for those two channels ([`ROOT_HORIZONTAL`]).

pub use dancegen_nn::edge151::{
    CONTACTS, DIMS, FEET, ROOT_HEIGHT, ROOT_HORIZONTAL, ROT6D_START, rot6d,
};

/// The VQ-VAE's "main joints" (paper §3.3.1: root, left/right shoulder, left/right arm,
/// left/right leg), as SMPL 24 indices: pelvis 0, shoulders 16/17, elbows 18/19, hips 1/2. The
/// paper names body parts, not indices; this is our reading.
pub const MAIN_JOINTS: [usize; 7] = [0, 16, 17, 18, 19, 1, 2];
/// Coarse-dance channels (7 × 6D = 42).
pub const MAIN_DIMS: usize = MAIN_JOINTS.len() * 6;

/// Joints compared when retrieving a primitive from the library (D.3 uses hips, knees,
/// shoulders, elbows; the coarse dance has no knees, so: hips, shoulders, elbows). Positions in
/// [`MAIN_JOINTS`].
pub const RETRIEVAL_MAIN: [usize; 6] = [1, 2, 3, 4, 5, 6];

/// The 42 coarse-dance channels, in [`MAIN_JOINTS`] order.
pub fn main_channels() -> Vec<usize> {
    MAIN_JOINTS
        .iter()
        .flat_map(|&j| (0..6).map(move |k| rot6d(j, k)))
        .collect()
}

/// SMPL joints whose rotation places the feet: pelvis 0, hips 1/2, knees 4/5, ankles 7/8,
/// feet 10/11.
pub const LEG_JOINTS: [usize; 9] = [0, 1, 2, 4, 5, 7, 8, 10, 11];

/// The channels that decide where the feet are and whether they touch the floor: contacts,
/// root position and the 6D of [`LEG_JOINTS`] (what the Foot Refine Block may change under
/// `FootRefineScope::Legs`).
pub fn leg_channels() -> Vec<usize> {
    let mut c: Vec<usize> = CONTACTS.chain(ROOT_HORIZONTAL).collect();
    c.push(ROOT_HEIGHT);
    c.extend(
        LEG_JOINTS
            .iter()
            .flat_map(|&j| (0..6).map(move |k| rot6d(j, k))),
    );
    c
}

/// Every channel except the root's horizontal position (what a hard boundary cue fixes at a
/// window's tail, where the absolute position is not known in advance).
pub fn all_but_root_horizontal() -> Vec<usize> {
    (0..DIMS).filter(|c| !ROOT_HORIZONTAL.contains(c)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn main_channels_are_the_6d_of_the_main_joints() {
        let c = main_channels();
        assert_eq!(c.len(), MAIN_DIMS);
        assert_eq!(&c[..6], &[7, 8, 9, 10, 11, 12]);
        assert_eq!(c[6], 7 + 6 * 16);
        assert!(c.iter().all(|&x| x < DIMS));
    }

    #[test]
    fn leg_channels_are_contacts_root_position_and_the_leg_rotations() {
        let c = leg_channels();
        assert_eq!(c.len(), 4 + 3 + 6 * LEG_JOINTS.len());
        assert_eq!(&c[..7], &[0, 1, 2, 3, 4, 5, 6]);
        // Pelvis 6D first, the right foot's (joint 11) last; no arm channel.
        assert_eq!(c[7], rot6d(0, 0));
        assert_eq!(*c.last().unwrap(), rot6d(11, 5));
        assert!(!c.contains(&rot6d(18, 0)) && !c.contains(&rot6d(3, 0)));
    }
}
