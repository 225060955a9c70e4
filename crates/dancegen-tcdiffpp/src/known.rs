//! The known parts of an edited group dance (`generate --edit`, `--continue-from`,
//! `--keep-joints`, `--keyframe` with `--system group`), as the LGDS sampler uses them.
//!
//! What is known is a mask over the raw frames `[T, N_MAX·151]` (Z-up, metres, roots on the
//! stage: the layout [`crate::sampler::generate`] returns). In each window:
//! - a window whose new frames are all known is not sampled: they are copied, and the next
//!   window continues from them as from any sampled window;
//! - otherwise every known value of the window's new frames is a hard cue in window
//!   coordinates (slots sorted, roots minus the window's origin), imposed as the window's
//!   prefix is ([`crate::config::PrefixMode`]), and a dancer whose root is known on a frame
//!   where the rest of it is not gets the formation-control flag there, as a requested path does
//!   (the network was trained to read a clean root under that flag).
//!
//! The sampler's last step writes the clean cued values, so known values come back exactly
//! (up to the normaliser's rounding; callers splice the raw values back).

use dancegen_nn::edge151::{DIMS, ROOT_HORIZONTAL};

use crate::layout::{GROUP_DIMS, N_MAX, channel};

/// See the module documentation. `values` and `mask` are `[frames, N_MAX·151]`, flat; `mask`
/// is 1 where the value is known.
#[derive(Clone, Copy, Debug)]
pub struct GroupKnown<'a> {
    pub values: &'a [f32],
    pub mask: &'a [f32],
}

/// A window's cues from what is known: values and mask `[W, N_MAX·151]` in window
/// coordinates, and control flags `[W, N_MAX]`.
pub(crate) struct KnownCue {
    pub values: Vec<f32>,
    pub mask: Vec<f32>,
    pub flags: Vec<f32>,
}

impl GroupKnown<'_> {
    pub fn frames(&self) -> usize {
        self.values.len() / GROUP_DIMS
    }

    fn is_known(&self, f: usize, i: usize) -> bool {
        self.mask[f * GROUP_DIMS + i] > 0.0
    }

    /// Every channel of the first `n` dancers known at frame `f`.
    pub fn frame_known(&self, f: usize, n: usize) -> bool {
        (0..n * DIMS).all(|i| self.is_known(f, i))
    }

    /// Some channel of dancer `d` known at frame `f`.
    pub fn any_known(&self, f: usize, d: usize) -> bool {
        (0..DIMS).any(|c| self.is_known(f, channel(d, c)))
    }

    /// Dancer `d`'s root x/y known at frame `f`.
    pub fn root_known(&self, f: usize, d: usize) -> bool {
        ROOT_HORIZONTAL
            .iter()
            .all(|&c| self.is_known(f, channel(d, c)))
    }

    /// Frame `f` normalised (`(raw − shift) / scale`, roots on the stage), slots `n..` zero.
    pub(crate) fn normalised(&self, f: usize, n: usize, scale: &[f32], shift: &[f32]) -> Vec<f32> {
        let row = &self.values[f * GROUP_DIMS..(f + 1) * GROUP_DIMS];
        (0..GROUP_DIMS)
            .map(|i| {
                if i / DIMS < n {
                    (row[i] - shift[i]) / scale[i]
                } else {
                    0.0
                }
            })
            .collect()
    }

    /// The cues of the window starting at frame `start`, on its frames `from..window` (the
    /// ones it makes), for slots `perm` (`perm[slot] = dancer`) and window origin `origin`
    /// (normalised root x/y).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn window_cue(
        &self,
        start: usize,
        window: usize,
        from: usize,
        perm: &[usize],
        origin: [f32; 2],
        scale: &[f32],
        shift: &[f32],
    ) -> KnownCue {
        let n = perm.len();
        let mut cue = KnownCue {
            values: vec![0.0; window * GROUP_DIMS],
            mask: vec![0.0; window * GROUP_DIMS],
            flags: vec![0.0; window * N_MAX],
        };
        for f in from..window {
            let g = start + f;
            if g >= self.frames() {
                break;
            }
            let norm = self.normalised(g, n, scale, shift);
            for (s, &d) in perm.iter().enumerate() {
                for c in 0..DIMS {
                    if !self.is_known(g, channel(d, c)) {
                        continue;
                    }
                    let mut v = norm[channel(d, c)];
                    if let Some(k) = ROOT_HORIZONTAL.iter().position(|&r| r == c) {
                        v -= origin[k];
                    }
                    let i = f * GROUP_DIMS + channel(s, c);
                    cue.values[i] = v;
                    cue.mask[i] = 1.0;
                }
                let whole = (0..DIMS).all(|c| self.is_known(g, channel(d, c)));
                if !whole && self.root_known(g, d) {
                    cue.flags[f * N_MAX + s] = 1.0;
                }
            }
        }
        cue
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cues_are_in_window_coordinates_and_flag_known_roots_of_made_frames() {
        let frames = 4;
        let mut values = vec![0f32; frames * GROUP_DIMS];
        let mut mask = vec![0f32; frames * GROUP_DIMS];
        // Dancer 1 wholly known at frame 2; dancer 0 only its root at frame 3.
        for c in 0..DIMS {
            values[2 * GROUP_DIMS + channel(1, c)] = 2.0;
            mask[2 * GROUP_DIMS + channel(1, c)] = 1.0;
        }
        for &c in &ROOT_HORIZONTAL {
            values[3 * GROUP_DIMS + channel(0, c)] = 4.0;
            mask[3 * GROUP_DIMS + channel(0, c)] = 1.0;
        }
        let k = GroupKnown {
            values: &values,
            mask: &mask,
        };
        assert!(!k.frame_known(2, 2) && k.root_known(3, 0) && !k.root_known(3, 1));
        let scale = vec![2.0; GROUP_DIMS];
        let shift = vec![0.0; GROUP_DIMS];
        // Slots swapped: slot 0 is dancer 1. Window from frame 1, cued from its frame 1.
        let cue = k.window_cue(1, 3, 1, &[1, 0], [0.5, -0.5], &scale, &shift);
        let at = |f: usize, s: usize, c: usize| f * GROUP_DIMS + channel(s, c);
        assert_eq!(cue.mask[at(1, 0, 20)], 1.0);
        assert_eq!(cue.values[at(1, 0, 20)], 1.0);
        assert_eq!(cue.values[at(1, 0, ROOT_HORIZONTAL[0])], 1.0 - 0.5);
        assert_eq!(cue.values[at(2, 1, ROOT_HORIZONTAL[1])], 2.0 + 0.5);
        assert_eq!(cue.mask[at(2, 1, 20)], 0.0);
        // Frame 3 (window frame 2): dancer 0 (slot 1) has a known root on a made frame.
        assert_eq!(cue.flags[2 * N_MAX + 1], 1.0);
        assert_eq!(
            cue.flags[N_MAX], 0.0,
            "a wholly known dancer is not flagged"
        );
        assert_eq!(
            cue.mask[at(0, 0, 20)],
            0.0,
            "frames before `from` are not cued"
        );
    }
}
