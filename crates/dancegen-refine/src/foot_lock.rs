//! Planted feet stay planted: a correction of the root's horizontal path from foot contacts.
//!
//! A generator that predicts the root's travel and the legs separately can move the body while
//! a foot it calls planted stays in the same pose, so the foot glides over the floor (foot
//! skating). Translating the whole body by minus the planted feet's horizontal step removes
//! that glide without touching the pose: with one planted foot its step becomes exactly zero,
//! with two the mean of their steps is removed. Frames without contact keep their own travel,
//! so jumps and slides the dance means to do survive, and the correction accumulates into the
//! path (the dancer travels by stepping).
//!
//! Which feet are planted comes from the caller: a model's own contact predictions, feet near
//! the floor ([`height_contacts`]), or both.
//!
//! This is not part of any of the four published methods; the systems use it as a named
//! post-processing step that can be switched off (`--no-foot-lock`) and report it as such.

/// Contact weight at or above which a foot counts as planted. EDGE's foot loss uses 0.95 on
/// its contact predictions (anchors C.2); a lower cut keeps feet the model is only fairly sure
/// of, and weights in between count partially (see [`contact_weight`]).
pub const PLANTED: f32 = 0.5;

/// When a foot counts as planted: a model's contact label, nearness to the floor, or both
/// (`dancegen_lodgepp::planted_feet` explains the choice for dance footwork).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PlantedRule {
    /// The model's contact label **or** near the floor (the rule of the first bundles).
    #[default]
    Either,
    /// The model's contact label **and** near the floor: a low foot the model moves is left
    /// to move (slides and steps close to the floor), a lifted foot is never pinned.
    Both,
}

/// How much a foot with contact prediction `c` (nominally 0 or 1) counts: 0 below
/// [`PLANTED`], rising linearly to 1 at 0.9.
pub fn contact_weight(c: f32) -> f32 {
    ((c - PLANTED) / (0.9 - PLANTED)).clamp(0.0, 1.0)
}

/// Contacts from geometry: 1 where foot `k` is less than `thresholds[k]` above `floor`, else 0
/// (`[T, F]`, same layout as the contacts [`planted_feet_offsets`] takes).
pub fn height_contacts(
    feet: &[f32],
    n_feet: usize,
    up: usize,
    floor: f32,
    thresholds: &[f32],
) -> Vec<f32> {
    assert_eq!(thresholds.len(), n_feet, "one threshold per foot");
    feet.chunks_exact(3)
        .enumerate()
        .map(|(i, p)| f32::from(u8::from(p[up] - floor < thresholds[i % n_feet])))
        .collect()
}

/// The axes of a coordinate system the correction needs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Axes {
    pub horizontal: [usize; 2],
    pub up: usize,
}

impl Axes {
    pub const Z_UP: Axes = Axes {
        horizontal: [0, 1],
        up: 2,
    };
    pub const Y_UP: Axes = Axes {
        horizontal: [0, 2],
        up: 1,
    };
}

/// Cumulative horizontal offsets `[T]` to add to the root (and so to every joint) that cancel
/// the support foot's horizontal steps. `feet` is `[T, F, 3]` (flat) in metres, `contact`
/// `[T, F]` (flat) the contact predictions. The support foot of a step is the lowest of the
/// feet planted at both of its ends (the one carrying the weight); its step is removed in
/// proportion to its contact weight. Removing one foot's step rather than the mean of all
/// planted feet keeps it exactly still when the model plants feet that move apart.
pub fn planted_feet_offsets(
    feet: &[f32],
    contact: &[f32],
    n_feet: usize,
    axes: Axes,
) -> Vec<[f32; 2]> {
    let frames = contact.len().checked_div(n_feet).unwrap_or(0);
    assert_eq!(
        feet.len(),
        frames * n_feet * 3,
        "feet and contacts disagree"
    );
    let at = |t: usize, k: usize, axis: usize| feet[(t * n_feet + k) * 3 + axis];
    let mut out = vec![[0f32; 2]; frames];
    for t in 1..frames {
        out[t] = out[t - 1];
        let support = (0..n_feet)
            .map(|k| {
                let w = contact_weight(contact[(t - 1) * n_feet + k])
                    .min(contact_weight(contact[t * n_feet + k]));
                (k, w)
            })
            .filter(|&(_, w)| w > 0.0)
            .min_by(|a, b| at(t, a.0, axes.up).total_cmp(&at(t, b.0, axes.up)));
        if let Some((k, w)) = support {
            for (a, &axis) in axes.horizontal.iter().enumerate() {
                out[t][a] -= w * (at(t, k, axis) - at(t - 1, k, axis));
            }
        }
    }
    out
}

/// [`planted_feet_offsets`] on a leash: every step's correction fades with time constant
/// `frames` (`o[t] = e^(−1/frames) o[t−1] + Δ[t]`), so the correction removes glides of a few
/// steps but never accumulates into the path. For a dancer whose place is set by someone else
/// (a duet follower beside its leader): the unleashed correction drifts the follower away from
/// the leader by the sum of every removed glide over the whole dance.
pub fn leashed(offsets: &[[f32; 2]], frames: f64) -> Vec<[f32; 2]> {
    let keep = (-1.0 / frames.max(f64::MIN_POSITIVE)).exp() as f32;
    let mut out = Vec::with_capacity(offsets.len());
    let mut prev_in = [0f32; 2];
    let mut prev_out = [0f32; 2];
    for o in offsets {
        let next: [f32; 2] = std::array::from_fn(|a| keep * prev_out[a] + (o[a] - prev_in[a]));
        out.push(next);
        prev_in = *o;
        prev_out = next;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_planted_foot_stops_gliding_and_a_swinging_one_keeps_its_step() {
        // Two feet, Z-up. The body glides +2 cm/frame in x; foot 0 is planted (its pose keeps it
        // under the body, so it glides too), foot 1 swings forward 5 cm/frame relative to it.
        let t = 10;
        let mut feet = vec![0f32; t * 2 * 3];
        let mut contact = vec![0f32; t * 2];
        for f in 0..t {
            feet[f * 6] = 0.02 * f as f32;
            feet[f * 6 + 3] = 0.07 * f as f32;
            feet[f * 6 + 5] = 0.1; // foot 1 in the air
            contact[f * 2] = 1.0;
        }
        let off = planted_feet_offsets(&feet, &contact, 2, Axes::Z_UP);
        for f in 0..t {
            let planted = feet[f * 6] + off[f][0];
            let swing = feet[f * 6 + 3] + off[f][0];
            assert!(planted.abs() < 1e-6, "frame {f}: planted foot at {planted}");
            assert!(
                (swing - 0.05 * f as f32).abs() < 1e-6,
                "frame {f}: swing {swing}"
            );
            assert_eq!(off[f][1], 0.0);
        }
    }

    #[test]
    fn low_feet_are_in_contact() {
        // Two frames, two feet (Y-up): heights 0.03 / 0.2 and 0.1 / 0.04 above a floor at −0.01.
        let feet = [0., 0.02, 0., 0., 0.19, 0., 0., 0.09, 0., 0., 0.03, 0.];
        assert_eq!(
            height_contacts(&feet, 2, 1, -0.01, &[0.12, 0.05]),
            vec![1.0, 0.0, 1.0, 1.0]
        );
    }

    #[test]
    fn without_contact_nothing_moves() {
        let feet: Vec<f32> = (0..4 * 3).map(|i| i as f32 * 0.1).collect();
        let off = planted_feet_offsets(&feet, &[0.0, 0.2, 0.49, 0.0], 1, Axes::Y_UP);
        assert!(off.iter().all(|o| *o == [0.0, 0.0]));
    }

    #[test]
    fn of_two_planted_feet_the_lower_one_is_held() {
        // Both feet planted and gliding +3 cm/frame in x; foot 1 also drifts in y and is 2 cm
        // higher: foot 0 carries the weight and is held exactly still.
        let t = 5;
        let mut feet = vec![0f32; t * 2 * 3];
        for f in 0..t {
            feet[f * 6] = 0.03 * f as f32;
            feet[f * 6 + 3] = 0.03 * f as f32;
            feet[f * 6 + 4] = -0.01 * f as f32;
            feet[f * 6 + 5] = 0.02;
        }
        let off = planted_feet_offsets(&feet, &vec![1.0; t * 2], 2, Axes::Z_UP);
        for (f, o) in off.iter().enumerate() {
            assert!(
                (o[0] + 0.03 * f as f32).abs() < 1e-6 && o[1].abs() < 1e-6,
                "{o:?}"
            );
        }
    }

    #[test]
    fn a_leashed_correction_fades_after_the_glide_and_keeps_the_glide_removed_while_it_lasts() {
        // Cumulative offsets of a 10-frame glide of −1 cm/frame, then nothing.
        let raw: Vec<[f32; 2]> = (0..100).map(|t| [-0.01 * t.min(10) as f32, 0.0]).collect();
        let held = leashed(&raw, 1e9);
        for (a, b) in raw.iter().zip(&held) {
            assert!(
                (a[0] - b[0]).abs() < 1e-5,
                "an endless leash is the plain correction"
            );
        }
        let l = leashed(&raw, 15.0);
        // During the glide the steps are removed almost fully (the leash only lets a little
        // back per frame)...
        assert!((l[1][0] - raw[1][0]).abs() < 1e-6);
        assert!(l[10][0] < -0.07, "{}", l[10][0]);
        // ...and afterwards the correction returns to the model's own place: what is left at
        // frame 99 is at most the 10 cm glide decayed over the 89 frames since it ended.
        assert!(
            l[99][0].abs() < 0.01 * (-89.0f32 / 15.0).exp() * 10.0,
            "{}",
            l[99][0]
        );
        assert!(l[99][0] < 0.0 && l[99][0] > l[50][0]);
    }
}
