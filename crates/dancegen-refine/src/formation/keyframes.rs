//! The user's FORMATION.json: where each dancer must be at given times.
//!
//! ```json
//! {"keyframes": [
//!   {"t": 0.0, "positions": [[-0.9, 0.0], [0.0, 0.0], [0.9, 0.0]]},
//!   {"t": 4.0, "positions": [[0.9, 0.0], null, [-0.9, 0.0]]}
//! ]}
//! ```
//!
//! `t` is seconds from the start of the song; each position is `[x, z]` in metres in the stage
//! frame ([`super`]), one per dancer in dancer order, or `null` where that dancer is free.
//!
//! # What a formation constrains (the product contract, [`Formation::sample`])
//! - **Keyframe frames**: a keyframe at `t` falls on frame `round(t · fps)` (round to nearest,
//!   halves away from zero, `f64::round`). On its frame a given position is exact.
//! - **Between two consecutive keyframes** where a dancer is given at both, the dancer moves
//!   from one position to the other on a minimum-jerk path in time ([`super::min_jerk`]) over
//!   the frames between them, so it arrives at rest and leaves at rest.
//! - **Free frames** (`None`): inside a segment where either end is `null` for that dancer,
//!   before its first given keyframe and after its last. A dancer given at one keyframe only is
//!   constrained on that frame only. A `null` therefore frees the dancer in both segments
//!   touching that keyframe; the generator decides where it goes.
//! - Keyframes closer together than one frame round onto the same frame; there the **later**
//!   keyframe's position is the one kept. Frames at or past `frames` are dropped.
//!
//! Validation ([`Formation::new`]) rejects what no dance can satisfy: times outside the song or
//! out of order, a wrong number of positions, non-finite coordinates, and two given dancers
//! closer than [`super::MIN_SEPARATION_M`] at one keyframe. It does not limit speed (a long
//! move in a short time is the user's choice) and does not check the paths between keyframes:
//! [`Formation::closest_constrained_approach`] does.

pub use super::keyframes_error::{FormationError, FormationProblem};
use super::min_jerk::min_jerk_point;
use super::{
    ClosestApproach, Pair, StagePos, closest_pair, distance, order_left_to_right, too_close,
};
use serde::Serialize;

/// One keyframe: a time and, per dancer, a position or `None` (free).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Keyframe {
    /// Seconds from the start of the song.
    pub t: f64,
    /// One entry per dancer; `None` is `null` in the file.
    pub positions: Vec<Option<StagePos>>,
}

/// A validated formation: keyframes with strictly increasing times inside the song, one
/// position per dancer, given dancers at least [`super::MIN_SEPARATION_M`] apart. Serialises
/// back to the FORMATION.json layout.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Formation {
    keyframes: Vec<Keyframe>,
    #[serde(skip)]
    dancers: usize,
}

/// The frame a keyframe time falls on: `round(t · fps)`, halves away from zero. Negative or
/// NaN products give frame 0 and huge ones `usize::MAX` (a saturating cast), never a panic.
#[inline]
pub fn keyframe_frame(t: f64, fps: f64) -> usize {
    (t * fps).round() as usize
}

impl Formation {
    /// Validates keyframes built in code (the composition generator's, say) by the rules of the
    /// file; `label` names their source in errors.
    pub fn new(
        label: &str,
        keyframes: Vec<Keyframe>,
        dancers: usize,
        song_seconds: f64,
    ) -> Result<Formation, FormationError> {
        validate(&keyframes, dancers, song_seconds).map_err(|problem| FormationError {
            file: label.to_string(),
            problem,
        })?;
        Ok(Formation { keyframes, dancers })
    }

    /// The keyframes, in time order.
    pub fn keyframes(&self) -> &[Keyframe] {
        &self.keyframes
    }

    /// The number of dancers (positions per keyframe).
    pub fn dancers(&self) -> usize {
        self.dancers
    }

    /// Per dancer and frame (`[dancer][frame]`, `frames` frames at `fps`), the constrained stage
    /// position or `None` where the dancer is free, by the rules in the module docs. A `fps`
    /// that is not finite and positive constrains nothing (every frame free).
    pub fn sample(&self, fps: f64, frames: usize) -> Vec<Vec<Option<StagePos>>> {
        let mut out = vec![vec![None; frames]; self.dancers];
        if !(fps.is_finite() && fps > 0.0) || frames == 0 {
            return out;
        }
        let at: Vec<usize> = self
            .keyframes
            .iter()
            .map(|k| keyframe_frame(k.t, fps))
            .collect();
        for (d, track) in out.iter_mut().enumerate() {
            for (w, pair) in self.keyframes.windows(2).enumerate() {
                let (Some(from), Some(to)) = (pair[0].positions[d], pair[1].positions[d]) else {
                    continue;
                };
                let (fa, fb) = (at[w], at[w + 1]);
                let span = fb.saturating_sub(fa) as f64;
                for (f, slot) in track
                    .iter_mut()
                    .enumerate()
                    .take(fb.saturating_add(1))
                    .skip(fa)
                {
                    let tau = if span > 0.0 {
                        (f - fa) as f64 / span
                    } else {
                        1.0
                    };
                    *slot = Some(min_jerk_point(from, to, tau));
                }
            }
            // Given positions are exact on their frames; on shared frames the later one wins.
            for (k, keyframe) in self.keyframes.iter().enumerate() {
                if let (Some(p), Some(slot)) = (keyframe.positions[d], track.get_mut(at[k])) {
                    *slot = Some(p);
                }
            }
        }
        out
    }

    /// The closest approach of two dancers on frames where [`Formation::sample`] constrains
    /// both (`None` if no frame constrains two). Validation only checks the keyframes
    /// themselves, so two dancers told to exchange places walk through each other on the
    /// straight paths between; a caller that follows the constraints should check this against
    /// [`super::too_close`] (or route such swaps through [`super::transition`]).
    pub fn closest_constrained_approach(&self, fps: f64, frames: usize) -> Option<ClosestApproach> {
        let tracks = self.sample(fps, frames);
        let mut best: Option<ClosestApproach> = None;
        for frame in 0..frames {
            let given: Vec<(usize, StagePos)> = tracks
                .iter()
                .enumerate()
                .filter_map(|(d, track)| track[frame].map(|p| (d, p)))
                .collect();
            let positions: Vec<StagePos> = given.iter().map(|&(_, p)| p).collect();
            if let Some(pair) = closest_pair(&positions)
                && best.is_none_or(|b| pair.distance < b.pair.distance)
            {
                let (a, b) = (given[pair.a].0, given[pair.b].0);
                let pair = Pair { a, b, ..pair };
                best = Some(ClosestApproach { frame, pair });
            }
        }
        best
    }

    /// The audience's left-to-right order at the first keyframe, if every dancer is given there.
    pub fn start_order(&self) -> Option<Vec<usize>> {
        self.keyframes.first().and_then(order_if_complete)
    }

    /// The audience's left-to-right order at the last keyframe, if every dancer is given there
    /// (the "final order" of group.md §4.4, which the swap mode S is built from).
    pub fn end_order(&self) -> Option<Vec<usize>> {
        self.keyframes.last().and_then(order_if_complete)
    }
}

fn order_if_complete(keyframe: &Keyframe) -> Option<Vec<usize>> {
    let positions: Option<Vec<StagePos>> = keyframe.positions.iter().copied().collect();
    positions.map(|p| order_left_to_right(&p))
}

fn validate(
    keyframes: &[Keyframe],
    dancers: usize,
    song_seconds: f64,
) -> Result<(), FormationProblem> {
    if !(song_seconds.is_finite() && song_seconds >= 0.0) {
        return Err(FormationProblem::BadSongDuration(song_seconds));
    }
    if keyframes.is_empty() {
        return Err(FormationProblem::NoKeyframes);
    }
    for (k, keyframe) in keyframes.iter().enumerate() {
        let (field, t) = (format!("keyframes[{k}].t"), keyframe.t);
        if !t.is_finite() {
            return Err(FormationProblem::TimeNotFinite { field, t });
        }
        if t < 0.0 {
            return Err(FormationProblem::TimeNegative { field, t });
        }
        if t > song_seconds {
            return Err(FormationProblem::TimeBeyondSong {
                field,
                t,
                song_seconds,
            });
        }
        if let Some(previous) = k.checked_sub(1).map(|p| keyframes[p].t)
            && t <= previous
        {
            return Err(FormationProblem::TimeNotIncreasing { field, t, previous });
        }
        let field = format!("keyframes[{k}].positions");
        if keyframe.positions.len() != dancers {
            return Err(FormationProblem::PositionCount {
                field,
                found: keyframe.positions.len(),
                dancers,
            });
        }
        for (d, p) in keyframe.positions.iter().enumerate() {
            for (c, &value) in p.iter().flatten().enumerate() {
                if !value.is_finite() {
                    let field = format!("{field}[{d}][{c}]");
                    return Err(FormationProblem::CoordinateNotFinite { field, value });
                }
            }
        }
        let given: Vec<(usize, StagePos)> = keyframe
            .positions
            .iter()
            .enumerate()
            .filter_map(|(d, p)| p.map(|p| (d, p)))
            .collect();
        for (i, &(a, pa)) in given.iter().enumerate() {
            for &(b, pb) in &given[i + 1..] {
                let distance = distance(pa, pb);
                if too_close(distance) {
                    return Err(FormationProblem::TooClose {
                        field,
                        a,
                        b,
                        distance,
                    });
                }
            }
        }
    }
    Ok(())
}
