//! Editing a dance (issue 44): the one notion of what is already known of the dance being
//! made, shared by every front end and every system.
//!
//! A front end describes an [`Edit`] (the dance being edited and the ranges to make new,
//! or a motion to continue). The generator turns it into [`KnownParts`] for the frames of the
//! job: per frame, which joints' rotations and whether the root's position are known, with
//! their values, in the canonical [`SmplMotion`] (Y-up, metres, 30 fps). Each system converts
//! them to its own representation and applies them in its own sampler (the solo system:
//! `dancegen_lodgepp::inpaint`), then [`KnownParts::splice`] copies the known values into the
//! result, so kept frames are the input's exactly, whatever the sampler did.

use std::path::Path;

use dancegen_formats::dispatch::{
    ConvertOptions, LoadOptions, LoadedMotion, convert_motion, load_motion_file_with,
};
use dancegen_motion::repr::motion::{POSE_DIMS, SMPL_JOINTS};
use dancegen_motion::repr::{Edge151, SmplMotion};

use crate::error::GenerateError;
use crate::song::FPS;

/// The operations, as [`Edit::operations`] and `DanceSystem::EDITS` name them.
pub const REGENERATE: &str = "--edit/--regenerate";
pub const CONTINUE: &str = "--continue-from";
pub const KEEP_JOINTS: &str = "--keep-joints";

/// Shortest range `--regenerate` accepts: shorter is a twitch, not a new phrase.
pub const MIN_RANGE_SECONDS: f64 = 0.5;
/// How much of a motion `--continue-from` keeps at the start of the new dance.
pub const CONTINUE_SECONDS: f64 = 1.0;

/// One dancer's motion given to a job (a leader, a dance to edit, a motion to continue): SMPL 24
/// at 30 fps, with the name messages use for it (its file).
#[derive(Clone, Debug)]
pub struct GivenMotion {
    pub label: String,
    pub motion: SmplMotion,
}

impl GivenMotion {
    /// `path` as one dancer at 30 fps, or an error naming the file and `what` it is for. Any
    /// format `convert` reads; a humanoid BVH is retargeted. `source_fps` overrides the file's
    /// rate; a file without a usable rate is refused with `rate_hint` as the way to give one.
    pub fn load(
        path: &Path,
        what: &str,
        source_fps: Option<f64>,
        rate_hint: &'static str,
    ) -> Result<Self, GenerateError> {
        let invalid = |why: String| GenerateError::Invalid(format!("{}: {why}", path.display()));
        let read = LoadOptions {
            source_fps,
            rate_hint,
        };
        let loaded = load_motion_file_with(path, &read)?;
        let opts = ConvertOptions {
            to_smpl24: true,
            fps: Some(FPS as f32),
            ..Default::default()
        };
        // The conversion's error already names the file.
        let m = match convert_motion(path, loaded, &opts).map_err(|e| {
            GenerateError::Invalid(format!(
                "{e} ({what} must be one humanoid dancer that retargets to SMPL 24)"
            ))
        })? {
            LoadedMotion::Smpl(m) => m,
            LoadedMotion::Group(g) => {
                return Err(invalid(format!(
                    "{} dancers; {what} must be one dancer",
                    g.len()
                )));
            }
            other => {
                return Err(invalid(format!(
                    "a {} has no joint rotations for {what} (give SMPL motion or a humanoid BVH)",
                    other.kind()
                )));
            }
        };
        if m.poses.iter().chain(&m.trans).any(|v| !v.is_finite()) {
            return Err(invalid("the motion holds NaN or infinite values".into()));
        }
        Ok(Self {
            label: path.display().to_string(),
            motion: m,
        })
    }

    fn seconds(&self) -> f64 {
        self.motion.frames() as f64 / f64::from(FPS)
    }
}

/// What a job keeps of existing motion (module documentation). The default keeps nothing: a
/// plain generation.
#[derive(Clone, Debug, Default)]
pub struct Edit {
    /// `--edit`: the dance being edited. Every frame outside [`Edit::regenerate`] is kept, and
    /// the new dance has its length.
    pub base: Option<GivenMotion>,
    /// `--regenerate A-B`: seconds from the dance's start to make new.
    pub regenerate: Vec<[f64; 2]>,
    /// `--continue-from`: the new dance starts with this motion's last [`CONTINUE_SECONDS`],
    /// unchanged, and continues from there.
    pub continue_from: Option<GivenMotion>,
    /// `--keep-joints SET --from MOTION`: those joints' rotations (and with `lower` the root)
    /// are MOTION's for the whole dance; the rest is made to go with them and the music.
    pub keep_joints: Option<KeepJoints>,
}

/// What `--keep-joints` keeps, and from which motion.
#[derive(Clone, Debug)]
pub struct KeepJoints {
    /// As the user wrote it, for messages.
    pub spec: String,
    /// Bit `j` set: joint `j`'s rotation is kept.
    pub joints: u32,
    /// The pelvis position is kept too (`lower`).
    pub root: bool,
    pub from: GivenMotion,
}

/// SMPL 24 joints of the named sets of `--keep-joints`.
const LEGS: [usize; 8] = [1, 2, 4, 5, 7, 8, 10, 11];
const ARMS: [usize; 10] = [13, 14, 16, 17, 18, 19, 20, 21, 22, 23];
const SPINE_AND_HEAD: [usize; 4] = [3, 6, 9, 12];
const HEAD: usize = 15;

/// Long names of the SMPL 24 joints that differ from SMPL-X's (whose first 22 are the body's,
/// `dancegen_motion::skeleton::SMPLX55_NAMES`): SMPL's last two are the hands.
const SMPL_HANDS: [&str; 2] = ["left_hand", "right_hand"];

/// Joint `j`'s long name (`left_knee`), as SMPL-X and most tools write it.
fn long_name(j: usize) -> &'static str {
    match j {
        22 | 23 => SMPL_HANDS[j - 22],
        _ => dancegen_motion::skeleton::SMPLX55_NAMES[j],
    }
}

/// The joints (bit mask) and whether the root is kept for a `--keep-joints` value: `upper`,
/// `lower` (legs, pelvis rotation and root position), `arms`, `legs`, or SMPL joint names
/// separated by commas (`left_knee` or `lknee`; `pelvis`/`root` keeps the pelvis rotation).
pub fn parse_joint_set(spec: &str) -> Result<(u32, bool), String> {
    let bits = |js: &[usize]| js.iter().fold(0u32, |m, &j| m | 1 << j);
    match spec.trim() {
        "lower" => return Ok((bits(&LEGS) | 1, true)),
        "legs" => return Ok((bits(&LEGS), false)),
        "arms" => return Ok((bits(&ARMS), false)),
        "upper" => return Ok((bits(&ARMS) | bits(&SPINE_AND_HEAD) | 1 << HEAD, false)),
        _ => {}
    }
    let short = dancegen_motion::skeleton::SMPL24_NAMES;
    let mut mask = 0u32;
    for name in spec.split(',').map(str::trim).filter(|n| !n.is_empty()) {
        let j = (0..24)
            .position(|j| long_name(j).eq_ignore_ascii_case(name))
            .or_else(|| short.iter().position(|n| n.eq_ignore_ascii_case(name)))
            .ok_or_else(|| {
                format!(
                    "--keep-joints: {name:?} is not a joint of the SMPL 24 skeleton (use upper, \
                     lower, arms, legs, or names such as {})",
                    (0..24).map(long_name).collect::<Vec<_>>().join(", ")
                )
            })?;
        mask |= 1 << j;
    }
    if mask == 0 {
        return Err("--keep-joints: name a set (upper, lower, arms, legs) or joints".into());
    }
    Ok((mask, false))
}

impl Edit {
    /// Whether this is a plain generation.
    pub fn is_empty(&self) -> bool {
        self.base.is_none()
            && self.regenerate.is_empty()
            && self.continue_from.is_none()
            && self.keep_joints.is_none()
    }

    /// The operations asked for, as the flags name them (for "not supported" messages).
    pub fn operations(&self) -> Vec<&'static str> {
        let mut ops = Vec::new();
        if self.base.is_some() {
            ops.push(REGENERATE);
        }
        if self.continue_from.is_some() {
            ops.push(CONTINUE);
        }
        if self.keep_joints.is_some() {
            ops.push(KEEP_JOINTS);
        }
        ops
    }

    /// Seconds of the edited dance, when the edit fixes them (the dance being edited).
    pub fn seconds(&self) -> Option<f64> {
        self.base.as_ref().map(GivenMotion::seconds)
    }

    /// Frames of the `--keep-joints --from` motion, which a dance cannot outlast.
    pub fn kept_joints_frames(&self) -> Option<usize> {
        self.keep_joints.as_ref().map(|k| k.from.motion.frames())
    }

    /// Checks the edit on its own (before the song is read): ranges inside the dance, in
    /// order, not overlapping, each at least [`MIN_RANGE_SECONDS`].
    pub fn check(&self) -> Result<(), GenerateError> {
        let bad = |m: String| Err(GenerateError::Invalid(m));
        match (&self.base, self.regenerate.is_empty()) {
            (None, false) => {
                return bad("--regenerate needs the dance to edit: --edit DANCE".into());
            }
            (Some(b), true) => {
                return bad(format!(
                    "--edit {}: say what to make new with --regenerate A-B (seconds)",
                    b.label
                ));
            }
            _ => {}
        }
        if let (Some(_), Some(c)) = (&self.base, &self.continue_from) {
            return bad(format!(
                "--continue-from {} and --edit both give the dance's start; use one",
                c.label
            ));
        }
        if let Some(k) = &self.keep_joints
            && (self.base.is_some() || self.continue_from.is_some())
        {
            return bad(format!(
                "--keep-joints {} with --edit or --continue-from is not supported yet; use it \
                 on its own",
                k.spec
            ));
        }
        if let Some(b) = &self.base {
            let len = b.seconds();
            let mut ranges = self.regenerate.clone();
            ranges.sort_by(|x, y| x[0].total_cmp(&y[0]));
            for [a, e] in &ranges {
                let name = format!("--regenerate {a}-{e}");
                if !(a.is_finite() && e.is_finite()) || a >= e {
                    return bad(format!(
                        "{name}: give START-END in seconds with START < END"
                    ));
                }
                if *a < 0.0 || *e > len + 0.5 / f64::from(FPS) {
                    return bad(format!(
                        "{name}: outside the dance, which is {len:.2} s long ({})",
                        b.label
                    ));
                }
                if e - a < MIN_RANGE_SECONDS {
                    return bad(format!(
                        "{name}: {:.2} s; a range must be at least {MIN_RANGE_SECONDS} s",
                        e - a
                    ));
                }
            }
            for w in ranges.windows(2) {
                if w[1][0] < w[0][1] {
                    return bad(format!(
                        "--regenerate {}-{} and {}-{} overlap; give each part once",
                        w[0][0], w[0][1], w[1][0], w[1][1]
                    ));
                }
            }
        }
        if let Some(c) = &self.continue_from
            && c.seconds() + 0.5 / f64::from(FPS) < CONTINUE_SECONDS
        {
            return bad(format!(
                "--continue-from {}: {:.2} s of motion; it needs at least {CONTINUE_SECONDS} s",
                c.label,
                c.seconds()
            ));
        }
        Ok(())
    }

    /// What is known of a dance of `frames` frames (30 fps), `None` for a plain generation.
    pub fn known(&self, frames: usize) -> Result<Option<KnownParts>, GenerateError> {
        self.check()?;
        if let Some(b) = &self.base {
            let have = b.motion.frames();
            if frames != have {
                return Err(GenerateError::Invalid(format!(
                    "--edit {}: the dance has {have} frames but the song gives {frames} from \
                     --start (give the song and --start it was made for)",
                    b.label
                )));
            }
            let mut k = KnownParts::all(b.motion.clone());
            for &[a, e] in &self.regenerate {
                let (fa, fe) = (seconds_to_frame(a, frames), seconds_to_frame(e, frames));
                for f in fa..fe {
                    k.joints[f] = 0;
                    k.root[f] = false;
                }
            }
            return Ok(Some(k));
        }
        if let Some(c) = &self.continue_from {
            let keep = (CONTINUE_SECONDS * f64::from(FPS)).round() as usize;
            if frames <= keep {
                return Err(GenerateError::Invalid(format!(
                    "--continue-from {}: the song part is {:.2} s; it must be longer than the \
                     {CONTINUE_SECONDS} s kept from the motion",
                    c.label,
                    frames as f64 / f64::from(FPS)
                )));
            }
            let src = &c.motion;
            let from = src.frames() - keep;
            let mut poses = vec![0f32; frames * POSE_DIMS];
            let mut trans = vec![0f32; frames * 3];
            poses[..keep * POSE_DIMS].copy_from_slice(&src.poses[from * POSE_DIMS..]);
            trans[..keep * 3].copy_from_slice(&src.trans[from * 3..]);
            let motion = SmplMotion::new(FPS as f32, poses, trans)
                .map_err(|e| GenerateError::Invalid(format!("--continue-from {}: {e}", c.label)))?;
            let mut k = KnownParts::none(motion);
            for f in 0..keep {
                k.joints[f] = ALL_JOINTS;
                k.root[f] = true;
            }
            return Ok(Some(k));
        }
        if let Some(k) = &self.keep_joints {
            let src = &k.from.motion;
            if src.frames() < frames {
                return Err(GenerateError::Invalid(format!(
                    "--from {}: {:.2} s of motion for a dance of {:.2} s (give --end, or a \
                     longer motion)",
                    k.from.label,
                    src.frames() as f64 / f64::from(FPS),
                    frames as f64 / f64::from(FPS)
                )));
            }
            let motion = SmplMotion::new(
                FPS as f32,
                src.poses[..frames * POSE_DIMS].to_vec(),
                src.trans[..frames * 3].to_vec(),
            )
            .map_err(|e| GenerateError::Invalid(format!("--from {}: {e}", k.from.label)))?;
            let mut known = KnownParts::none(motion);
            known.joints.fill(k.joints);
            known.root.fill(k.root);
            return Ok(Some(known));
        }
        Ok(None)
    }
}

/// Frame index of `seconds` in a dance of `frames` frames.
fn seconds_to_frame(seconds: f64, frames: usize) -> usize {
    ((seconds * f64::from(FPS)).round().max(0.0) as usize).min(frames)
}

/// Every joint's bit in [`KnownParts::joints`].
pub const ALL_JOINTS: u32 = (1 << SMPL_JOINTS) - 1;

/// What is known of a dance (module documentation): `motion` holds the values; per frame,
/// `joints` has bit `j` set where joint `j`'s rotation is known (the root's is joint 0) and
/// `root` is whether the pelvis position is.
#[derive(Clone, Debug)]
pub struct KnownParts {
    pub motion: SmplMotion,
    pub joints: Vec<u32>,
    pub root: Vec<bool>,
}

impl KnownParts {
    /// Everything of `motion` known.
    pub fn all(motion: SmplMotion) -> Self {
        let t = motion.frames();
        Self {
            motion,
            joints: vec![ALL_JOINTS; t],
            root: vec![true; t],
        }
    }

    /// Nothing known yet; `motion` gives the frame count and room for values.
    pub fn none(motion: SmplMotion) -> Self {
        let t = motion.frames();
        Self {
            motion,
            joints: vec![0; t],
            root: vec![false; t],
        }
    }

    pub fn frames(&self) -> usize {
        self.root.len()
    }

    /// Whether frame `f` is kept whole.
    pub fn kept(&self, f: usize) -> bool {
        self.joints[f] == ALL_JOINTS && self.root[f]
    }

    /// Frames to make, at least partly.
    pub fn frames_to_make(&self) -> usize {
        (0..self.frames()).filter(|&f| !self.kept(f)).count()
    }

    /// The known values in EDGE-151 (raw, Z-up) and their channel mask, for systems that
    /// sample in it. A whole kept frame is known in every channel, its foot contacts included;
    /// a partly known frame in its joints' 6D channels and, with its root, the root position.
    pub fn edge151(&self) -> Result<(Vec<f32>, Vec<f32>), GenerateError> {
        let values = Edge151::encode(&self.motion)
            .map_err(|e| GenerateError::Generation(format!("encoding the known motion: {e}")))?;
        let d = Edge151::DIMS;
        let mut mask = vec![0f32; values.len()];
        for f in 0..self.frames() {
            let row = &mut mask[f * d..(f + 1) * d];
            if self.kept(f) {
                row.fill(1.0);
                continue;
            }
            for j in 0..SMPL_JOINTS {
                if self.joints[f] & (1 << j) != 0 {
                    let at = Edge151::ROT6D.start + 6 * j;
                    row[at..at + 6].fill(1.0);
                }
            }
            if self.root[f] {
                row[Edge151::ROOT].fill(1.0);
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
            if self.root[f] {
                generated.trans[f * 3..f * 3 + 3]
                    .copy_from_slice(&self.motion.trans[f * 3..f * 3 + 3]);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn given(frames: usize) -> GivenMotion {
        let poses = (0..frames * POSE_DIMS)
            .map(|i| (i % 7) as f32 * 0.01)
            .collect();
        let trans = (0..frames * 3).map(|i| i as f32 * 0.001).collect();
        GivenMotion {
            label: "base.npz".into(),
            motion: SmplMotion::new(30.0, poses, trans).unwrap(),
        }
    }

    fn regenerate(ranges: &[[f64; 2]]) -> Edit {
        Edit {
            base: Some(given(300)),
            regenerate: ranges.to_vec(),
            ..Edit::default()
        }
    }

    #[test]
    fn ranges_are_checked_with_the_flag_in_the_message() {
        for (ranges, words) in [
            (vec![[2.0, 12.0]], "outside the dance"),
            (vec![[-1.0, 2.0]], "outside the dance"),
            (vec![[3.0, 3.2]], "at least 0.5 s"),
            (vec![[4.0, 3.0]], "START < END"),
            (vec![[1.0, 4.0], [3.0, 6.0]], "overlap"),
            (vec![[f64::NAN, 4.0]], "START < END"),
        ] {
            let e = regenerate(&ranges).check().unwrap_err().to_string();
            assert!(
                e.contains("--regenerate") && e.contains(words),
                "{ranges:?}: {e}"
            );
        }
        assert!(regenerate(&[[1.0, 4.0], [4.0, 6.0]]).check().is_ok());
        assert!(
            regenerate(&[])
                .check()
                .unwrap_err()
                .to_string()
                .contains("--regenerate A-B")
        );
        let e = Edit {
            regenerate: vec![[1.0, 2.0]],
            ..Edit::default()
        };
        assert!(e.check().unwrap_err().to_string().contains("--edit DANCE"));
    }

    #[test]
    fn a_regenerated_range_is_unknown_and_the_rest_spliced_back_exactly() {
        let edit = regenerate(&[[2.0, 4.0]]);
        let k = edit.known(300).unwrap().unwrap();
        assert_eq!(k.frames_to_make(), 60);
        assert!(k.kept(59) && !k.kept(60) && !k.kept(119) && k.kept(120));
        let mut generated = SmplMotion::new(30.0, vec![0.5; 300 * 72], vec![9.0; 900]).unwrap();
        k.splice(&mut generated);
        let base = &edit.base.as_ref().unwrap().motion;
        assert_eq!(generated.poses[..60 * 72], base.poses[..60 * 72]);
        assert_eq!(generated.trans[120 * 3..], base.trans[120 * 3..]);
        assert!(generated.poses[60 * 72..120 * 72].iter().all(|&v| v == 0.5));
        let (values, mask) = k.edge151().unwrap();
        assert_eq!(values.len(), 300 * 151);
        assert!(mask[..60 * 151].iter().all(|&m| m == 1.0));
        assert!(mask[60 * 151..120 * 151].iter().all(|&m| m == 0.0));
        let e = edit.known(299).unwrap_err().to_string();
        assert!(e.contains("300 frames") && e.contains("--start"), "{e}");
    }

    #[test]
    fn joint_sets_and_names_parse_and_unknown_names_are_refused() {
        let (lower, root) = parse_joint_set("lower").unwrap();
        assert!(root && lower & 1 != 0 && lower & (1 << 4) != 0 && lower & (1 << 20) == 0);
        let (legs, root) = parse_joint_set("legs").unwrap();
        assert!(!root && legs & 1 == 0 && legs.count_ones() == 8);
        let (upper, _) = parse_joint_set("upper").unwrap();
        assert_eq!(upper & legs, 0);
        assert_eq!(
            (upper | legs | 1).count_ones(),
            24,
            "upper + legs + pelvis is everything"
        );
        assert_eq!(
            parse_joint_set("left_knee, rknee").unwrap(),
            ((1 << 4) | (1 << 5), false)
        );
        let e = parse_joint_set("left_knee,tail").unwrap_err();
        assert!(e.contains("\"tail\"") && e.contains("SMPL 24"), "{e}");
        assert!(parse_joint_set(" , ").is_err());
    }

    #[test]
    fn kept_joints_are_known_in_every_frame_and_need_a_long_enough_motion() {
        let (joints, root) = parse_joint_set("lower").unwrap();
        let edit = Edit {
            keep_joints: Some(KeepJoints {
                spec: "lower".into(),
                joints,
                root,
                from: given(100),
            }),
            ..Edit::default()
        };
        let k = edit.known(90).unwrap().unwrap();
        assert!((0..90).all(|f| k.joints[f] == joints && k.root[f] && !k.kept(f)));
        let (_, mask) = k.edge151().unwrap();
        let knee = Edge151::ROT6D.start + 6 * 4;
        let wrist = Edge151::ROT6D.start + 6 * 20;
        assert!(mask[knee] == 1.0 && mask[wrist] == 0.0 && mask[Edge151::ROOT.start] == 1.0);
        let e = edit.known(101).unwrap_err().to_string();
        assert!(e.contains("--from base.npz"), "{e}");
    }

    #[test]
    fn a_continuation_keeps_the_last_second_of_the_motion_first() {
        let edit = Edit {
            continue_from: Some(given(100)),
            ..Edit::default()
        };
        let k = edit.known(200).unwrap().unwrap();
        assert!(k.kept(29) && !k.kept(30));
        let src = &edit.continue_from.as_ref().unwrap().motion;
        assert_eq!(k.motion.poses[..30 * 72], src.poses[70 * 72..]);
        assert_eq!(k.motion.trans[..90], src.trans[210..]);
        let e = edit.known(30).unwrap_err().to_string();
        assert!(e.contains("--continue-from") && e.contains("longer"), "{e}");
        let short = Edit {
            continue_from: Some(given(20)),
            ..Edit::default()
        };
        assert!(
            short
                .check()
                .unwrap_err()
                .to_string()
                .contains("at least 1 s")
        );
    }
}
