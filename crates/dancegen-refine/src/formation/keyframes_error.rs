//! The errors of a FORMATION.json file ([`super::keyframes`]).
//!
//! Every message starts with the file and names the JSON field it is about
//! (`keyframes[2].positions[1]`), the path the user edits, then says what is wrong.

use super::MIN_SEPARATION_M;

/// A FORMATION.json problem, with the file it is in.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{file}: {problem}")]
pub struct FormationError {
    /// The label the caller gave the file (its path, usually).
    pub file: String,
    /// What is wrong, and where in the file.
    pub problem: FormationProblem,
}

/// What is wrong with a formation; `field` is the JSON path, e.g. `keyframes[2].positions[1]`.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FormationProblem {
    #[error("cannot read: {0}")]
    Read(String),
    #[error("not valid JSON: {0}")]
    Json(String),
    #[error("{field}: expected {expected}, found {found}")]
    WrongType {
        field: String,
        expected: &'static str,
        found: String,
    },
    #[error("{field} is missing")]
    Missing { field: String },
    #[error("{field}: unknown field (the fields here are: {allowed})")]
    UnknownField { field: String, allowed: String },
    #[error("keyframes: the list is empty; give at least one keyframe")]
    NoKeyframes,
    #[error("{field}: {found} positions for {dancers} dancers (one [x, z] or null per dancer)")]
    PositionCount {
        field: String,
        found: usize,
        dancers: usize,
    },
    #[error("{field}: t = {t} is not a finite number of seconds")]
    TimeNotFinite { field: String, t: f64 },
    #[error("{field}: t = {t} s is before the start of the song")]
    TimeNegative { field: String, t: f64 },
    #[error("{field}: t = {t} s is after the end of the song ({song_seconds} s)")]
    TimeBeyondSong {
        field: String,
        t: f64,
        song_seconds: f64,
    },
    #[error(
        "{field}: t = {t} s does not come after the previous keyframe's t = {previous} s \
         (times must strictly increase)"
    )]
    TimeNotIncreasing {
        field: String,
        t: f64,
        previous: f64,
    },
    #[error("{field}: {value} is not a finite number of metres")]
    CoordinateNotFinite { field: String, value: f64 },
    #[error(
        "{field}[{a}] and {field}[{b}]: dancers {a} and {b} are {distance:.3} m apart, closer \
         than the {min} m at which dancers collide",
        min = MIN_SEPARATION_M
    )]
    TooClose {
        field: String,
        a: usize,
        b: usize,
        distance: f64,
    },
    #[error("the song duration {0} s is not a finite, non-negative number")]
    BadSongDuration(f64),
}
