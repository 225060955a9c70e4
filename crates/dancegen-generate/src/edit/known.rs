//! What is known of a dance being made: per frame, which joints' rotations and which parts of
//! the root's position, with their values. Every edit operation ends here, and every system
//! applies it in its own sampler.

use dancegen_motion::repr::motion::{POSE_DIMS, SMPL_JOINTS};
use dancegen_motion::repr::{Edge151, SmplMotion};

use crate::error::GenerateError;

/// Every joint's bit in [`KnownParts::joints`].
pub const ALL_JOINTS: u32 = (1 << SMPL_JOINTS) - 1;

/// EDGE-151 root channels: the Z-up root is the Y-up `(x, −z, y)`, so the floor position is
/// the first two and the height the third.
const EDGE_ROOT_HORIZONTAL: [usize; 2] = [Edge151::ROOT.start, Edge151::ROOT.start + 1];
const EDGE_ROOT_HEIGHT: usize = Edge151::ROOT.start + 2;

/// What is known of a dance (module documentation): `motion` holds the values (SMPL 24, Y-up,
/// metres, 30 fps); per frame, `joints` has bit `j` set where joint `j`'s rotation is known
/// (the root's orientation is joint 0), `root_horizontal` whether the pelvis's floor position
/// (x, z) is, and `root_height` whether its height (y) is.
#[derive(Clone, Debug)]
pub struct KnownParts {
    pub motion: SmplMotion,
    pub joints: Vec<u32>,
    pub root_horizontal: Vec<bool>,
    pub root_height: Vec<bool>,
    /// Whether `motion` is a real dance in every frame (the dance being edited), rather than
    /// values only where they are known.
    pub whole: bool,
}

impl KnownParts {
    /// Everything of `motion` known (a real dance in every frame).
    pub fn all(motion: SmplMotion) -> Self {
        let t = motion.frames();
        Self {
            motion,
            joints: vec![ALL_JOINTS; t],
            root_horizontal: vec![true; t],
            root_height: vec![true; t],
            whole: true,
        }
    }

    /// Nothing known yet; `motion` gives the frame count and room for values ([`Self::set`]).
    pub fn none(motion: SmplMotion) -> Self {
        let t = motion.frames();
        Self {
            motion,
            joints: vec![0; t],
            root_horizontal: vec![false; t],
            root_height: vec![false; t],
            whole: false,
        }
    }

    pub fn frames(&self) -> usize {
        self.joints.len()
    }

    /// Whether frame `f` is kept whole.
    pub fn kept(&self, f: usize) -> bool {
        self.joints[f] == ALL_JOINTS && self.root_horizontal[f] && self.root_height[f]
    }

    /// Whether anything of frame `f` is known.
    pub fn touched(&self, f: usize) -> bool {
        self.joints[f] != 0 || self.root_horizontal[f] || self.root_height[f]
    }

    /// Frames to make, at least partly.
    pub fn frames_to_make(&self) -> usize {
        (0..self.frames()).filter(|&f| !self.kept(f)).count()
    }

    /// Marks frame `f`'s joints `joints` and the root parts given as known, with the values
    /// of `pose` (72 axis-angle values) and `trans` (Y-up).
    pub fn set(&mut self, f: usize, joints: u32, root: [bool; 2], pose: &[f32], trans: [f32; 3]) {
        for j in (0..SMPL_JOINTS).filter(|j| joints & (1 << j) != 0) {
            let at = f * POSE_DIMS + 3 * j;
            self.motion.poses[at..at + 3].copy_from_slice(&pose[3 * j..3 * j + 3]);
        }
        self.joints[f] |= joints;
        if root[0] {
            self.motion.trans[f * 3] = trans[0];
            self.motion.trans[f * 3 + 2] = trans[2];
            self.root_horizontal[f] = true;
        }
        if root[1] {
            self.motion.trans[f * 3 + 1] = trans[1];
            self.root_height[f] = true;
        }
    }

    /// The known values in EDGE-151 (raw, Z-up) and their channel mask, for systems that
    /// sample in it. A whole kept frame is known in every channel, its foot contacts included
    /// where the next frame is kept too; a partly known frame in its joints' 6D channels and
    /// its known root channels.
    pub fn edge151(&self) -> Result<(Vec<f32>, Vec<f32>), GenerateError> {
        let mut values = Edge151::encode(&self.motion)
            .map_err(|e| GenerateError::Generation(format!("encoding the known motion: {e}")))?;
        let d = Edge151::DIMS;
        let mut mask = vec![0f32; values.len()];
        for f in 0..self.frames() {
            let row = &mut mask[f * d..(f + 1) * d];
            if self.kept(f) {
                row.fill(1.0);
                // Contacts come from the step to the next frame (the last frame: EDGE's 1).
                // Where that frame holds no real value, a kept frame takes the contacts of the
                // kept frame before it (the last frame of a continued motion), and a lone
                // kept frame (a keyframe's whole pose) leaves them to be made.
                let t = self.frames();
                let next_real = self.whole
                    || if f + 1 < t {
                        self.kept(f + 1)
                    } else {
                        f > 0 && self.kept(f - 1)
                    };
                if !next_real {
                    if f > 0 && self.kept(f - 1) {
                        let (before, here) = values.split_at_mut(f * d);
                        here[Edge151::CONTACTS]
                            .copy_from_slice(&before[(f - 1) * d..][Edge151::CONTACTS]);
                    } else {
                        mask[f * d..][Edge151::CONTACTS].fill(0.0);
                    }
                }
                continue;
            }
            for j in 0..SMPL_JOINTS {
                if self.joints[f] & (1 << j) != 0 {
                    let at = Edge151::ROT6D.start + 6 * j;
                    row[at..at + 6].fill(1.0);
                }
            }
            if self.root_horizontal[f] {
                for c in EDGE_ROOT_HORIZONTAL {
                    row[c] = 1.0;
                }
            }
            if self.root_height[f] {
                row[EDGE_ROOT_HEIGHT] = 1.0;
            }
        }
        Ok((values, mask))
    }

    /// Writes every known value into `generated` (the same frame count), so that what was
    /// known is kept exactly.
    pub fn splice(&self, generated: &mut SmplMotion) {
        assert_eq!(generated.frames(), self.frames(), "one value per frame");
        for f in 0..self.frames() {
            for j in 0..SMPL_JOINTS {
                if self.joints[f] & (1 << j) != 0 {
                    let at = f * POSE_DIMS + 3 * j;
                    generated.poses[at..at + 3].copy_from_slice(&self.motion.poses[at..at + 3]);
                }
            }
            for (axis, known) in [
                (0, self.root_horizontal[f]),
                (1, self.root_height[f]),
                (2, self.root_horizontal[f]),
            ] {
                if known {
                    generated.trans[f * 3 + axis] = self.motion.trans[f * 3 + axis];
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn root_parts_map_to_their_edge151_channels_and_splice_alone() {
        let t = 3;
        let motion = SmplMotion::new(30.0, vec![0.0; t * POSE_DIMS], vec![0.0; t * 3]).unwrap();
        let mut k = KnownParts::none(motion);
        let pose: Vec<f32> = (0..POSE_DIMS).map(|i| i as f32 * 0.001).collect();
        k.set(0, 1 << 4, [true, false], &pose, [1.0, 2.0, 3.0]);
        k.set(1, 0, [false, true], &pose, [4.0, 5.0, 6.0]);
        assert!(k.touched(0) && k.touched(1) && !k.touched(2) && !k.kept(0));
        let (values, mask) = k.edge151().unwrap();
        let d = Edge151::DIMS;
        let root = Edge151::ROOT.start;
        assert_eq!(mask[root..root + 3], [1.0, 1.0, 0.0]);
        assert_eq!(mask[d + root..d + root + 3], [0.0, 0.0, 1.0]);
        // Y-up (1, _, 3) is Z-up (1, -3, _); the height 5 is the third channel.
        assert_eq!(values[root..root + 2], [1.0, -3.0]);
        assert_eq!(values[d + root + 2], 5.0);
        let knee = Edge151::ROT6D.start + 6 * 4;
        assert!(mask[knee..knee + 6].iter().all(|&m| m == 1.0) && mask[knee + 6] == 0.0);
        let mut g = SmplMotion::new(30.0, vec![9.0; t * POSE_DIMS], vec![9.0; t * 3]).unwrap();
        k.splice(&mut g);
        assert_eq!(g.trans, vec![1.0, 9.0, 3.0, 9.0, 5.0, 9.0, 9.0, 9.0, 9.0]);
        assert_eq!(g.poses[12..15], pose[12..15]);
        assert_eq!(g.poses[15], 9.0);
    }

    #[test]
    fn a_lone_kept_frame_leaves_its_contacts_to_be_made() {
        let t = 5;
        let motion = SmplMotion::new(30.0, vec![0.1; t * POSE_DIMS], vec![0.0; t * 3]).unwrap();
        let mut k = KnownParts::none(motion);
        let pose = vec![0.2; POSE_DIMS];
        for f in [1, 3, 4] {
            k.set(f, ALL_JOINTS, [true, true], &pose, [0.0, 0.9, 0.0]);
        }
        let (_, mask) = k.edge151().unwrap();
        let d = Edge151::DIMS;
        let contacts = |f: usize| mask[f * d + Edge151::CONTACTS.start];
        assert_eq!([contacts(1), contacts(3), contacts(4)], [0.0, 1.0, 1.0]);
        // The last of a block of kept frames before unknown ones takes its contacts from the
        // frame before it.
        k.set(2, ALL_JOINTS, [true, true], &pose, [0.0, 0.9, 0.0]);
        k.joints[3] = 0;
        let (values, mask) = k.edge151().unwrap();
        let c = Edge151::CONTACTS;
        assert_eq!(mask[2 * d + c.start], 1.0);
        assert_eq!(values[2 * d..][c.clone()], values[d..][c]);
        assert_eq!(mask[d + Edge151::ROOT.start], 1.0);
    }
}
