//! Beat warp: a monotone piecewise-linear time map from motion time to music time whose anchors
//! put kinematic beats on music beats, and the resampling of a motion through it. The data set
//! builder pseudo-pairs real motion with songs by it ([`match_beats`]); the generation library
//! moves a generated dance's beats onto its song's, keeping its length ([`match_beats_in_span`]).
//!
//! The map is found by a dynamic program over (motion beat, music beat) pairs: a chain of pairs
//! `(a_i1, b_j1), (a_i2, b_j2), ...` with strictly increasing indices on both sides, every
//! segment's rate `Δmusic / Δmotion` inside `[min_rate, max_rate]`, maximising the number of
//! pairs (ties: the smallest total `|ln rate|`, i.e. the least tempo distortion). The first pair
//! may be anywhere in the song, which is the music start offset. Between anchors the map is
//! linear; before the first and after the last anchor it continues with the neighbouring
//! segment's rate.

use dancegen_motion::Quat;
use dancegen_motion::repr::motion::{POSE_DIMS, SMPL_JOINTS, SmplMotion};

/// Largest local tempo change of the warped motion: its playback speed stays within ±15 %
/// (`Δmotion / Δmusic ∈ [0.85, 1.15]`).
pub const MAX_TEMPO_CHANGE: f64 = 0.15;

/// How far back (in motion beats) the program looks for a predecessor anchor: skipping more
/// than this many kinematic beats in a row is never needed for a dense matching and bounds the
/// cost to `O(N · M · MAX_SKIP · w)` (`w` = music beats inside the rate window).
pub const MAX_SKIP: usize = 16;

/// Limits of the warp.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WarpParams {
    /// Smallest segment rate `Δmusic / Δmotion`.
    pub min_rate: f64,
    /// Largest segment rate.
    pub max_rate: f64,
    /// See [`MAX_SKIP`].
    pub max_skip: usize,
}

impl Default for WarpParams {
    /// Playback speed within `1 ± MAX_TEMPO_CHANGE`: rate in `[1/1.15, 1/0.85]`.
    fn default() -> Self {
        WarpParams {
            min_rate: 1.0 / (1.0 + MAX_TEMPO_CHANGE),
            max_rate: 1.0 / (1.0 - MAX_TEMPO_CHANGE),
            max_skip: MAX_SKIP,
        }
    }
}

/// A monotone piecewise-linear map `music_time = f(motion_time)` (seconds).
#[derive(Clone, Debug, PartialEq)]
pub struct TimeMap {
    /// `(motion time, music time)` anchors, strictly increasing in both coordinates.
    pub anchors: Vec<(f64, f64)>,
    /// Rate used before the first anchor (the first segment's rate; 1 with fewer than 2 anchors).
    pub rate_before: f64,
    /// Rate used after the last anchor.
    pub rate_after: f64,
    /// Music time of motion time 0 when there is no anchor at all.
    pub offset: f64,
}

impl TimeMap {
    /// The identity shifted by `offset` (no beats to match).
    pub fn shift(offset: f64) -> Self {
        TimeMap {
            anchors: Vec::new(),
            rate_before: 1.0,
            rate_after: 1.0,
            offset,
        }
    }

    /// Builds the map through `anchors` (strictly increasing in both coordinates).
    pub fn through(anchors: Vec<(f64, f64)>) -> Self {
        let rate = |k: usize| {
            let (a0, b0) = anchors[k];
            let (a1, b1) = anchors[k + 1];
            (b1 - b0) / (a1 - a0)
        };
        let (rate_before, rate_after) = if anchors.len() >= 2 {
            (rate(0), rate(anchors.len() - 2))
        } else {
            (1.0, 1.0)
        };
        let offset = anchors.first().map_or(0.0, |&(a, b)| b - rate_before * a);
        TimeMap {
            anchors,
            rate_before,
            rate_after,
            offset,
        }
    }

    /// Music time of motion time `t`.
    pub fn forward(&self, t: f64) -> f64 {
        interp(
            &self.anchors,
            t,
            self.rate_before,
            self.rate_after,
            self.offset,
            false,
        )
    }

    /// Motion time of music time `u` (the map is strictly increasing, so this is exact).
    pub fn inverse(&self, u: f64) -> f64 {
        interp(
            &self.anchors,
            u,
            1.0 / self.rate_before,
            1.0 / self.rate_after,
            -self.offset,
            true,
        )
    }

    /// `next` after `self`: the map `t ↦ next.forward(self.forward(t))`, exact everywhere.
    /// Its knots are `self`'s anchors and the motion times `next`'s anchors come from, plus one
    /// point beyond each end, so the extensions have the composed rates too.
    pub fn then(&self, next: &TimeMap) -> TimeMap {
        let mut knots: Vec<f64> = self.anchors.iter().map(|&(t, _)| t).collect();
        knots.extend(next.anchors.iter().map(|&(u, _)| self.inverse(u)));
        knots.sort_by(f64::total_cmp);
        knots.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
        let (Some(&first), Some(&last)) = (knots.first(), knots.last()) else {
            // Neither map has an anchor: both are shifts.
            return TimeMap::shift(next.forward(self.forward(0.0)));
        };
        let mut ts = vec![first - 1.0];
        ts.extend(knots);
        ts.push(last + 1.0);
        TimeMap::through(
            ts.into_iter()
                .map(|t| (t, next.forward(self.forward(t))))
                .collect(),
        )
    }

    /// Whether every piece's rate lies within `p`'s limits (up to rounding).
    pub fn within(&self, p: &WarpParams) -> bool {
        self.rates()
            .iter()
            .all(|&r| r >= p.min_rate * (1.0 - 1e-9) && r <= p.max_rate * (1.0 + 1e-9))
    }

    /// Rate of every piece, including the two extensions: `[before, segments..., after]`.
    pub fn rates(&self) -> Vec<f64> {
        let mut r = vec![self.rate_before];
        r.extend(
            self.anchors
                .windows(2)
                .map(|w| (w[1].1 - w[0].1) / (w[1].0 - w[0].0)),
        );
        r.push(self.rate_after);
        r
    }
}

/// Piecewise-linear interpolation through `(x, y)` knots (or `(y, x)` when `swap`), extended
/// linearly with the given slopes; with no knot, `y = x + offset`.
fn interp(knots: &[(f64, f64)], x: f64, before: f64, after: f64, offset: f64, swap: bool) -> f64 {
    let k = |i: usize| {
        let (a, b) = knots[i];
        if swap { (b, a) } else { (a, b) }
    };
    let n = knots.len();
    if n == 0 {
        return x + offset;
    }
    let (x0, y0) = k(0);
    if x <= x0 {
        return y0 + (x - x0) * before;
    }
    let (xn, yn) = k(n - 1);
    if x >= xn {
        return yn + (x - xn) * after;
    }
    // First knot strictly after x (binary search; x0 < x < xn here).
    let (mut lo, mut hi) = (0usize, n - 1);
    while hi - lo > 1 {
        let mid = (lo + hi) / 2;
        if k(mid).0 <= x {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let (xa, ya) = k(hi - 1);
    let (xb, yb) = k(hi);
    ya + (x - xa) * (yb - ya) / (xb - xa)
}

/// The result of [`match_beats`].
#[derive(Clone, Debug, PartialEq)]
pub struct BeatMatch {
    /// Matched `(motion beat index, music beat index)` pairs, increasing on both sides.
    pub pairs: Vec<(usize, usize)>,
    /// The time map through the matched beats.
    pub map: TimeMap,
}

/// Finds the monotone matching of motion beats (seconds from the motion's start) to music beats
/// (seconds from the song's start) described in the module docs.
///
/// `motion_len` and `song_len` (seconds) constrain where the chain may start and end: the
/// extended map should put motion time 0 at music time ≥ 0 and the motion's end before the
/// song's end, assuming the extension rate could be anything in the allowed range. When no chain
/// satisfies that (the motion is longer than the song can hold), the constraint is dropped and
/// the caller trims what falls outside the song.
pub fn match_beats(
    motion_beats: &[f64],
    music_beats: &[f64],
    motion_len: f64,
    song_len: f64,
    p: &WarpParams,
) -> BeatMatch {
    let fits_start = |i: usize, j: usize| music_beats[j] - p.max_rate * motion_beats[i] >= 0.0;
    let fits_end = |i: usize, j: usize| {
        music_beats[j] + p.max_rate * (motion_len - motion_beats[i]) <= song_len
    };
    let strict = dp(motion_beats, music_beats, p, &fits_start, &fits_end);
    let pairs = match strict {
        Some(pairs) => pairs,
        None => dp(motion_beats, music_beats, p, &|_, _| true, &|_, _| true).unwrap_or_default(),
    };
    let anchors: Vec<(f64, f64)> = pairs
        .iter()
        .map(|&(i, j)| (motion_beats[i], music_beats[j]))
        .collect();
    let map = if anchors.is_empty() {
        TimeMap::shift(0.0)
    } else {
        TimeMap::through(anchors)
    };
    BeatMatch { pairs, map }
}

/// [`match_beats`] for a motion that already spans the music: the map keeps both ends fixed
/// (motion time 0 → music time 0, `len` → `len`) and moves as many motion beats onto music
/// beats as the rate limits allow, all times in seconds from the start of the span. Beats
/// outside `(0, len)` are ignored. Without any beat to match, or when no chain of matches
/// reaches the end inside the limits, it is the identity.
pub fn match_beats_in_span(
    motion_beats: &[f64],
    music_beats: &[f64],
    len: f64,
    p: &WarpParams,
) -> BeatMatch {
    let identity = BeatMatch {
        pairs: Vec::new(),
        map: TimeMap::shift(0.0),
    };
    if len.is_nan() || len <= 0.0 {
        return identity;
    }
    // The span's two ends as sentinel beats on both sides: a chain from (0, 0) to (len, len).
    let inner = |beats: &[f64]| -> Vec<f64> {
        let mut v = vec![0.0];
        v.extend(beats.iter().copied().filter(|&t| t > 0.0 && t < len));
        v.push(len);
        v
    };
    let (a, b) = (inner(motion_beats), inner(music_beats));
    let (n, m) = (a.len(), b.len());
    let Some(chain) = dp(&a, &b, p, &|i, j| i == 0 && j == 0, &|i, j| {
        i == n - 1 && j == m - 1
    }) else {
        return identity;
    };
    let anchors: Vec<(f64, f64)> = chain.iter().map(|&(i, j)| (a[i], b[j])).collect();
    // Pairs as indices into the caller's arrays (sentinels dropped).
    let index_of = |beats: &[f64], t: f64| beats.iter().position(|&x| x == t);
    let pairs = chain[1..chain.len() - 1]
        .iter()
        .filter_map(|&(i, j)| Some((index_of(motion_beats, a[i])?, index_of(music_beats, b[j])?)))
        .collect();
    BeatMatch {
        pairs,
        map: TimeMap::through(anchors),
    }
}

#[derive(Clone, Copy)]
struct Cell {
    count: u32,
    penalty: f64,
    prev: Option<(u32, u32)>,
    valid: bool,
}

fn better(count: u32, penalty: f64, than: &Cell) -> bool {
    !than.valid || count > than.count || (count == than.count && penalty < than.penalty - 1e-12)
}

/// The dynamic program; `None` when no pair satisfies both `start_ok` and `end_ok`.
fn dp(
    a: &[f64],
    b: &[f64],
    p: &WarpParams,
    start_ok: &dyn Fn(usize, usize) -> bool,
    end_ok: &dyn Fn(usize, usize) -> bool,
) -> Option<Vec<(usize, usize)>> {
    let (n, m) = (a.len(), b.len());
    if n == 0 || m == 0 {
        return None;
    }
    let empty = Cell {
        count: 0,
        penalty: 0.0,
        prev: None,
        valid: false,
    };
    let mut cells = vec![empty; n * m];
    for i in 0..n {
        for j in 0..m {
            let mut best = if start_ok(i, j) {
                Cell {
                    count: 1,
                    penalty: 0.0,
                    prev: None,
                    valid: true,
                }
            } else {
                empty
            };
            for ip in i.saturating_sub(p.max_skip)..i {
                let dt = a[i] - a[ip];
                if dt <= 0.0 {
                    continue;
                }
                // Predecessor music beats with b[j] - b[jp] in [min_rate, max_rate] * dt.
                let lo = b.partition_point(|&x| x < b[j] - p.max_rate * dt - 1e-9);
                let hi = b.partition_point(|&x| x <= b[j] - p.min_rate * dt + 1e-9);
                for jp in lo..hi.min(j) {
                    let c = &cells[ip * m + jp];
                    if !c.valid {
                        continue;
                    }
                    let rate = (b[j] - b[jp]) / dt;
                    let count = c.count + 1;
                    let penalty = c.penalty + rate.ln().abs();
                    if better(count, penalty, &best) {
                        best = Cell {
                            count,
                            penalty,
                            prev: Some((ip as u32, jp as u32)),
                            valid: true,
                        };
                    }
                }
            }
            cells[i * m + j] = best;
        }
    }
    let mut end: Option<(usize, usize)> = None;
    for i in 0..n {
        for j in 0..m {
            let c = &cells[i * m + j];
            if !c.valid || !end_ok(i, j) {
                continue;
            }
            if end.is_none_or(|(ei, ej)| better(c.count, c.penalty, &cells[ei * m + ej])) {
                end = Some((i, j));
            }
        }
    }
    let mut pairs = Vec::new();
    let mut cur = end;
    while let Some((i, j)) = cur {
        pairs.push((i, j));
        cur = cells[i * m + j].prev.map(|(a, b)| (a as usize, b as usize));
    }
    pairs.reverse();
    end.map(|_| pairs)
}

/// The warped motion: frame `k` is at music time `(start_frame + k) / fps`; its pose is the
/// source motion at motion time `map.inverse(music time)`, joint rotations slerped (shortest
/// arc), root position interpolated linearly. Frames whose source time falls outside the
/// motion, or whose music time falls outside `[0, song_frames)`, are not produced.
///
/// Returns `(start_frame, motion)`; the motion has the source's frame rate `fps`.
pub fn warp_motion(m: &SmplMotion, map: &TimeMap, song_frames: usize) -> (usize, SmplMotion) {
    let fps = m.fps as f64;
    let t = m.frames();
    let empty = |s| {
        (
            s,
            SmplMotion {
                fps: m.fps,
                poses: Vec::new(),
                trans: Vec::new(),
            },
        )
    };
    if t == 0 || song_frames == 0 {
        return empty(0);
    }
    let end_time = (t - 1) as f64 / fps;
    let first = (map.forward(0.0) * fps - 1e-6).ceil().max(0.0) as usize;
    let last_f = (map.forward(end_time) * fps + 1e-6).floor();
    if last_f < first as f64 {
        return empty(first);
    }
    let last = (last_f as usize).min(song_frames - 1);
    if last < first {
        return empty(first);
    }
    let n = last - first + 1;
    let mut poses = Vec::with_capacity(n * POSE_DIMS);
    let mut trans = Vec::with_capacity(n * 3);
    for k in 0..n {
        let u = (first + k) as f64 / fps;
        let src = (map.inverse(u) * fps).clamp(0.0, (t - 1) as f64);
        let i0 = (src.floor() as usize).min(t - 1);
        let w = src - i0 as f64;
        if w < 1e-9 || i0 + 1 >= t {
            poses.extend_from_slice(&m.poses[i0 * POSE_DIMS..(i0 + 1) * POSE_DIMS]);
            trans.extend_from_slice(&m.trans[i0 * 3..(i0 + 1) * 3]);
            continue;
        }
        for j in 0..SMPL_JOINTS {
            let q0 = Quat::from_axis_angle(m.joint_aa(i0, j).map(f64::from));
            let q1 = Quat::from_axis_angle(m.joint_aa(i0 + 1, j).map(f64::from));
            poses.extend(Quat::slerp(q0, q1, w).to_axis_angle().map(|v| v as f32));
        }
        for c in 0..3 {
            let p0 = f64::from(m.trans[i0 * 3 + c]);
            let p1 = f64::from(m.trans[(i0 + 1) * 3 + c]);
            trans.push((p0 + (p1 - p0) * w) as f32);
        }
    }
    (
        first,
        SmplMotion {
            fps: m.fps,
            poses,
            trans,
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(start: f64, step: f64, n: usize) -> Vec<f64> {
        (0..n).map(|k| start + step * k as f64).collect()
    }

    fn check_rates(bm: &BeatMatch, p: &WarpParams) {
        for r in bm.map.rates() {
            assert!(
                r >= p.min_rate - 1e-9 && r <= p.max_rate + 1e-9,
                "rate {r} outside [{}, {}]",
                p.min_rate,
                p.max_rate
            );
        }
    }

    /// Brute force over all monotone subsets (small inputs): the largest admissible chain.
    fn brute_force(a: &[f64], b: &[f64], p: &WarpParams) -> usize {
        fn rec(a: &[f64], b: &[f64], p: &WarpParams, last: Option<(usize, usize)>) -> usize {
            let mut best = 0;
            let (i0, j0) = last.map_or((0, 0), |(i, j)| (i + 1, j + 1));
            for i in i0..a.len() {
                for j in j0..b.len() {
                    if let Some((li, lj)) = last {
                        let r = (b[j] - b[lj]) / (a[i] - a[li]);
                        if r < p.min_rate - 1e-9 || r > p.max_rate + 1e-9 || i - li > p.max_skip {
                            continue;
                        }
                    }
                    best = best.max(1 + rec(a, b, p, Some((i, j))));
                }
            }
            best
        }
        rec(a, b, p, None)
    }

    #[test]
    fn same_tempo_matches_every_beat_with_the_offset() {
        // Motion beats every 0.5 s; music beats every 0.5 s starting at 10 s.
        let a = grid(0.3, 0.5, 20);
        let b = grid(10.0, 0.5, 80);
        let p = WarpParams::default();
        let bm = match_beats(&a, &b, 10.0, 50.0, &p);
        assert_eq!(bm.pairs.len(), 20);
        check_rates(&bm, &p);
        for r in bm.map.rates() {
            assert!((r - 1.0).abs() < 1e-9, "no distortion needed, got rate {r}");
        }
        // The offset puts motion time 0 somewhere in the song, before the first matched beat.
        let start = bm.map.forward(0.0);
        assert!(start >= 0.0);
        assert!((bm.map.forward(a[0]) - b[bm.pairs[0].1]).abs() < 1e-12);
    }

    #[test]
    fn ten_percent_slower_music_is_matched_at_rate_1_1() {
        let a = grid(0.0, 0.5, 16);
        let b = grid(2.0, 0.55, 60);
        let p = WarpParams::default();
        let bm = match_beats(&a, &b, 8.0, 40.0, &p);
        assert_eq!(bm.pairs.len(), 16);
        check_rates(&bm, &p);
        assert!(bm.map.rates().iter().all(|r| (r - 1.1).abs() < 1e-9));
    }

    #[test]
    fn tempo_out_of_range_is_not_forced() {
        // Music twice as slow: consecutive beats cannot match (rate 2), but the program may
        // skip every other motion beat (rate 1: 1.0 s of motion to 1.0 s of music).
        let a = grid(0.0, 0.5, 11);
        let b = grid(0.0, 1.0, 30);
        let p = WarpParams::default();
        let bm = match_beats(&a, &b, 5.0, 30.0, &p);
        check_rates(&bm, &p);
        assert_eq!(bm.pairs.len(), 6, "beats 0, 2, 4, ... of the motion");
        for w in bm.pairs.windows(2) {
            assert_eq!(w[1].0 - w[0].0, 2);
        }
    }

    #[test]
    fn matching_is_maximal_on_irregular_beats() {
        // Deterministic pseudo-random irregular beat lists, compared with exhaustive search.
        let mut s = 12345u64;
        let mut rnd = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 33) as f64 / (1u64 << 31) as f64
        };
        let p = WarpParams::default();
        for _ in 0..20 {
            let mut a = vec![0.2 + rnd()];
            for _ in 0..6 {
                let x = a.last().unwrap() + 0.3 + 0.5 * rnd();
                a.push(x);
            }
            // Music starts late enough that the song-start constraint never binds (the brute
            // force does not model it).
            let mut b = vec![10.0 + rnd()];
            for _ in 0..8 {
                let x = b.last().unwrap() + 0.3 + 0.5 * rnd();
                b.push(x);
            }
            let bm = match_beats(&a, &b, a[6] + 1.0, 1e3, &p);
            check_rates(&bm, &p);
            assert_eq!(bm.pairs.len(), brute_force(&a, &b, &p), "a={a:?} b={b:?}");
            for w in bm.pairs.windows(2) {
                assert!(w[1].0 > w[0].0 && w[1].1 > w[0].1);
            }
        }
    }

    #[test]
    fn start_and_end_stay_inside_the_song() {
        // The song's beats start at 0; a chain starting there would put motion time 0 before
        // the song's start, so the program starts later.
        let a = grid(2.0, 0.5, 10);
        let b = grid(0.0, 0.5, 40);
        let bm = match_beats(&a, &b, 7.0, 20.0, &WarpParams::default());
        assert!(bm.map.forward(0.0) >= -1e-9);
        assert!(bm.map.forward(7.0) <= 20.0 + 1e-9);
        assert_eq!(bm.pairs.len(), 10);
    }

    #[test]
    fn no_beats_gives_the_identity() {
        let bm = match_beats(&[], &[1.0, 2.0], 3.0, 10.0, &WarpParams::default());
        assert!(bm.pairs.is_empty());
        assert_eq!(bm.map.forward(1.5), 1.5);
    }

    /// A motion whose beats fall 0.1 s after a 0.5 s grid of music beats, spanning 10 s: the
    /// fixed-span map keeps both ends, puts the inner beats on the grid, and stays in the rate
    /// limits; no motion beats gives the identity.
    #[test]
    fn span_map_keeps_the_ends_and_moves_beats_onto_music() {
        let p = WarpParams::default();
        let music = grid(0.5, 0.5, 19);
        let motion: Vec<f64> = music.iter().map(|t| t + 0.1).collect();
        let bm = match_beats_in_span(&motion, &music, 10.0, &p);
        assert!((bm.map.forward(0.0)).abs() < 1e-12);
        assert!((bm.map.forward(10.0) - 10.0).abs() < 1e-9);
        assert!(bm.pairs.len() >= 17, "{} pairs", bm.pairs.len());
        for &(i, j) in &bm.pairs {
            assert!((bm.map.forward(motion[i]) - music[j]).abs() < 1e-9);
        }
        check_rates(&bm, &p);
        // Another tempo: whatever is matched, the ends and the rate limits hold.
        let other = grid(0.37, 0.37, 26);
        let bm = match_beats_in_span(&other, &music, 10.0, &p);
        check_rates(&bm, &p);
        assert!((bm.map.forward(10.0) - 10.0).abs() < 1e-9);
        let none = match_beats_in_span(&[], &music, 10.0, &p);
        assert!(none.pairs.is_empty());
        assert!((none.map.forward(3.0) - 3.0).abs() < 1e-12);
    }

    #[test]
    fn inverse_inverts_forward() {
        let map = TimeMap::through(vec![(1.0, 3.0), (2.0, 4.1), (3.0, 5.0)]);
        for t in [-1.0, 0.0, 0.5, 1.0, 1.7, 2.0, 2.9, 3.0, 4.5] {
            assert!((map.inverse(map.forward(t)) - t).abs() < 1e-12);
        }
        assert_eq!(map.rates().len(), 4);
        assert!((map.forward(0.0) - (3.0 - 1.1)).abs() < 1e-12);
    }

    #[test]
    fn warp_resamples_on_the_music_grid() {
        // A root moving at 1 m/s, played 10 % slower (rate 1.1) from music time 1 s.
        let fps = 30.0f32;
        let t = 61;
        let trans: Vec<f32> = (0..t).flat_map(|f| [f as f32 / fps, 0.9, 0.0]).collect();
        let m = SmplMotion::new(fps, vec![0.0; t * POSE_DIMS], trans).unwrap();
        let map = TimeMap::through(vec![(0.0, 1.0), (2.0, 3.2)]);
        let (start, w) = warp_motion(&m, &map, 1000);
        assert_eq!(start, 30);
        assert_eq!(w.frames(), 67); // music 1.0 s ..= 3.2 s at 30 fps
        for k in 0..w.frames() {
            let u = (start + k) as f64 / 30.0;
            let expect = (u - 1.0) / 1.1;
            assert!((f64::from(w.trans[k * 3]) - expect).abs() < 1e-5);
        }
        // The song's end cuts the warped motion.
        let (_, short) = warp_motion(&m, &map, 50);
        assert_eq!(short.frames(), 20);
    }

    /// Composition is exact: inside the anchors, on the extensions, and with a shift.
    #[test]
    fn then_composes_two_maps() {
        let a = TimeMap::through(vec![(0.0, 0.0), (1.0, 1.1), (3.0, 2.9), (4.0, 4.0)]);
        let b = TimeMap::through(vec![(0.0, 0.0), (2.0, 1.8), (4.0, 4.0)]);
        let c = a.then(&b);
        for k in -20..=60 {
            let t = f64::from(k) / 10.0;
            let want = b.forward(a.forward(t));
            assert!(
                (c.forward(t) - want).abs() < 1e-9,
                "t = {t}: {} vs {want}",
                c.forward(t)
            );
        }
        let shifted = TimeMap::shift(0.5).then(&TimeMap::shift(-0.2));
        assert!((shifted.forward(2.0) - 2.3).abs() < 1e-12);
        assert!(a.within(&WarpParams::default()));
        let fast = TimeMap::through(vec![(0.0, 0.0), (1.0, 1.5), (2.0, 2.0)]);
        assert!(!fast.within(&WarpParams::default()));
    }
}
