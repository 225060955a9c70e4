//! Gaussian smoothing of a per-frame signal: the root-path corrections of the solo and duet
//! pipelines and the duet representation's leader frame share this one filter.

/// What the kernel sees past the ends of the signal.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Ends {
    /// Nothing: the kernel is cut and renormalised, so a constant stays constant and the ends
    /// are not pulled towards made-up values (a trend flattens there).
    Renormalise,
    /// The signal mirrored through its end value (`2 x[0] − x[k]`), so a straight line stays
    /// straight up to the last frame.
    OddReflect,
    /// The end values repeated (scipy's `mode='nearest'`): a correction that is still needed at
    /// the last frame keeps its full size there.
    Hold,
}

/// Where [`gaussian_smooth`] cuts the kernel, in σ.
pub const TRUNCATE_SIGMAS: f64 = 3.0;

/// `x` convolved with a Gaussian of `sigma` frames, truncated at [`TRUNCATE_SIGMAS`] σ.
/// `sigma <= 0` returns `x`.
pub fn gaussian_smooth(x: &[f64], sigma: f64, ends: Ends) -> Vec<f64> {
    gaussian_smooth_truncated(x, sigma, TRUNCATE_SIGMAS, ends)
}

/// [`gaussian_smooth`] with the kernel cut at `truncate` σ (radius `⌈truncate · σ⌉` frames).
pub fn gaussian_smooth_truncated(x: &[f64], sigma: f64, truncate: f64, ends: Ends) -> Vec<f64> {
    let t = x.len();
    if sigma <= 0.0 || t == 0 {
        return x.to_vec();
    }
    let r = (truncate * sigma).ceil() as i64;
    let w: Vec<f64> = (-r..=r)
        .map(|i| (-((i * i) as f64) / (2.0 * sigma * sigma)).exp())
        .collect();
    let last = t as i64 - 1;
    let mirrored = |j: i64| -> f64 {
        // Mirror indices are clamped for signals shorter than the kernel.
        if j < 0 {
            2.0 * x[0] - x[(-j).min(last) as usize]
        } else {
            2.0 * x[last as usize] - x[(2 * last - j).max(0) as usize]
        }
    };
    (0..t as i64)
        .map(|f| {
            let (mut acc, mut norm) = (0.0, 0.0);
            for (k, wk) in (-r..=r).zip(&w) {
                let j = f + k;
                if (0..=last).contains(&j) {
                    acc += wk * x[j as usize];
                    norm += wk;
                } else if ends == Ends::OddReflect {
                    acc += wk * mirrored(j);
                    norm += wk;
                } else if ends == Ends::Hold {
                    acc += wk * x[j.clamp(0, last) as usize];
                    norm += wk;
                }
            }
            acc / norm
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn constants_survive_and_a_step_is_spread() {
        for ends in [Ends::Renormalise, Ends::OddReflect, Ends::Hold] {
            let s = gaussian_smooth(&[2.0; 9], 1.5, ends);
            assert!(s.iter().all(|v| (v - 2.0).abs() < 1e-12));
            let step: Vec<f64> = (0..20).map(|f| if f < 10 { 0.0 } else { 1.0 }).collect();
            let s = gaussian_smooth(&step, 2.0, ends);
            assert!(s[9] > 0.2 && s[9] < 0.5 && s[10] > 0.5 && s[10] < 0.8);
            assert_eq!(gaussian_smooth(&step, 0.0, ends), step);
        }
    }

    #[test]
    fn odd_reflection_keeps_a_line_straight_to_the_ends() {
        let line: Vec<f64> = (0..20).map(|f| 0.3 * f64::from(f) - 1.0).collect();
        let s = gaussian_smooth(&line, 2.0, Ends::OddReflect);
        for (a, b) in s.iter().zip(&line) {
            assert!((a - b).abs() < 1e-12);
        }
        // Renormalising flattens the trend at the ends.
        let s = gaussian_smooth(&line, 2.0, Ends::Renormalise);
        assert!(s[0] > line[0] + 0.1 && s[19] < line[19] - 0.1);
        // Shorter than the kernel (mirror indices clamped): finite, in order.
        let s = gaussian_smooth(&[0.0, 1.0, 2.0], 3.0, Ends::OddReflect);
        assert!(s.iter().all(|v| v.is_finite()) && s[0] < s[1] && s[1] < s[2]);
        assert!((gaussian_smooth(&[5.0], 3.0, Ends::OddReflect)[0] - 5.0).abs() < 1e-12);
    }

    #[test]
    fn holding_the_ends_keeps_an_edge_step_at_full_size() {
        let step: Vec<f64> = (0..30).map(|f| if f < 25 { 0.0 } else { 1.0 }).collect();
        let held = gaussian_smooth(&step, 2.0, Ends::Hold);
        let cut = gaussian_smooth(&step, 2.0, Ends::Renormalise);
        assert!(
            held[29] > 0.985 && held[29] > cut[29],
            "{} {}",
            held[29],
            cut[29]
        );
        // Holding flattens a ramp at the ends, like scipy's `nearest`.
        let ramp: Vec<f64> = (0..20).map(f64::from).collect();
        let s = gaussian_smooth_truncated(&ramp, 2.0, 4.0, Ends::Hold);
        assert!(s[19] < 19.0 - 0.5 && s[0] > 0.5);
    }
}
