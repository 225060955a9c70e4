//! Paths from one formation to the next that keep every pair of dancers apart.
//!
//! Every dancer moves on a minimum-jerk path ([`super::min_jerk`]) from its place to its target
//! over the same frames. Two dancers exchanging places on straight paths would walk through
//! each other at the midpoint, so a swap bends the swappers' paths (group.md §4.4, "swaps with
//! a lateral offset ≥ 0.4 m, or an upstage pass"):
//! - [`TransitionKind::LateralSwap`]: both swappers bow apart perpendicular to the line between
//!   their starting places, [`SWAP_LATERAL_OFFSET_M`] each side, so they pass twice that apart.
//! - [`TransitionKind::UpstagePass`]: one dancer bows [`UPSTAGE_PASS_DEPTH_M`] upstage (−z)
//!   and passes behind the other, who keeps the straight path downstage (and stays in view).
//!   This is for dancers exchanging places across the stage; for a front-to-back exchange the
//!   pass would run along their line, and [`plan_transition`] reports the collision.
//!
//! A bow is added on top of the straight path with the profile [`bow`] `= 64τ³(1 − τ)³`: zero
//! with zero velocity and acceleration at both ends (like the blend), full at the midpoint,
//! where the swappers cross. Whatever the kind, [`plan_transition`] checks every pair on every
//! frame against [`MIN_SEPARATION_M`] and returns an error rather than a colliding plan.

use super::min_jerk::{lerp, min_jerk};
use super::{MIN_SEPARATION_M, StagePos, min_pairwise_distance, too_close};

/// How far each swapper's path bows sideways at the crossing: group.md §4.4's minimum lateral
/// offset, 0.4 m. The swappers pass 0.8 m apart, clear of [`MIN_SEPARATION_M`].
pub const SWAP_LATERAL_OFFSET_M: f64 = 0.4;

/// How far upstage the passing dancer goes at the crossing (ours; group.md names the move
/// only): 0.8 m, the same clearance as a lateral swap's two offsets.
pub const UPSTAGE_PASS_DEPTH_M: f64 = 0.8;

/// Which paths a transition uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TransitionKind {
    /// Everybody on the straight minimum-jerk path.
    Direct,
    /// Dancers `a` and `b` bow apart sideways; `a` bows towards `(−u_z, u_x)`, `u` pointing from
    /// `a`'s start to `b`'s, so with `a` on the left of `b`, `a` passes downstage and `b`
    /// upstage. Everybody else goes straight.
    LateralSwap { a: usize, b: usize },
    /// `behind` bows upstage and passes behind `front`, who goes straight; so does everybody
    /// else.
    UpstagePass { behind: usize, front: usize },
}

/// Why no transition was planned.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TransitionError {
    #[error("{from} dancers in the first formation but {to} in the second")]
    LengthMismatch { from: usize, to: usize },
    #[error("a transition over {frames} frames: it needs at least 2 (start and end)")]
    TooFewFrames { frames: usize },
    #[error("{formation} formation: dancer {dancer} has a non-finite position")]
    NotFinite {
        formation: &'static str,
        dancer: usize,
    },
    #[error("swap of dancer {dancer}: there are only {dancers} dancers")]
    NoSuchDancer { dancer: usize, dancers: usize },
    #[error("swap of dancer {0} with itself")]
    SameDancer(usize),
    #[error(
        "dancers {a} and {b} come {distance:.3} m apart at frame {frame}, closer than the \
         {min} m at which dancers collide (swap them, or space the formations wider)",
        min = MIN_SEPARATION_M
    )]
    TooClose {
        a: usize,
        b: usize,
        frame: usize,
        distance: f64,
    },
}

/// The bow profile `64τ³(1 − τ)³` (ours): 0 at `τ = 0` and `1` with zero velocity and
/// acceleration, 1 at `τ = ½`. `τ` is clamped to `[0, 1]`.
#[inline]
pub fn bow(tau: f64) -> f64 {
    let t = tau.clamp(0.0, 1.0);
    let u = t * (1.0 - t);
    64.0 * u * u * u
}

/// `from` with dancers `a` and `b` exchanged: the targets of a swap.
pub fn swap_targets(from: &[StagePos], a: usize, b: usize) -> Vec<StagePos> {
    let mut to = from.to_vec();
    if a < to.len() && b < to.len() {
        to.swap(a, b);
    }
    to
}

/// Paths `paths[dancer][frame]` over `frames` frames from `from` to `to` (dancer `d` goes from
/// `from[d]` to `to[d]`; frame 0 and frame `frames − 1` are exactly the formations), with the
/// swap paths of `kind` (module docs). Errors if any two dancers come closer than
/// [`MIN_SEPARATION_M`] on any frame, naming the closest pair and the frame where they are
/// closest.
pub fn plan_transition(
    from: &[StagePos],
    to: &[StagePos],
    kind: TransitionKind,
    frames: usize,
) -> Result<Vec<Vec<StagePos>>, TransitionError> {
    let n = from.len();
    if to.len() != n {
        return Err(TransitionError::LengthMismatch {
            from: n,
            to: to.len(),
        });
    }
    if frames < 2 {
        return Err(TransitionError::TooFewFrames { frames });
    }
    for (formation, positions) in [("first", from), ("second", to)] {
        if let Some(dancer) = positions
            .iter()
            .position(|p| !(p[0].is_finite() && p[1].is_finite()))
        {
            return Err(TransitionError::NotFinite { formation, dancer });
        }
    }
    let mut bows = vec![[0.0, 0.0]; n];
    match kind {
        TransitionKind::Direct => {}
        TransitionKind::LateralSwap { a, b } => {
            check_pair(a, b, n)?;
            let (dx, dz) = (from[b][0] - from[a][0], from[b][1] - from[a][1]);
            let length = dx.hypot(dz);
            // Coincident starts have no line between them; bow along z (the frame-0 check
            // below reports the collision anyway).
            let (ux, uz) = if length > 0.0 {
                (dx / length, dz / length)
            } else {
                (1.0, 0.0)
            };
            let side = [-uz * SWAP_LATERAL_OFFSET_M, ux * SWAP_LATERAL_OFFSET_M];
            bows[a] = side;
            bows[b] = [-side[0], -side[1]];
        }
        TransitionKind::UpstagePass { behind, front } => {
            check_pair(behind, front, n)?;
            bows[behind] = [0.0, -UPSTAGE_PASS_DEPTH_M];
        }
    }
    let last = frames - 1;
    let paths: Vec<Vec<StagePos>> = (0..n)
        .map(|d| {
            let mut path: Vec<StagePos> = (0..frames)
                .map(|f| {
                    let tau = f as f64 / last as f64;
                    let (p, k) = (lerp(from[d], to[d], min_jerk(tau)), bow(tau));
                    [p[0] + bows[d][0] * k, p[1] + bows[d][1] * k]
                })
                .collect();
            (path[0], path[last]) = (from[d], to[d]);
            path
        })
        .collect();
    if let Some(closest) = min_pairwise_distance(&paths)
        && too_close(closest.pair.distance)
    {
        return Err(TransitionError::TooClose {
            a: closest.pair.a,
            b: closest.pair.b,
            frame: closest.frame,
            distance: closest.pair.distance,
        });
    }
    Ok(paths)
}

fn check_pair(a: usize, b: usize, dancers: usize) -> Result<(), TransitionError> {
    for dancer in [a, b] {
        if dancer >= dancers {
            return Err(TransitionError::NoSuchDancer { dancer, dancers });
        }
    }
    if a == b {
        return Err(TransitionError::SameDancer(a));
    }
    Ok(())
}
