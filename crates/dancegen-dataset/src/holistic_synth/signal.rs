//! Small per-frame signal helpers shared by the synthetic hands and face.

use dancegen_motion::rng::SplitMix64;

/// Centred moving average over `radius` frames each side (shorter at the ends).
pub fn smooth(x: &[f32], radius: usize) -> Vec<f32> {
    let n = x.len();
    let mut prefix = vec![0.0f64; n + 1];
    for (i, &v) in x.iter().enumerate() {
        prefix[i + 1] = prefix[i] + v as f64;
    }
    (0..n)
        .map(|i| {
            let (a, b) = (i.saturating_sub(radius), (i + radius + 1).min(n));
            ((prefix[b] - prefix[a]) / (b - a) as f64) as f32
        })
        .collect()
}

/// The `q` quantile (0–1) of `x` (nearest rank; 0 for an empty slice).
pub fn quantile(x: &[f32], q: f32) -> f32 {
    if x.is_empty() {
        return 0.0;
    }
    let mut v: Vec<f32> = x.iter().copied().filter(|v| v.is_finite()).collect();
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(f32::total_cmp);
    v[((v.len() - 1) as f32 * q.clamp(0.0, 1.0)).round() as usize]
}

/// `x` scaled so its 95th percentile is 1, clamped to [0, 1] (all zeros stay zeros).
pub fn unit_scale(x: &[f32]) -> Vec<f32> {
    let top = quantile(x, 0.95);
    if top <= 0.0 {
        return vec![0.0; x.len()];
    }
    x.iter().map(|v| (v / top).clamp(0.0, 1.0)).collect()
}

/// Per-frame speed (units per second) of point `k` of `(T, n, 3)` `points` at `fps`, by central
/// differences (one-sided at the ends).
pub fn point_speed(points: &[f32], n: usize, k: usize, fps: f32) -> Vec<f32> {
    let t = points.len() / (n * 3);
    let p = |f: usize| {
        let o = (f * n + k) * 3;
        [points[o], points[o + 1], points[o + 2]]
    };
    (0..t)
        .map(|f| {
            if t < 2 {
                return 0.0;
            }
            let (a, b) = (f.saturating_sub(1), (f + 1).min(t - 1));
            let (pa, pb) = (p(a), p(b));
            let d = ((pb[0] - pa[0]).powi(2) + (pb[1] - pa[1]).powi(2) + (pb[2] - pa[2]).powi(2))
                .sqrt();
            d * fps / (b - a) as f32
        })
        .collect()
}

/// Hermite smoothstep of `x` in [0, 1].
pub fn smoothstep(x: f32) -> f32 {
    let x = x.clamp(0.0, 1.0);
    x * x * (3.0 - 2.0 * x)
}

/// A slow random wobble: the sum of two sines with random frequencies in `[lo, hi]` Hz and
/// random phases, amplitude `amp` (peak of each sine), sampled at `fps` for `t` frames.
pub fn wobble(rng: &mut SplitMix64, t: usize, fps: f32, lo: f32, hi: f32, amp: f32) -> Vec<f32> {
    let mut parts = [(0.0f32, 0.0f32); 2];
    for p in &mut parts {
        *p = (
            lo + (hi - lo) * rng.next_f64() as f32,
            std::f32::consts::TAU * rng.next_f64() as f32,
        );
    }
    (0..t)
        .map(|f| {
            let s = f as f32 / fps;
            parts
                .iter()
                .map(|(hz, ph)| amp * (std::f32::consts::TAU * hz * s + ph).sin())
                .sum()
        })
        .collect()
}

/// A standard Gumbel draw (for sampling an argmax with noise).
pub fn gumbel(rng: &mut SplitMix64) -> f32 {
    let u = rng.next_f64().clamp(1e-12, 1.0 - 1e-12);
    -(-(u.ln())).ln() as f32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn helpers() {
        assert_eq!(smooth(&[0.0, 3.0, 0.0], 1), vec![1.5, 1.0, 1.5]);
        assert_eq!(quantile(&[3.0, 1.0, 2.0], 0.5), 2.0);
        assert_eq!(unit_scale(&[0.0, 0.0]), vec![0.0, 0.0]);
        // A point moving 0.1 per frame at 30 fps: 3 units/s everywhere.
        let pts: Vec<f32> = (0..5).flat_map(|f| [0.1 * f as f32, 0.0, 0.0]).collect();
        let v = point_speed(&pts, 1, 0, 30.0);
        assert!(v.iter().all(|s| (s - 3.0).abs() < 1e-4), "{v:?}");
        assert_eq!(
            (smoothstep(0.0), smoothstep(0.5), smoothstep(1.0)),
            (0.0, 0.5, 1.0)
        );
        let mut r = SplitMix64(1);
        let w = wobble(&mut r, 300, 30.0, 0.5, 1.0, 0.1);
        assert!(w.iter().all(|v| v.abs() <= 0.2 + 1e-6));
        assert!(quantile(&w, 0.9) > 0.05);
    }
}
