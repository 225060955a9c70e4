//! Editing a dance (issue 44): the one notion of what is already known of the dance being
//! made, shared by every front end and every system.
//!
//! A front end describes an [`Edit`]: the dance being edited and the ranges to make new, a
//! motion to continue, joints to keep, poses to reach, a path to follow. The generator turns
//! it into [`KnownParts`] for the frames of the job: per frame, which joints' rotations and
//! which parts of the root's position are known, with their values, in the canonical
//! [`SmplMotion`] (Y-up, metres, 30 fps). Each system converts them to its own representation
//! and applies them in its own sampler (the solo system: `dancegen_lodgepp::inpaint`), then
//! [`KnownParts::splice`] copies the known values into the result, so what was known is the
//! input's exactly, whatever the sampler did.
//!
//! Operations combine where they do not claim the same value: `--keep-joints` joints the
//! regenerated ranges of an `--edit` or the frames after a `--continue-from`, keyframes and a
//! `--path` constrain frames nothing else keeps. Two claims on one value are an error naming
//! both.

mod dancers;
mod given;
mod joints;
mod keyframe;
mod known;

pub use given::{GivenMotion, HolisticGiven, dance_file};
pub use joints::{legs_mask, parse_joint_set, with_ancestors};
pub use keyframe::{KeyframePose, parse_keyframe_spec};
pub use known::{ALL_JOINTS, KnownParts};

use dancegen_motion::repr::SmplMotion;
use dancegen_motion::repr::motion::POSE_DIMS;

use crate::error::GenerateError;
use crate::formation_file::{ANY_SONG_SECONDS, FormationFile};
use crate::song::{AnalysedSong, FPS, Span};

/// The operations, as [`Edit::operations`] and `DanceSystem::EDITS` name them.
pub const REGENERATE: &str = "--edit/--regenerate";
pub const EXTEND: &str = "--edit/--extend";
pub const CONTINUE: &str = "--continue-from";
pub const KEEP_JOINTS: &str = "--keep-joints";
pub const KEYFRAME: &str = "--keyframe";
pub const PATH: &str = "--path";
/// Every operation, in the order tables list them.
pub const OPERATIONS: [&str; 6] = [REGENERATE, EXTEND, CONTINUE, KEEP_JOINTS, KEYFRAME, PATH];

/// Shortest range `--regenerate` accepts: shorter is a twitch, not a new phrase.
pub const MIN_RANGE_SECONDS: f64 = 0.5;
/// How much of a motion `--continue-from` keeps at the start of the new dance.
pub const CONTINUE_SECONDS: f64 = 1.0;

/// What a job keeps of existing motion (module documentation). The default keeps nothing: a
/// plain generation.
#[derive(Clone, Debug, Default)]
pub struct Edit {
    /// `--edit`: the dance being edited. Every frame outside [`Edit::regenerate`] is kept, and
    /// the new dance has its length.
    pub base: Option<GivenMotion>,
    /// `--regenerate A-B`: seconds from the dance's start to make new.
    pub regenerate: Vec<[f64; 2]>,
    /// `--extend`: the dance being edited is kept and danced on to `--end` (the song's end
    /// by default): the web app's "Continue".
    pub extend: bool,
    /// `--continue-from`: the new dance starts with this motion's last [`CONTINUE_SECONDS`],
    /// unchanged, and continues from there.
    pub continue_from: Option<GivenMotion>,
    /// `--keep-joints SET --from MOTION`: those joints' rotations (and with `lower` the root)
    /// are MOTION's for the whole dance; the rest is made to go with them and the music.
    pub keep_joints: Option<KeepJoints>,
    /// `--keyframe POSE@T`: poses reached at song times.
    pub keyframes: Vec<KeyframePose>,
    /// `--keyframe-joints SET`: the joints the keyframes place (default: all), as written and
    /// as a mask.
    pub keyframe_joints: Option<(String, u32)>,
    /// `--keyframe-root`: the keyframes' floor position is reached too (by default the dancer
    /// reaches the pose where it is).
    pub keyframe_root: bool,
    /// `--path PATH.json`: the root's floor positions over time, a FORMATION.json of one
    /// dancer.
    pub path: Option<FormationFile>,
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

impl Edit {
    /// Whether this is a plain generation.
    pub fn is_empty(&self) -> bool {
        self.operations().is_empty()
    }

    /// The operations asked for, as the flags name them (for "not supported" messages).
    pub fn operations(&self) -> Vec<&'static str> {
        [
            (
                !self.regenerate.is_empty() || (self.base.is_some() && !self.extend),
                REGENERATE,
            ),
            (self.extend, EXTEND),
            (self.continue_from.is_some(), CONTINUE),
            (self.keep_joints.is_some(), KEEP_JOINTS),
            (
                !self.keyframes.is_empty() || self.keyframe_joints.is_some() || self.keyframe_root,
                KEYFRAME,
            ),
            (self.path.is_some(), PATH),
        ]
        .into_iter()
        .filter_map(|(asked, op)| asked.then_some(op))
        .collect()
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
    /// order, not overlapping, each at least [`MIN_RANGE_SECONDS`]; keyframe options with
    /// keyframes; a path file that parses.
    pub fn check(&self) -> Result<(), GenerateError> {
        let bad = |m: String| Err(GenerateError::Invalid(m));
        match (&self.base, self.regenerate.is_empty()) {
            (None, false) => {
                return bad("--regenerate needs the dance to edit: --edit DANCE".into());
            }
            (Some(b), true) if !self.extend => {
                return bad(format!(
                    "--edit {}: say what to make new with --regenerate A-B (seconds), or \
                     continue it with --extend",
                    b.label
                ));
            }
            _ => {}
        }
        if self.extend && self.base.is_none() {
            return bad("--extend continues the dance of --edit DANCE; give it".into());
        }
        if let (Some(_), Some(c)) = (&self.base, &self.continue_from) {
            return bad(format!(
                "--continue-from {} and --edit both give the dance's start; use one",
                c.label
            ));
        }
        if self.keyframes.is_empty() && (self.keyframe_joints.is_some() || self.keyframe_root) {
            return bad("--keyframe-joints and --keyframe-root apply to --keyframe POSE@T".into());
        }
        if let Some(p) = &self.path {
            p.parse(1, ANY_SONG_SECONDS)?;
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

    /// The part of `song` an edit dances, from `start` (to `end` where the edit does not fix
    /// its length): an edited dance's own length (to `end` when it is extended), a kept-joints
    /// motion's length when no `end` is given, else `start`-`end`.
    pub fn span(
        &self,
        song: &AnalysedSong,
        start: Option<f64>,
        end: Option<f64>,
    ) -> Result<Span, GenerateError> {
        match (self.base.as_ref(), self.kept_joints_frames()) {
            (Some(_), _) if self.extend => song.span(start, end),
            (Some(b), _) => song.span_of_frames(start, b.motion.frames()),
            (None, Some(n)) if end.is_none() => {
                let first = (start.unwrap_or(0.0) * f64::from(FPS)).round() as usize;
                song.span_of_frames(start, n.min(song.frames().saturating_sub(first)))
            }
            _ => song.span(start, end),
        }
    }

    /// What is known of the dance on `span` of a song of `song_seconds`, `None` for a plain
    /// generation.
    pub fn known(
        &self,
        span: &Span,
        song_seconds: f64,
    ) -> Result<Option<KnownParts>, GenerateError> {
        self.check()?;
        if self.is_empty() {
            return Ok(None);
        }
        self.check_one_dancer()?;
        let frames = span.end_frame - span.first_frame;
        let mut k = self.kept_frames(frames)?;
        self.keep_joints_into(&mut k)?;
        self.keyframes_into(&mut k, span, song_seconds)?;
        self.path_into(&mut k, span, song_seconds)?;
        Ok(Some(k))
    }

    /// The frames `--edit` or `--continue-from` keep whole (none without them).
    fn kept_frames(&self, frames: usize) -> Result<KnownParts, GenerateError> {
        if let Some(b) = &self.base
            && self.extend
        {
            return self.extended(b, frames);
        }
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
                    k.root_horizontal[f] = false;
                    k.root_height[f] = false;
                }
            }
            return Ok(k);
        }
        let empty = SmplMotion::new(
            FPS as f32,
            vec![0.0; frames * POSE_DIMS],
            vec![0.0; frames * 3],
        )
        .map_err(|e| GenerateError::Generation(e.to_string()))?;
        let mut k = KnownParts::none(empty);
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
            for f in 0..keep {
                let g = from + f;
                let trans = [0, 1, 2].map(|i| src.trans[g * 3 + i]);
                let pose = &src.poses[g * POSE_DIMS..(g + 1) * POSE_DIMS];
                k.set(f, ALL_JOINTS, [true, true], pose, trans);
            }
        }
        Ok(k)
    }

    /// `--extend`: the dance being edited kept whole as the first frames of `frames`, its
    /// `--regenerate` ranges made new, the rest new.
    fn extended(&self, b: &GivenMotion, frames: usize) -> Result<KnownParts, GenerateError> {
        let have = b.motion.frames();
        let more = frames as f64 / f64::from(FPS) - b.seconds();
        if more < MIN_RANGE_SECONDS {
            return Err(GenerateError::Invalid(format!(
                "--extend: the song from --start to --end gives {:.2} s, {:.2} s more than the \
                 dance ({}); give a later --end (at least {MIN_RANGE_SECONDS} s more)",
                frames as f64 / f64::from(FPS),
                more.max(0.0),
                b.label
            )));
        }
        let empty = SmplMotion::new(
            FPS as f32,
            vec![0.0; frames * POSE_DIMS],
            vec![0.0; frames * 3],
        )
        .map_err(|e| GenerateError::Generation(e.to_string()))?;
        let mut k = KnownParts::none(empty);
        let src = &b.motion;
        let made = |f: usize| {
            self.regenerate
                .iter()
                .any(|&[a, e]| (seconds_to_frame(a, have)..seconds_to_frame(e, have)).contains(&f))
        };
        for f in (0..have).filter(|&f| !made(f)) {
            let trans = [0, 1, 2].map(|i| src.trans[f * 3 + i]);
            let pose = &src.poses[f * POSE_DIMS..(f + 1) * POSE_DIMS];
            k.set(f, ALL_JOINTS, [true, true], pose, trans);
        }
        Ok(k)
    }

    /// `--keep-joints`: the joints (and with `lower` the root) of `--from` on every frame not
    /// kept whole.
    fn keep_joints_into(&self, k: &mut KnownParts) -> Result<(), GenerateError> {
        let Some(keep) = &self.keep_joints else {
            return Ok(());
        };
        let frames = k.frames();
        let src = &keep.from.motion;
        if src.frames() < frames {
            return Err(GenerateError::Invalid(format!(
                "--from {}: {:.2} s of motion for a dance of {:.2} s (give --end, or a longer \
                 motion)",
                keep.from.label,
                src.frames() as f64 / f64::from(FPS),
                frames as f64 / f64::from(FPS)
            )));
        }
        for f in 0..frames {
            if k.touched(f) {
                continue;
            }
            let trans = [0, 1, 2].map(|i| src.trans[f * 3 + i]);
            let pose = &src.poses[f * POSE_DIMS..(f + 1) * POSE_DIMS];
            k.set(f, keep.joints, [keep.root, keep.root], pose, trans);
        }
        Ok(())
    }

    /// `--keyframe`: on its frame, the named joints and every joint above them (what places
    /// them in the world, [`with_ancestors`]) take the pose's rotations; with both legs among
    /// them the root takes the pose's height (without the legs it keeps the dance's: the
    /// dance's legs would not reach the floor from another pelvis height), and with
    /// `--keyframe-root` its floor position.
    fn keyframes_into(
        &self,
        k: &mut KnownParts,
        span: &Span,
        song_seconds: f64,
    ) -> Result<(), GenerateError> {
        let joints = with_ancestors(self.keyframe_joints.as_ref().map_or(ALL_JOINTS, |j| j.1));
        let mut taken: Vec<(usize, &str)> = Vec::new();
        for key in &self.keyframes {
            let name = format!("--keyframe {}", key.spec);
            let f = song_frame(&name, key.t, span, song_seconds)?;
            if let Some((_, other)) = taken.iter().find(|(g, _)| *g == f) {
                return Err(GenerateError::Invalid(format!(
                    "{name} and --keyframe {other} fall on the same frame; give one pose per time"
                )));
            }
            taken.push((f, &key.spec));
            let height = joints & legs_mask() == legs_mask();
            let root_taken =
                (height && k.root_height[f]) || (self.keyframe_root && k.root_horizontal[f]);
            if k.joints[f] & joints != 0 || root_taken {
                return Err(GenerateError::Invalid(format!(
                    "{name}: at {:.2} s the dance is already given by {} (a keyframe goes \
                     where the dance is made new)",
                    key.t,
                    self.claimed_by(KEYFRAME)
                )));
            }
            k.set(
                f,
                joints,
                [self.keyframe_root, height],
                &key.pose,
                key.trans,
            );
        }
        Ok(())
    }

    /// `--path`: the root's floor position on every frame the path constrains.
    fn path_into(
        &self,
        k: &mut KnownParts,
        span: &Span,
        song_seconds: f64,
    ) -> Result<(), GenerateError> {
        let Some(file) = &self.path else {
            return Ok(());
        };
        let path = file.parse(1, song_seconds)?;
        let track = &path.sample(f64::from(FPS), span.end_frame)[0];
        let mut any = false;
        for (f, p) in track[span.first_frame..].iter().enumerate() {
            let Some([x, z]) = *p else { continue };
            if k.root_horizontal[f] {
                return Err(GenerateError::Invalid(format!(
                    "--path {}: at {:.2} s the root is already given by {}; a path goes where \
                     the dance is made new",
                    file.label,
                    (span.first_frame + f) as f64 / f64::from(FPS),
                    self.claimed_by(PATH)
                )));
            }
            k.set(f, 0, [true, false], &[], [x as f32, 0.0, z as f32]);
            any = true;
        }
        if !any {
            return Err(GenerateError::Invalid(format!(
                "--path {}: none of its positions falls in the danced part of the song \
                 ({:.2}-{:.2} s)",
                file.label, span.start_s, span.end_s
            )));
        }
        Ok(())
    }

    /// The operations other than `op` that give parts of the dance, for conflict messages.
    fn claimed_by(&self, op: &str) -> String {
        self.operations()
            .into_iter()
            .filter(|o| *o != op)
            .collect::<Vec<_>>()
            .join(" or ")
    }
}

/// The frame of the span at song time `t`, or an error naming `name` when `t` is outside the
/// song or the danced part of it.
fn song_frame(name: &str, t: f64, span: &Span, song_seconds: f64) -> Result<usize, GenerateError> {
    let g = (t * f64::from(FPS)).round();
    if !(t.is_finite() && t >= 0.0) || t > song_seconds + 0.5 / f64::from(FPS) {
        return Err(GenerateError::Invalid(format!(
            "{name}: {t} s is outside the song, which is {song_seconds:.2} s long"
        )));
    }
    let g = g as usize;
    if g < span.first_frame || g >= span.end_frame {
        return Err(GenerateError::Invalid(format!(
            "{name}: {t} s is outside the danced part of the song, {:.2}-{:.2} s (--start, \
             --end)",
            span.start_s, span.end_s
        )));
    }
    Ok(g - span.first_frame)
}

/// Frame index of `seconds` in a dance of `frames` frames.
fn seconds_to_frame(seconds: f64, frames: usize) -> usize {
    ((seconds * f64::from(FPS)).round().max(0.0) as usize).min(frames)
}

#[cfg(test)]
mod tests {
    use super::*;
    use dancegen_motion::repr::Edge151;

    fn given(frames: usize) -> GivenMotion {
        let poses = (0..frames * POSE_DIMS)
            .map(|i| (i % 7) as f32 * 0.01)
            .collect();
        let trans = (0..frames * 3).map(|i| i as f32 * 0.001).collect();
        GivenMotion::one(
            "base.npz".into(),
            SmplMotion::new(30.0, poses, trans).unwrap(),
        )
    }

    fn span(frames: usize) -> Span {
        Span {
            start_s: 0.0,
            end_s: frames as f64 / 30.0,
            first_frame: 0,
            end_frame: frames,
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
        let k = edit.known(&span(300), 100.0).unwrap().unwrap();
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
        let e = edit.known(&span(299), 100.0).unwrap_err().to_string();
        assert!(e.contains("300 frames") && e.contains("--start"), "{e}");
    }

    #[test]
    fn kept_joints_are_known_in_every_frame_and_need_a_long_enough_motion() {
        let (joints, root) = parse_joint_set("--keep-joints", "lower").unwrap();
        let edit = Edit {
            keep_joints: Some(KeepJoints {
                spec: "lower".into(),
                joints,
                root,
                from: given(100),
            }),
            ..Edit::default()
        };
        let k = edit.known(&span(90), 100.0).unwrap().unwrap();
        assert!((0..90).all(|f| k.joints[f] == joints && k.root_horizontal[f] && !k.kept(f)));
        let (_, mask) = k.edge151().unwrap();
        let knee = Edge151::ROT6D.start + 6 * 4;
        let wrist = Edge151::ROT6D.start + 6 * 20;
        assert!(mask[knee] == 1.0 && mask[wrist] == 0.0 && mask[Edge151::ROOT.start] == 1.0);
        let e = edit.known(&span(101), 100.0).unwrap_err().to_string();
        assert!(e.contains("--from base.npz"), "{e}");
    }

    #[test]
    fn a_continuation_keeps_the_last_second_of_the_motion_first() {
        let edit = Edit {
            continue_from: Some(given(100)),
            ..Edit::default()
        };
        let k = edit.known(&span(200), 100.0).unwrap().unwrap();
        assert!(k.kept(29) && !k.kept(30));
        let src = &edit.continue_from.as_ref().unwrap().motion;
        assert_eq!(k.motion.poses[..30 * 72], src.poses[70 * 72..]);
        assert_eq!(k.motion.trans[..90], src.trans[210..]);
        let e = edit.known(&span(30), 100.0).unwrap_err().to_string();
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

    fn keyframe(t: f64, x: f32) -> KeyframePose {
        KeyframePose {
            spec: format!("pose.npz@{t}"),
            t,
            pose: vec![0.3; POSE_DIMS],
            trans: [x, 0.9, -x],
        }
    }

    #[test]
    fn a_keyframe_places_its_joints_chains_and_root_height_on_its_frame() {
        let (wrist, _) = parse_joint_set("--keyframe-joints", "right_wrist").unwrap();
        let mut edit = Edit {
            keyframes: vec![keyframe(2.0, 1.5)],
            keyframe_joints: Some(("right_wrist".into(), wrist)),
            ..Edit::default()
        };
        let k = edit.known(&span(300), 100.0).unwrap().unwrap();
        assert_eq!(k.joints[60], with_ancestors(wrist));
        assert!(!k.root_height[60] && !k.root_horizontal[60]);
        assert!((0..300).filter(|&f| f != 60).all(|f| !k.touched(f)));
        edit.keyframe_root = true;
        let k = edit.known(&span(300), 100.0).unwrap().unwrap();
        assert!(k.root_horizontal[60] && !k.root_height[60]);
        assert_eq!(
            [k.motion.trans[60 * 3], k.motion.trans[60 * 3 + 2]],
            [1.5, -1.5]
        );
        edit.keyframe_joints = None;
        let k = edit.known(&span(300), 100.0).unwrap().unwrap();
        assert!(k.kept(60), "a whole pose with its root is the whole frame");
        assert_eq!(k.motion.trans[60 * 3..60 * 3 + 3], [1.5, 0.9, -1.5]);
        edit.keyframe_joints = Some(("right_wrist".into(), wrist));
        // Song time: with --start 5 the same keyframe is the dance's frame 60 - 150 < 0.
        let later = Span {
            start_s: 5.0,
            end_s: 10.0,
            first_frame: 150,
            end_frame: 300,
        };
        let e = edit.known(&later, 100.0).unwrap_err().to_string();
        assert!(
            e.contains("--keyframe pose.npz@2") && e.contains("danced part"),
            "{e}"
        );
    }

    #[test]
    fn keyframes_outside_the_song_on_one_frame_or_on_kept_frames_are_refused() {
        let outside = Edit {
            keyframes: vec![keyframe(120.0, 0.0)],
            ..Edit::default()
        };
        let e = outside.known(&span(300), 100.0).unwrap_err().to_string();
        assert!(e.contains("outside the song"), "{e}");
        let twice = Edit {
            keyframes: vec![keyframe(2.0, 0.0), keyframe(2.01, 0.0)],
            ..Edit::default()
        };
        let e = twice.known(&span(300), 100.0).unwrap_err().to_string();
        assert!(e.contains("same frame"), "{e}");
        let mut on_kept = regenerate(&[[2.0, 4.0]]);
        on_kept.keyframes = vec![keyframe(5.0, 0.0)];
        let e = on_kept.known(&span(300), 100.0).unwrap_err().to_string();
        assert!(e.contains("--edit/--regenerate"), "{e}");
        on_kept.keyframes = vec![keyframe(3.0, 0.0)];
        let k = on_kept.known(&span(300), 100.0).unwrap().unwrap();
        assert!(k.root_height[90] && !k.kept(90));
        let alone = Edit {
            keyframe_root: true,
            ..Edit::default()
        };
        assert!(
            alone
                .check()
                .unwrap_err()
                .to_string()
                .contains("--keyframe POSE@T")
        );
    }

    fn path(json: &str) -> Edit {
        Edit {
            path: Some(FormationFile {
                label: "path.json".into(),
                json: json.into(),
            }),
            ..Edit::default()
        }
    }

    #[test]
    fn a_path_gives_the_floor_position_where_it_constrains_and_nothing_else() {
        let p = path(
            r#"{"keyframes": [{"t": 1, "positions": [[0, 0]]}, {"t": 3, "positions": [[2, -1]]}]}"#,
        );
        let k = p.known(&span(300), 100.0).unwrap().unwrap();
        assert!(!k.root_horizontal[29] && k.root_horizontal[30] && k.root_horizontal[90]);
        assert!(!k.root_horizontal[91] && !k.root_height[60] && k.joints[60] == 0);
        assert_eq!(
            [k.motion.trans[90 * 3], k.motion.trans[90 * 3 + 2]],
            [2.0, -1.0]
        );
        let e = path(r#"{"keyframes": [{"t": 1, "positions": [[0, 0], [1, 0]]}]}"#)
            .check()
            .unwrap_err()
            .to_string();
        assert!(e.contains("path.json"), "{e}");
        let e = p
            .known(
                &Span {
                    start_s: 5.0,
                    end_s: 10.0,
                    first_frame: 150,
                    end_frame: 300,
                },
                100.0,
            )
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("--path path.json") && e.contains("none of its"),
            "{e}"
        );
        let (joints, root) = parse_joint_set("--keep-joints", "lower").unwrap();
        let mut with_lower = p.clone();
        with_lower.keep_joints = Some(KeepJoints {
            spec: "lower".into(),
            joints,
            root,
            from: given(300),
        });
        let e = with_lower.known(&span(300), 100.0).unwrap_err().to_string();
        assert!(e.contains("--path") && e.contains("--keep-joints"), "{e}");
    }

    #[test]
    fn kept_joints_fill_the_regenerated_range_of_an_edit() {
        let (arms, _) = parse_joint_set("--keep-joints", "arms").unwrap();
        let mut edit = regenerate(&[[2.0, 4.0]]);
        edit.keep_joints = Some(KeepJoints {
            spec: "arms".into(),
            joints: arms,
            root: false,
            from: given(300),
        });
        let k = edit.known(&span(300), 100.0).unwrap().unwrap();
        assert!(k.kept(59) && k.joints[60] == arms && !k.root_horizontal[60] && k.kept(120));
    }

    #[test]
    fn an_extended_dance_keeps_all_of_the_old_one_first_and_makes_the_rest() {
        let mut edit = Edit {
            base: Some(given(300)),
            extend: true,
            ..Edit::default()
        };
        assert_eq!(edit.operations(), vec![EXTEND]);
        let k = edit.known(&span(450), 100.0).unwrap().unwrap();
        assert!((0..300).all(|f| k.kept(f)) && (300..450).all(|f| !k.touched(f)));
        let base = &edit.base.as_ref().unwrap().motion;
        assert_eq!(k.motion.poses[..300 * 72], base.poses[..]);
        let e = edit.known(&span(310), 100.0).unwrap_err().to_string();
        assert!(e.contains("--extend") && e.contains("later --end"), "{e}");
        edit.regenerate = vec![[2.0, 4.0]];
        assert_eq!(edit.operations(), vec![REGENERATE, EXTEND]);
        let k = edit.known(&span(450), 100.0).unwrap().unwrap();
        assert!(k.kept(59) && !k.touched(60) && k.kept(120));
        let alone = Edit {
            extend: true,
            ..Edit::default()
        };
        assert!(
            alone
                .check()
                .unwrap_err()
                .to_string()
                .contains("--edit DANCE")
        );
    }
}
