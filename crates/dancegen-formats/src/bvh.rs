//! BVH (Biovision Hierarchy) reading and writing at the text/structure level.
//!
//! This module keeps Euler angles as plain numbers (degrees, in the channel order of the file);
//! forward kinematics and retargeting live elsewhere and interpret them with
//! [`Bvh::euler_order`] and [`Bvh::rotation_xyz`].
//!
//! # What is accepted
//!
//! - Exactly one `ROOT`. A second `ROOT` is an error ([`BvhErrorKind::MultipleRoots`]); files with
//!   several independent skeletons must be split first.
//! - Any number of channels per joint (0 to 6, no duplicates), in any order, including position
//!   channels on non-root joints. Channel names are matched case-insensitively.
//! - `End Site` blocks (at most one per joint), stored as [`BvhJoint::end_site`]; they are not
//!   joints and have no channels.
//! - LF or CRLF line endings, tabs or spaces, numbers in any form Rust's `f64` parser accepts
//!   (including scientific notation). `NaN` and infinities are rejected.
//! - A joint name is the rest of its `ROOT`/`JOINT` line (so names may contain spaces); a `{` at
//!   the end of that line is accepted.
//! - `Frames: 0` is a valid rest-pose file: reading returns `frames == 0` and empty `data`.
//!   `Frame Time` must be finite and positive, except that `0` is allowed when there are no frames.
//! - One frame per line; blank lines in the motion section are ignored. Fewer frame lines than
//!   `Frames:` is [`BvhErrorKind::Truncated`], more is [`BvhErrorKind::TooManyFrames`].
//!
//! Parsing never panics and does not recurse, whatever the input.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// One BVH channel.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Channel {
    Xposition,
    Yposition,
    Zposition,
    Xrotation,
    Yrotation,
    Zrotation,
}

impl Channel {
    /// The name as written in BVH files.
    pub fn name(self) -> &'static str {
        match self {
            Channel::Xposition => "Xposition",
            Channel::Yposition => "Yposition",
            Channel::Zposition => "Zposition",
            Channel::Xrotation => "Xrotation",
            Channel::Yrotation => "Yrotation",
            Channel::Zrotation => "Zrotation",
        }
    }

    /// Parses a channel name, case-insensitively.
    pub fn from_name(s: &str) -> Option<Channel> {
        const ALL: [Channel; 6] = [
            Channel::Xposition,
            Channel::Yposition,
            Channel::Zposition,
            Channel::Xrotation,
            Channel::Yrotation,
            Channel::Zrotation,
        ];
        ALL.into_iter().find(|c| c.name().eq_ignore_ascii_case(s))
    }

    pub fn is_position(self) -> bool {
        matches!(
            self,
            Channel::Xposition | Channel::Yposition | Channel::Zposition
        )
    }

    pub fn is_rotation(self) -> bool {
        !self.is_position()
    }

    /// The axis: 0 for X, 1 for Y, 2 for Z.
    pub fn axis(self) -> usize {
        match self {
            Channel::Xposition | Channel::Xrotation => 0,
            Channel::Yposition | Channel::Yrotation => 1,
            Channel::Zposition | Channel::Zrotation => 2,
        }
    }
}

/// One joint of the hierarchy. End sites are not joints; they are stored on their parent.
#[derive(Debug, Clone, PartialEq)]
pub struct BvhJoint {
    pub name: String,
    /// Index of the parent in [`Bvh::joints`]; `None` for the root. Always smaller than the
    /// joint's own index (joints are stored in depth-first file order).
    pub parent: Option<usize>,
    pub offset: [f64; 3],
    /// Channels in file order.
    pub channels: Vec<Channel>,
    /// Offset of the `End Site` child, if any.
    pub end_site: Option<[f64; 3]>,
}

/// A BVH file: hierarchy plus motion.
#[derive(Debug, Clone, PartialEq)]
pub struct Bvh {
    /// Joints in depth-first file order; `joints[0]` is the root.
    pub joints: Vec<BvhJoint>,
    /// Seconds per frame, as written in the file.
    pub frame_time: f64,
    pub frames: usize,
    /// `frames × num_channels()` values, row-major, channels in file order. Angles in degrees.
    pub data: Vec<f64>,
}

/// Options for reading.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BvhReadOptions {
    /// Multiplies offsets, end-site offsets and position channels. Must be finite.
    pub scale: f64,
    /// Seconds per frame to use instead of the header's `Frame Time`, for files whose header
    /// is wrong (the CMU salsa conversions say 120 fps for a 60 fps capture). With it, the
    /// header's value is not checked and the `Frame Time:` line may be missing. Must be finite
    /// and positive.
    pub frame_time: Option<f64>,
}

impl Default for BvhReadOptions {
    fn default() -> Self {
        BvhReadOptions {
            scale: 1.0,
            frame_time: None,
        }
    }
}

/// Options for writing.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BvhWriteOptions {
    /// Decimal places for offsets and channel values; `None` writes the shortest representation
    /// that parses back to the identical `f64`. The frame time is always written losslessly.
    pub precision: Option<usize>,
}

impl Default for BvhWriteOptions {
    fn default() -> Self {
        BvhWriteOptions { precision: Some(6) }
    }
}

/// What went wrong. Line numbers are 1-based.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BvhErrorKind {
    #[error("cannot read: {0}")]
    Io(String),
    #[error("line {line}: not valid UTF-8")]
    NonUtf8 { line: usize },
    #[error("line {line}: expected {expected}, found {found:?}")]
    Unexpected {
        line: usize,
        expected: &'static str,
        found: String,
    },
    #[error("line {line}: unexpected end of file, expected {expected}")]
    UnexpectedEof { line: usize, expected: &'static str },
    #[error("line {line}: unknown channel {name:?}")]
    UnknownChannel { line: usize, name: String },
    #[error("line {line}: channel {name} listed twice")]
    DuplicateChannel { line: usize, name: &'static str },
    #[error("line {line}: invalid channel count {found:?} (expected 0 to 6)")]
    BadChannelCount { line: usize, found: String },
    #[error("line {line}: invalid number {token:?}")]
    BadNumber { line: usize, token: String },
    #[error("line {line}: non-finite value {token:?}")]
    NonFinite { line: usize, token: String },
    #[error("line {line}: a second ROOT (only one skeleton per file is supported)")]
    MultipleRoots { line: usize },
    #[error("no ROOT joint in HIERARCHY")]
    NoRoot,
    #[error("line {line}: unbalanced braces: {detail}")]
    UnbalancedBraces { line: usize, detail: &'static str },
    #[error("line {line}: {what} has no OFFSET")]
    MissingOffset { line: usize, what: String },
    #[error("line {line}: {what} has two OFFSET lines")]
    DuplicateOffset { line: usize, what: String },
    #[error("line {line}: joint has two End Site blocks")]
    DuplicateEndSite { line: usize },
    #[error("missing MOTION section")]
    MissingMotion,
    #[error("line {line}: invalid frame time {value} (must be finite and positive)")]
    BadFrameTime { line: usize, value: f64 },
    #[error("line {line}: no `Frame Time:` line after the frame count")]
    MissingFrameTime { line: usize },
    #[error("line {line}: expected {expected} values, found {found}")]
    WrongValueCount {
        line: usize,
        expected: usize,
        found: usize,
    },
    #[error("line {line}: truncated: Frames: {expected} but only {found} frame lines")]
    Truncated {
        line: usize,
        expected: usize,
        found: usize,
    },
    #[error("line {line}: more frame lines than Frames: {expected}")]
    TooManyFrames { line: usize, expected: usize },
    #[error("{0}")]
    Invalid(String),
}

/// A BVH error: the kind, and the file it concerns when known.
#[derive(Debug, Clone, PartialEq)]
pub struct BvhError {
    pub path: Option<PathBuf>,
    pub kind: BvhErrorKind,
}

impl std::fmt::Display for BvhError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match &self.path {
            Some(p) => write!(f, "{}: {}", p.display(), self.kind),
            None => write!(f, "{}", self.kind),
        }
    }
}

impl std::error::Error for BvhError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        Some(&self.kind)
    }
}

impl From<BvhErrorKind> for BvhError {
    fn from(kind: BvhErrorKind) -> Self {
        BvhError { path: None, kind }
    }
}

impl BvhError {
    fn with_path(mut self, path: &Path) -> Self {
        self.path = Some(path.to_path_buf());
        self
    }
}

/// Shortens a token for an error message (input may be adversarially long).
fn clip(s: &str) -> String {
    const MAX: usize = 40;
    if s.len() <= MAX {
        return s.to_string();
    }
    let mut end = MAX;
    while !s.is_char_boundary(end) {
        end -= 1;
    }
    format!("{}…", &s[..end])
}

#[derive(Clone)]
struct Lexer<'a> {
    lines: std::str::Lines<'a>,
    line_no: usize,
    toks: std::str::SplitAsciiWhitespace<'a>,
}

impl<'a> Lexer<'a> {
    fn new(text: &'a str) -> Self {
        Lexer {
            lines: text.lines(),
            line_no: 0,
            toks: "".split_ascii_whitespace(),
        }
    }

    fn next_token(&mut self) -> Option<(usize, &'a str)> {
        loop {
            if let Some(t) = self.toks.next() {
                return Some((self.line_no, t));
            }
            let l = self.lines.next()?;
            self.line_no += 1;
            self.toks = l.split_ascii_whitespace();
        }
    }

    /// Remaining tokens on the current line.
    fn rest_of_line(&mut self) -> Vec<&'a str> {
        self.toks.by_ref().collect()
    }

    fn expect_token(&mut self, expected: &'static str) -> Result<(usize, &'a str), BvhErrorKind> {
        self.next_token().ok_or(BvhErrorKind::UnexpectedEof {
            line: self.line_no,
            expected,
        })
    }

    fn expect_keyword(&mut self, kw: &'static str) -> Result<usize, BvhErrorKind> {
        let (line, t) = self.expect_token(kw)?;
        if t.eq_ignore_ascii_case(kw) {
            Ok(line)
        } else {
            Err(BvhErrorKind::Unexpected {
                line,
                expected: kw,
                found: clip(t),
            })
        }
    }

    /// `Frames:` or `Frames :` (the label without its colon is `label`).
    fn expect_label(
        &mut self,
        label: &'static str,
        expected: &'static str,
    ) -> Result<(), BvhErrorKind> {
        let (line, t) = self.expect_token(expected)?;
        let lower = t.to_ascii_lowercase();
        if lower == format!("{}:", label.to_ascii_lowercase()) {
            return Ok(());
        }
        if lower == label.to_ascii_lowercase() {
            let (line, t) = self.expect_token(expected)?;
            if t == ":" {
                return Ok(());
            }
            return Err(BvhErrorKind::Unexpected {
                line,
                expected,
                found: clip(t),
            });
        }
        Err(BvhErrorKind::Unexpected {
            line,
            expected,
            found: clip(t),
        })
    }

    fn expect_number(&mut self, expected: &'static str) -> Result<(usize, f64), BvhErrorKind> {
        let (line, t) = self.expect_token(expected)?;
        Ok((line, parse_f64(line, t)?))
    }
}

/// `Frame Time: <seconds>` up to the end of its line: `(line, value)`, the value unchecked.
fn read_frame_time(lx: &mut Lexer<'_>) -> Result<(usize, f64), BvhErrorKind> {
    let (l2, t2) = lx.expect_token("Frame Time:")?;
    if !t2.eq_ignore_ascii_case("Frame") {
        return Err(BvhErrorKind::Unexpected {
            line: l2,
            expected: "Frame Time:",
            found: clip(t2),
        });
    }
    lx.expect_label("Time", "Frame Time:")?;
    let (tline, frame_time) = lx.expect_number("frame time")?;
    if let Some(extra) = lx.rest_of_line().first() {
        return Err(BvhErrorKind::Unexpected {
            line: tline,
            expected: "end of line after Frame Time",
            found: clip(extra),
        });
    }
    Ok((tline, frame_time))
}

fn parse_f64(line: usize, t: &str) -> Result<f64, BvhErrorKind> {
    match t.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(_) => Err(BvhErrorKind::NonFinite {
            line,
            token: clip(t),
        }),
        Err(_) => Err(BvhErrorKind::BadNumber {
            line,
            token: clip(t),
        }),
    }
}

enum Open {
    Joint(usize),
    EndSite(usize),
}

/// Parses the text of a BVH file.
pub fn parse_bvh(text: &str, opts: &BvhReadOptions) -> Result<Bvh, BvhError> {
    parse_inner(text, opts).map_err(BvhError::from)
}

/// Parses the bytes of a BVH file; non-UTF-8 input is an error with its line number.
pub fn parse_bvh_bytes(bytes: &[u8], opts: &BvhReadOptions) -> Result<Bvh, BvhError> {
    match std::str::from_utf8(bytes) {
        Ok(text) => parse_bvh(text, opts),
        Err(e) => {
            let good = bytes.get(..e.valid_up_to()).unwrap_or_default();
            let line = good.iter().filter(|&&b| b == b'\n').count() + 1;
            Err(BvhErrorKind::NonUtf8 { line }.into())
        }
    }
}

/// Reads a BVH file; errors carry the path.
pub fn read_bvh(path: impl AsRef<Path>, opts: &BvhReadOptions) -> Result<Bvh, BvhError> {
    let path = path.as_ref();
    let bytes = std::fs::read(path)
        .map_err(|e| BvhError::from(BvhErrorKind::Io(e.to_string())).with_path(path))?;
    parse_bvh_bytes(&bytes, opts).map_err(|e| e.with_path(path))
}

fn parse_inner(text: &str, opts: &BvhReadOptions) -> Result<Bvh, BvhErrorKind> {
    let scale = opts.scale;
    if !scale.is_finite() {
        return Err(BvhErrorKind::Invalid(format!(
            "scale must be finite, got {scale}"
        )));
    }
    if let Some(ft) = opts.frame_time
        && !(ft.is_finite() && ft > 0.0)
    {
        return Err(BvhErrorKind::Invalid(format!(
            "the given frame time must be finite and positive, got {ft}"
        )));
    }
    let mut lx = Lexer::new(text.strip_prefix('\u{feff}').unwrap_or(text));
    lx.expect_keyword("HIERARCHY")?;

    let mut joints: Vec<BvhJoint> = Vec::new();
    // Line of each joint's header and whether it has an OFFSET yet.
    let mut joint_line: Vec<usize> = Vec::new();
    let mut has_offset: Vec<bool> = Vec::new();
    let mut stack: Vec<Open> = Vec::new();
    let mut end_has_offset = false;
    let mut end_line = 0usize;

    loop {
        let Some((line, tok)) = lx.next_token() else {
            return Err(if joints.is_empty() {
                BvhErrorKind::NoRoot
            } else if !stack.is_empty() {
                BvhErrorKind::UnbalancedBraces {
                    line: lx.line_no,
                    detail: "end of file before the closing '}'",
                }
            } else {
                BvhErrorKind::MissingMotion
            });
        };
        let kw = tok.to_ascii_uppercase();
        match stack.last() {
            None => match kw.as_str() {
                "ROOT" => {
                    if !joints.is_empty() {
                        return Err(BvhErrorKind::MultipleRoots { line });
                    }
                    let idx = open_joint(&mut lx, line, None, &mut joints)?;
                    joint_line.push(line);
                    has_offset.push(false);
                    stack.push(Open::Joint(idx));
                }
                "MOTION" => {
                    if joints.is_empty() {
                        return Err(BvhErrorKind::NoRoot);
                    }
                    break;
                }
                "}" => {
                    return Err(BvhErrorKind::UnbalancedBraces {
                        line,
                        detail: "'}' without an open block",
                    });
                }
                _ => {
                    return Err(BvhErrorKind::Unexpected {
                        line,
                        expected: if joints.is_empty() { "ROOT" } else { "MOTION" },
                        found: clip(tok),
                    });
                }
            },
            Some(&Open::Joint(j)) => match kw.as_str() {
                "OFFSET" => {
                    let o = read_offset(&mut lx, scale)?;
                    let (Some(joint), Some(seen)) = (joints.get_mut(j), has_offset.get_mut(j))
                    else {
                        return Err(BvhErrorKind::Invalid("internal joint index".into()));
                    };
                    if *seen {
                        return Err(BvhErrorKind::DuplicateOffset {
                            line,
                            what: format!("joint {:?}", joint.name),
                        });
                    }
                    *seen = true;
                    joint.offset = o;
                }
                "CHANNELS" => {
                    let chans = read_channels(&mut lx)?;
                    if let Some(joint) = joints.get_mut(j) {
                        if !joint.channels.is_empty() {
                            return Err(BvhErrorKind::Unexpected {
                                line,
                                expected: "a single CHANNELS line per joint",
                                found: "CHANNELS".into(),
                            });
                        }
                        joint.channels = chans;
                    }
                }
                "JOINT" => {
                    let idx = open_joint(&mut lx, line, Some(j), &mut joints)?;
                    joint_line.push(line);
                    has_offset.push(false);
                    stack.push(Open::Joint(idx));
                }
                "END" => {
                    let (l2, t2) = lx.expect_token("Site")?;
                    if !t2.eq_ignore_ascii_case("Site") {
                        return Err(BvhErrorKind::Unexpected {
                            line: l2,
                            expected: "Site",
                            found: clip(t2),
                        });
                    }
                    if joints.get(j).is_some_and(|jt| jt.end_site.is_some()) {
                        return Err(BvhErrorKind::DuplicateEndSite { line });
                    }
                    lx.expect_keyword("{")?;
                    end_has_offset = false;
                    end_line = line;
                    stack.push(Open::EndSite(j));
                }
                "}" => {
                    if !has_offset.get(j).copied().unwrap_or(false) {
                        let name = joints.get(j).map(|jt| jt.name.clone()).unwrap_or_default();
                        return Err(BvhErrorKind::MissingOffset {
                            line: joint_line.get(j).copied().unwrap_or(line),
                            what: format!("joint {name:?}"),
                        });
                    }
                    stack.pop();
                }
                "MOTION" => {
                    return Err(BvhErrorKind::UnbalancedBraces {
                        line,
                        detail: "MOTION before the hierarchy's closing '}'",
                    });
                }
                _ => {
                    return Err(BvhErrorKind::Unexpected {
                        line,
                        expected: "OFFSET, CHANNELS, JOINT, End Site or '}'",
                        found: clip(tok),
                    });
                }
            },
            Some(&Open::EndSite(j)) => match kw.as_str() {
                "OFFSET" => {
                    if end_has_offset {
                        return Err(BvhErrorKind::DuplicateOffset {
                            line,
                            what: "End Site".into(),
                        });
                    }
                    let o = read_offset(&mut lx, scale)?;
                    end_has_offset = true;
                    if let Some(joint) = joints.get_mut(j) {
                        joint.end_site = Some(o);
                    }
                }
                "}" => {
                    if !end_has_offset {
                        return Err(BvhErrorKind::MissingOffset {
                            line: end_line,
                            what: "End Site".into(),
                        });
                    }
                    stack.pop();
                }
                "MOTION" => {
                    return Err(BvhErrorKind::UnbalancedBraces {
                        line,
                        detail: "MOTION before the End Site's closing '}'",
                    });
                }
                _ => {
                    return Err(BvhErrorKind::Unexpected {
                        line,
                        expected: "OFFSET or '}' in End Site",
                        found: clip(tok),
                    });
                }
            },
        }
    }

    // MOTION section.
    lx.expect_label("Frames", "Frames:")?;
    let (fline, ftok) = lx.expect_token("frame count")?;
    let frames: usize = ftok.parse().map_err(|_| BvhErrorKind::BadNumber {
        line: fline,
        token: clip(ftok),
    })?;
    // The `Frame Time:` line; a file without one has its first motion value next.
    let next = lx.clone().next_token();
    let header_time = match next {
        Some((line, t)) if !t.eq_ignore_ascii_case("Frame") && t.parse::<f64>().is_ok() => {
            if opts.frame_time.is_none() && frames > 0 {
                return Err(BvhErrorKind::MissingFrameTime { line });
            }
            None
        }
        _ => Some(read_frame_time(&mut lx)?),
    };
    let frame_time = match (opts.frame_time, header_time) {
        (Some(given), _) => given,
        (None, Some((line, value))) => {
            if !(value > 0.0 || (frames == 0 && value == 0.0)) {
                return Err(BvhErrorKind::BadFrameTime { line, value });
            }
            value
        }
        (None, None) => 0.0,
    };

    let nch: usize = joints.iter().map(|j| j.channels.len()).sum();
    let pos_mask: Vec<bool> = joints
        .iter()
        .flat_map(|j| j.channels.iter().map(|c| c.is_position()))
        .collect();
    let mut data: Vec<f64> = Vec::new();
    if let Some(total) = frames.checked_mul(nch) {
        // Every value needs at least two bytes of text; don't trust a huge `Frames:`.
        if total.saturating_mul(2) <= text.len() {
            data.reserve_exact(total);
        }
    }
    let mut read = 0usize;
    for l in lx.lines.by_ref() {
        lx.line_no += 1;
        let line = lx.line_no;
        let mut toks = l.split_ascii_whitespace().peekable();
        if toks.peek().is_none() {
            continue;
        }
        if read == frames {
            return Err(BvhErrorKind::TooManyFrames {
                line,
                expected: frames,
            });
        }
        let mut n = 0usize;
        for t in toks {
            if n < nch {
                let mut v = parse_f64(line, t)?;
                if scale != 1.0 && pos_mask.get(n).copied().unwrap_or(false) {
                    v *= scale;
                }
                data.push(v);
            }
            n += 1;
        }
        if n != nch {
            return Err(BvhErrorKind::WrongValueCount {
                line,
                expected: nch,
                found: n,
            });
        }
        read += 1;
    }
    if read < frames {
        return Err(BvhErrorKind::Truncated {
            line: lx.line_no,
            expected: frames,
            found: read,
        });
    }
    Ok(Bvh {
        joints,
        frame_time,
        frames,
        data,
    })
}

fn open_joint(
    lx: &mut Lexer<'_>,
    line: usize,
    parent: Option<usize>,
    joints: &mut Vec<BvhJoint>,
) -> Result<usize, BvhErrorKind> {
    let mut rest = lx.rest_of_line();
    let brace_on_line = rest.last() == Some(&"{");
    if brace_on_line {
        rest.pop();
    }
    if rest.is_empty() {
        return Err(BvhErrorKind::Unexpected {
            line,
            expected: "joint name",
            found: String::new(),
        });
    }
    if let Some(t) = rest.iter().find(|t| t.contains(['{', '}'])) {
        return Err(BvhErrorKind::Unexpected {
            line,
            expected: "joint name without braces",
            found: clip(t),
        });
    }
    // Tokens are split on ASCII whitespace only; trim the Unicode whitespace (vertical tab,
    // NBSP, ...) that can remain at the ends so every accepted name also writes back (found by
    // the fuzz target, tests/fuzz_regressions.rs).
    let name = rest.join(" ").trim().to_string();
    if name.is_empty() {
        return Err(BvhErrorKind::Unexpected {
            line,
            expected: "joint name",
            found: String::new(),
        });
    }
    if !brace_on_line {
        lx.expect_keyword("{")?;
    }
    joints.push(BvhJoint {
        name,
        parent,
        offset: [0.0; 3],
        channels: Vec::new(),
        end_site: None,
    });
    Ok(joints.len() - 1)
}

fn read_offset(lx: &mut Lexer<'_>, scale: f64) -> Result<[f64; 3], BvhErrorKind> {
    let mut o = [0.0; 3];
    for v in &mut o {
        *v = lx.expect_number("OFFSET value")?.1 * scale;
    }
    Ok(o)
}

fn read_channels(lx: &mut Lexer<'_>) -> Result<Vec<Channel>, BvhErrorKind> {
    let (line, t) = lx.expect_token("channel count")?;
    let n: usize = match t.parse() {
        Ok(n) if n <= 6 => n,
        _ => {
            return Err(BvhErrorKind::BadChannelCount {
                line,
                found: clip(t),
            });
        }
    };
    let mut chans = Vec::with_capacity(n);
    for _ in 0..n {
        let (line, t) = lx.expect_token("channel name")?;
        let c = Channel::from_name(t).ok_or_else(|| BvhErrorKind::UnknownChannel {
            line,
            name: clip(t),
        })?;
        if chans.contains(&c) {
            return Err(BvhErrorKind::DuplicateChannel {
                line,
                name: c.name(),
            });
        }
        chans.push(c);
    }
    Ok(chans)
}

impl Bvh {
    /// Total number of channels per frame.
    pub fn num_channels(&self) -> usize {
        self.joints.iter().map(|j| j.channels.len()).sum()
    }

    /// Frames per second, `1 / frame_time` (0 if the frame time is 0).
    pub fn fps(&self) -> f64 {
        if self.frame_time > 0.0 {
            1.0 / self.frame_time
        } else {
            0.0
        }
    }

    /// [`Self::fps`] rounded to the nearest integer when within 0.1% of it (BVH writers round
    /// the frame time, e.g. `0.008333` for 120 fps), otherwise the exact value.
    pub fn nominal_fps(&self) -> f64 {
        let fps = self.fps();
        let r = fps.round();
        if r > 0.0 && ((fps - r) / r).abs() < 1e-3 {
            r
        } else {
            fps
        }
    }

    /// Index of the joint with this name.
    pub fn joint_index(&self, name: &str) -> Option<usize> {
        self.joints.iter().position(|j| j.name == name)
    }

    /// Indices of the direct children of `joint`.
    pub fn children(&self, joint: usize) -> Vec<usize> {
        (0..self.joints.len())
            .filter(|&i| self.joints.get(i).and_then(|j| j.parent) == Some(joint))
            .collect()
    }

    /// Index of the first channel of `joint` within a frame row; `None` if out of range.
    pub fn channel_offset(&self, joint: usize) -> Option<usize> {
        if joint >= self.joints.len() {
            return None;
        }
        Some(
            self.joints
                .iter()
                .take(joint)
                .map(|j| j.channels.len())
                .sum(),
        )
    }

    /// The rotation channel order of `joint` as axis letters in file order, e.g. `"ZXY"` for
    /// `Zrotation Xrotation Yrotation`; empty if the joint has no rotation channels, `None` if
    /// the joint is out of range. In BVH the rotation is `R = R_first · R_second · R_third`
    /// applied to column vectors (intrinsic rotations in this order).
    pub fn euler_order(&self, joint: usize) -> Option<String> {
        let j = self.joints.get(joint)?;
        Some(
            j.channels
                .iter()
                .filter(|c| c.is_rotation())
                .map(|c| ['X', 'Y', 'Z'][c.axis()])
                .collect(),
        )
    }

    /// The row of channel values of frame `frame`.
    pub fn frame(&self, frame: usize) -> Option<&[f64]> {
        let n = self.num_channels();
        let start = frame.checked_mul(n)?;
        self.data.get(start..start.checked_add(n)?)
    }

    /// Value of one channel of `joint` in `frame`; `None` if out of range or absent.
    pub fn channel_value(&self, joint: usize, frame: usize, channel: Channel) -> Option<f64> {
        let j = self.joints.get(joint)?;
        let k = j.channels.iter().position(|&c| c == channel)?;
        let row = self.frame(frame)?;
        row.get(self.channel_offset(joint)? + k).copied()
    }

    fn axes(&self, joint: usize, frame: usize, want_pos: bool) -> Option<[f64; 3]> {
        let j = self.joints.get(joint)?;
        let row = self.frame(frame)?;
        let start = self.channel_offset(joint)?;
        let mut out = [0.0; 3];
        let mut any = false;
        for (k, c) in j.channels.iter().enumerate() {
            if c.is_position() == want_pos {
                *out.get_mut(c.axis())? = *row.get(start + k)?;
                any = true;
            }
        }
        any.then_some(out)
    }

    /// Position channels of `joint` in `frame` as `[x, y, z]` (missing axes are 0); `None` if
    /// the joint has no position channels or the indices are out of range.
    pub fn position(&self, joint: usize, frame: usize) -> Option<[f64; 3]> {
        self.axes(joint, frame, true)
    }

    /// Rotation angles (degrees) of `joint` in `frame`, indexed by axis: `[about X, about Y,
    /// about Z]` (missing axes are 0). Combine with [`Self::euler_order`] for the order.
    /// `None` if the joint has no rotation channels or the indices are out of range.
    pub fn rotation_xyz(&self, joint: usize, frame: usize) -> Option<[f64; 3]> {
        self.axes(joint, frame, false)
    }

    /// Checks the invariants the writer relies on: one root at index 0, parents before
    /// children in depth-first order, `data.len() == frames × num_channels()`, finite values,
    /// no duplicate channels, names without line breaks or braces.
    pub fn validate(&self) -> Result<(), BvhError> {
        let bad = |s: String| Err(BvhError::from(BvhErrorKind::Invalid(s)));
        if self.joints.is_empty() {
            return bad("no joints".into());
        }
        // `chain` is the ancestor chain of the previous joint (depth-first order check).
        let mut chain: Vec<usize> = Vec::new();
        for (i, j) in self.joints.iter().enumerate() {
            match (i, j.parent) {
                (0, None) => {}
                (0, Some(_)) => return bad("joint 0 must be the root".into()),
                (_, None) => return bad(format!("joint {i} is a second root")),
                (_, Some(p)) => {
                    while chain.last().is_some_and(|&c| c != p) {
                        chain.pop();
                    }
                    if chain.is_empty() {
                        return bad(format!(
                            "joint {i} ({:?}): parent {p} is not an ancestor of the previous \
                             joint (joints must be in depth-first order)",
                            j.name
                        ));
                    }
                }
            }
            chain.push(i);
            let name_ok = !j.name.trim().is_empty()
                && !j.name.contains(['\n', '\r', '{', '}'])
                && j.name.trim() == j.name;
            if !name_ok {
                return bad(format!("joint {i}: invalid name {:?}", j.name));
            }
            for (k, c) in j.channels.iter().enumerate() {
                if j.channels.get(..k).is_some_and(|s| s.contains(c)) {
                    return bad(format!("joint {i}: duplicate channel {}", c.name()));
                }
            }
            let finite = j.offset.iter().all(|v| v.is_finite())
                && j.end_site.is_none_or(|e| e.iter().all(|v| v.is_finite()));
            if !finite {
                return bad(format!("joint {i}: non-finite offset"));
            }
        }
        let n = self.num_channels();
        if self.frames.checked_mul(n) != Some(self.data.len()) {
            return bad(format!(
                "data has {} values, expected {} frames × {n} channels",
                self.data.len(),
                self.frames
            ));
        }
        if let Some(i) = self.data.iter().position(|v| !v.is_finite()) {
            return bad(format!("non-finite value at data index {i}"));
        }
        if !(self.frame_time > 0.0 || (self.frames == 0 && self.frame_time == 0.0)) {
            return bad(format!("invalid frame time {}", self.frame_time));
        }
        Ok(())
    }
}

fn push_num(out: &mut String, v: f64, precision: Option<usize>) {
    // Writing to a String cannot fail.
    let _ = match precision {
        Some(p) => write!(out, "{v:.p$}"),
        None => write!(out, "{v:?}"),
    };
}

/// Writes a BVH file as text (tab-indented, LF line endings), in the layout Blender and other
/// importers expect. Fails if [`Bvh::validate`] does.
pub fn write_bvh(bvh: &Bvh, opts: &BvhWriteOptions) -> Result<String, BvhError> {
    bvh.validate()?;
    let p = opts.precision;
    let mut out = String::with_capacity(
        256 + bvh.joints.len() * 160 + bvh.data.len() * (p.unwrap_or(12) + 6),
    );
    out.push_str("HIERARCHY\n");
    let indent = |out: &mut String, d: usize| {
        for _ in 0..d {
            out.push('\t');
        }
    };
    let mut depth_of: Vec<usize> = Vec::with_capacity(bvh.joints.len());
    // Open joints, innermost last: (joint index, depth).
    let mut open: Vec<(usize, usize)> = Vec::new();
    let close = |out: &mut String, open: &mut Vec<(usize, usize)>, keep_parent: Option<usize>| {
        while let Some(&(j, d)) = open.last() {
            if Some(j) == keep_parent {
                break;
            }
            if let Some(e) = bvh.joints.get(j).and_then(|jt| jt.end_site) {
                indent(out, d + 1);
                out.push_str("End Site\n");
                indent(out, d + 1);
                out.push_str("{\n");
                indent(out, d + 2);
                out.push_str("OFFSET");
                for v in e {
                    out.push(' ');
                    push_num(out, v, p);
                }
                out.push('\n');
                indent(out, d + 1);
                out.push_str("}\n");
            }
            indent(out, d);
            out.push_str("}\n");
            open.pop();
        }
    };
    for (i, j) in bvh.joints.iter().enumerate() {
        close(&mut out, &mut open, j.parent);
        let d = j
            .parent
            .and_then(|pi| depth_of.get(pi))
            .map_or(0, |d| d + 1);
        depth_of.push(d);
        indent(&mut out, d);
        out.push_str(if i == 0 { "ROOT " } else { "JOINT " });
        out.push_str(&j.name);
        out.push('\n');
        indent(&mut out, d);
        out.push_str("{\n");
        indent(&mut out, d + 1);
        out.push_str("OFFSET");
        for v in j.offset {
            out.push(' ');
            push_num(&mut out, v, p);
        }
        out.push('\n');
        indent(&mut out, d + 1);
        let _ = write!(out, "CHANNELS {}", j.channels.len());
        for c in &j.channels {
            out.push(' ');
            out.push_str(c.name());
        }
        out.push('\n');
        open.push((i, d));
    }
    close(&mut out, &mut open, None);
    let _ = write!(
        out,
        "MOTION\nFrames: {}\nFrame Time: {:?}\n",
        bvh.frames, bvh.frame_time
    );
    let n = bvh.num_channels();
    if n > 0 {
        for row in bvh.data.chunks_exact(n) {
            for (k, &v) in row.iter().enumerate() {
                if k > 0 {
                    out.push(' ');
                }
                push_num(&mut out, v, p);
            }
            out.push('\n');
        }
    }
    Ok(out)
}

/// Writes a BVH file atomically (see [`dancegen_io::write_atomic`]).
pub fn write_bvh_file(
    path: impl AsRef<Path>,
    bvh: &Bvh,
    opts: &BvhWriteOptions,
) -> Result<(), BvhError> {
    let path = path.as_ref();
    let text = write_bvh(bvh, opts).map_err(|e| e.with_path(path))?;
    dancegen_io::write_atomic(path, |w| w.write_all(text.as_bytes()))
        .map_err(|e| BvhError::from(BvhErrorKind::Io(e.reason)).with_path(path))
}
