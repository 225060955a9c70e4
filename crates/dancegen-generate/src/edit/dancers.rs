//! A group's edit, dancer by dancer: the group system asks each dancer's [`KnownParts`] of an
//! [`Edit`] whose given motions are that dancer's.

use super::{Edit, GivenMotion, KeepJoints};
use crate::error::GenerateError;

impl Edit {
    /// Dancers of the motions given to the edit (1 when none holds a group).
    pub fn given_dancers(&self) -> usize {
        self.givens()
            .iter()
            .map(|(_, g)| g.dancers())
            .max()
            .unwrap_or(1)
    }

    fn givens(&self) -> Vec<(&'static str, &GivenMotion)> {
        let mut v = Vec::new();
        if let Some(b) = &self.base {
            v.push(("--edit", b));
        }
        if let Some(c) = &self.continue_from {
            v.push(("--continue-from", c));
        }
        if let Some(k) = &self.keep_joints {
            v.push(("--from", &k.from));
        }
        v
    }

    /// A one-dancer edit must not be given a group (it would use the group's first dancer).
    pub(crate) fn check_one_dancer(&self) -> Result<(), GenerateError> {
        match self.givens().into_iter().find(|(_, g)| g.dancers() > 1) {
            Some((flag, g)) => Err(GenerateError::Invalid(format!(
                "{flag} {}: {} dancers; a group is edited with --system group",
                g.label,
                g.dancers()
            ))),
            None => Ok(()),
        }
    }

    /// The edit of dancer `d` of a group of `n`: the dance being edited and the motion being
    /// continued must be groups of `n` (each dancer keeps its own); the motion of
    /// `--keep-joints` gives each dancer its own, or one dancer's joints to every dancer
    /// (not its root: the dancers would stand on one spot). Keyframes are reached by every
    /// dancer where it stands; `--keyframe-root` and `--path` would put every dancer on one
    /// spot and are refused (a group's paths are its `--formation`).
    pub fn for_dancer(&self, d: usize, n: usize) -> Result<Edit, GenerateError> {
        let bad = |m: String| Err(GenerateError::Invalid(m));
        for (flag, g) in self.givens() {
            let whole = flag != "--from";
            if (whole || g.dancers() > 1) && g.dancers() != n {
                return bad(format!(
                    "{flag} {}: {} dancer{}, and this group dance has {n}{}",
                    g.label,
                    g.dancers(),
                    if g.dancers() == 1 { "" } else { "s" },
                    if whole {
                        " (give the group's files: the .npz files a group dance wrote, or \
                         --dancers to match)"
                    } else {
                        ""
                    }
                ));
            }
        }
        if let Some(k) = &self.keep_joints
            && k.root
            && k.from.dancers() == 1
        {
            return bad(format!(
                "--keep-joints {} --from {}: one dancer's root for every dancer of a group \
                 would put them all on one spot; give a group's motion (one file per dancer)",
                k.spec, k.from.label
            ));
        }
        if self.keyframe_root {
            return bad(
                "--keyframe-root puts the dancer at the pose's place; in a group every dancer \
                 would stand there (leave it out: each dancer reaches the pose where it is)"
                    .into(),
            );
        }
        if let Some(p) = &self.path {
            return bad(format!(
                "--path {}: a group's paths are its formation; give it as --formation",
                p.label
            ));
        }
        Ok(Edit {
            base: self.base.as_ref().map(|b| b.dancer(d)),
            continue_from: self.continue_from.as_ref().map(|c| c.dancer(d)),
            keep_joints: self.keep_joints.as_ref().map(|k| KeepJoints {
                spec: k.spec.clone(),
                joints: k.joints,
                root: k.root,
                from: k.from.dancer(d),
            }),
            ..self.clone()
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use dancegen_motion::repr::SmplMotion;
    use dancegen_motion::repr::motion::POSE_DIMS;

    fn motion(frames: usize, x: f32) -> SmplMotion {
        SmplMotion::new(30.0, vec![0.0; frames * POSE_DIMS], vec![x; frames * 3]).unwrap()
    }

    fn group(n: usize) -> GivenMotion {
        let dancers = (0..n)
            .map(|d| GivenMotion::one(format!("g_{d}.npz"), motion(60, d as f32)))
            .collect();
        GivenMotion::of_group("g.npz".into(), dancers).unwrap()
    }

    #[test]
    fn each_dancer_gets_its_own_motion_and_counts_must_match() {
        let e = Edit {
            base: Some(group(3)),
            regenerate: vec![[0.5, 1.5]],
            ..Edit::default()
        };
        assert_eq!(e.given_dancers(), 3);
        assert!(e.check_one_dancer().is_err());
        let two = e.for_dancer(2, 3).unwrap();
        assert_eq!(two.base.as_ref().unwrap().motion.trans[0], 2.0);
        assert_eq!(two.given_dancers(), 1);
        assert_eq!(two.regenerate, vec![[0.5, 1.5]]);
        let err = e.for_dancer(0, 4).unwrap_err().to_string();
        assert!(err.contains("3 dancers") && err.contains("has 4"), "{err}");
    }

    #[test]
    fn one_dancers_joints_go_to_every_dancer_but_not_its_root() {
        let keep = |root: bool| Edit {
            keep_joints: Some(KeepJoints {
                spec: if root { "lower" } else { "arms" }.into(),
                joints: 1 << 16,
                root,
                from: GivenMotion::one("me.bvh".into(), motion(60, 7.0)),
            }),
            ..Edit::default()
        };
        let arms = keep(false).for_dancer(1, 3).unwrap();
        assert_eq!(arms.keep_joints.unwrap().from.motion.trans[0], 7.0);
        let err = keep(true).for_dancer(1, 3).unwrap_err().to_string();
        assert!(err.contains("one spot") && err.contains("me.bvh"), "{err}");
    }

    #[test]
    fn groups_of_unequal_length_are_refused() {
        let dancers = vec![
            GivenMotion::one("a".into(), motion(60, 0.0)),
            GivenMotion::one("b".into(), motion(59, 0.0)),
        ];
        let err = GivenMotion::of_group("g".into(), dancers)
            .unwrap_err()
            .to_string();
        assert!(err.contains("60 frames") && err.contains("59"), "{err}");
    }
}
