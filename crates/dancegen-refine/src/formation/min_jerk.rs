//! The minimum-jerk blend, the one time profile every move on the stage uses.
//!
//! Flash & Hogan (1985) showed that unconstrained point-to-point arm movements follow the path
//! that minimises the integrated squared jerk; for a move that starts and ends at rest the
//! solution is the quintic `s(τ) = 10τ³ − 15τ⁴ + 6τ⁵`. group.md §4.4 puts formation transitions
//! on these paths: a dancer walking to a new spot accelerates and settles smoothly, and paths
//! chained end to end join with zero velocity and acceleration, so no frame jumps.

use super::StagePos;

/// The minimum-jerk blend `s(τ) = 10τ³ − 15τ⁴ + 6τ⁵` (Flash & Hogan 1985), `τ` clamped to
/// `[0, 1]`. Evaluated in Horner form so `s(0) = 0` and `s(1) = 1` exactly.
#[inline]
pub fn min_jerk(tau: f64) -> f64 {
    let t = tau.clamp(0.0, 1.0);
    t * t * t * (10.0 + t * (-15.0 + 6.0 * t))
}

/// `ds/dτ = 30τ²(1 − τ)²`, zero at both ends and never negative (the blend is monotone).
#[inline]
pub fn min_jerk_rate(tau: f64) -> f64 {
    let t = tau.clamp(0.0, 1.0);
    30.0 * t * t * (1.0 - t) * (1.0 - t)
}

/// The point a fraction `s` of the way from `from` to `to`, written `from·(1 − s) + to·s` so
/// `s = 0` and `s = 1` return the endpoints bit for bit (`from + (to − from)·1` need not).
#[inline]
pub fn lerp(from: StagePos, to: StagePos, s: f64) -> StagePos {
    [
        from[0] * (1.0 - s) + to[0] * s,
        from[1] * (1.0 - s) + to[1] * s,
    ]
}

/// Where a minimum-jerk move from `from` to `to` is at normalised time `tau` in `[0, 1]`.
#[inline]
pub fn min_jerk_point(from: StagePos, to: StagePos, tau: f64) -> StagePos {
    lerp(from, to, min_jerk(tau))
}

/// A minimum-jerk move sampled on `frames` frames: frame 0 is `from`, frame `frames − 1` is
/// `to` (both exact), frame `f` is at `τ = f / (frames − 1)`. A single frame is the arrival
/// (`[to]`): the caller asked for a move that takes no time. No frames, no samples.
pub fn min_jerk_path(from: StagePos, to: StagePos, frames: usize) -> Vec<StagePos> {
    match frames {
        0 => Vec::new(),
        1 => vec![to],
        _ => {
            let last = (frames - 1) as f64;
            (0..frames)
                .map(|f| min_jerk_point(from, to, f as f64 / last))
                .collect()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blend_endpoints_are_exact() {
        assert_eq!(min_jerk(0.0), 0.0);
        assert_eq!(min_jerk(1.0), 1.0);
        assert_eq!(min_jerk(0.5), 0.5);
        assert_eq!(min_jerk(-3.0), 0.0);
        assert_eq!(min_jerk(7.0), 1.0);
        let (a, b) = ([0.1, -0.7], [0.3, 2.9]);
        let path = min_jerk_path(a, b, 91);
        assert_eq!(path.len(), 91);
        assert_eq!(path[0], a);
        assert_eq!(path[90], b);
        assert_eq!(min_jerk_path(a, b, 1), vec![b]);
        assert!(min_jerk_path(a, b, 0).is_empty());
    }

    #[test]
    fn velocity_and_acceleration_vanish_at_both_ends() {
        // Central differences at h = 1e-4: the true values are 0 and O(h²) = 1e-8 for
        // velocity (30τ² near 0), O(h) = 6e-3 for acceleration (60τ); the tolerances bound that.
        let h = 1e-4;
        for end in [0.0, 1.0] {
            let s = |t: f64| 10.0 * t.powi(3) - 15.0 * t.powi(4) + 6.0 * t.powi(5);
            let vel = (s(end + h) - s(end - h)) / (2.0 * h);
            let acc = (s(end + h) - 2.0 * s(end) + s(end - h)) / (h * h);
            assert!(vel.abs() < 1e-6, "velocity {vel} at τ = {end}");
            assert!(acc.abs() < 1e-2, "acceleration {acc} at τ = {end}");
            // The clamped blend holds still outside [0, 1], so one-sided differences too.
            let inside = if end == 0.0 { h } else { -h };
            let one_sided = (min_jerk(end + inside) - min_jerk(end)) / inside;
            assert!(one_sided.abs() < 1e-6);
            assert_eq!(min_jerk_rate(end), 0.0);
        }
        // The rate matches the blend's derivative in the middle.
        let (t, h) = (0.3, 1e-6);
        let numeric = (min_jerk(t + h) - min_jerk(t - h)) / (2.0 * h);
        assert!((numeric - min_jerk_rate(t)).abs() < 1e-8);
    }

    #[test]
    fn blend_is_monotone_and_symmetric() {
        let mut previous = 0.0;
        for i in 1..=1000 {
            let t = i as f64 / 1000.0;
            let s = min_jerk(t);
            assert!(s >= previous, "s({t}) = {s} < {previous}");
            assert!(min_jerk_rate(t) >= 0.0);
            // s(1 − τ) = 1 − s(τ): the move accelerates and settles the same way.
            assert!((min_jerk(1.0 - t) - (1.0 - s)).abs() < 1e-12);
            previous = s;
        }
        let path = min_jerk_path([0.0, 0.0], [2.0, -1.0], 31);
        assert!(
            path.windows(2)
                .all(|w| w[1][0] >= w[0][0] && w[1][1] <= w[0][1])
        );
    }
}
