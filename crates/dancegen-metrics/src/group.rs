//! Group-dance metrics (anchors A.9): GMR, GMC, group MMC (ported from `aioz-ai/GCD`, commit
//! `b9524d82`) and TIF (own definition, no reference code exists).
//!
//! A scene is `N` dancers, each a flat `(T, 24, 3)` Y-up joint array (same `T` for all), passed
//! as `&[Vec<f64>]` / `&[&[f64]]`-like slices of dancers.
//!
//! - [`group_kinetic_features`] (→ GMR): `eval/features/group_kinetic.py::extract_group_kinetic_features`
//!   with `GroupKineticFeatures(frame_time = 1/30, up_vec = "y", sliding_window = 1)` and GCD's
//!   **fixed** acceleration (`eval/features/utils.py`). Per joint `[h, v, e]`, each
//!   `log(1 + 1.5·x)`, `x` summed over dancers and frames `i ∈ [1, T)` and divided by
//!   `(T − 1)` then by `N`. The reference casts the 72-vector to float32; we return float64
//!   (the golden test compares after the same cast).
//! - [`gmr`]: `eval/calculate_gmr_scores.py::calculate_frechet_feature_distance(real, generated)`:
//!   z-normalise both sets with the GT mean / population std (+1e−10), Fréchet distance
//!   ([`crate::fid`], eps 1e−6); also returns `Dist_k` = all-pairs diversity of the normalised
//!   generated set.
//! - [`per_frame_kinetic_features`], [`dtw_best_path`], [`gmc`]:
//!   `eval/calculate_gmc_scores.py::calculate_gmc_score_generated` with
//!   `eval/features/kinetic.py::extract_kinetic_features_per_frame` (`KineticFeatures(frame_time =
//!   1/30, sliding_window = 2)`, fixed acceleration, `log(1 + 1.5·x)`, shape `(T − 1, 72)`) and
//!   the DTW path of `dtaidistance` 2.5.1 (`dtw_ndim.warping_paths` on the raw `(T, 24, 3)`
//!   positions, pure-Python path: squared Euclidean cost over all 72 values, full window, no
//!   penalty/psi, then `sqrt` of the matrix; `dtw.best_path`: from the lower-right corner, argmin
//!   over `[diag, up, left]` with ties going to the first). GMC of a scene is the mean over
//!   dancer pairs `n1 < n2` of the mean dot product of matched per-frame features (pairs with an
//!   index ≥ T − 1 skipped). The values are raw dot products (~50–270 on the fixtures), **not**
//!   percentages: the papers' ~80 % normalisation is not in the code.
//! - [`group_mmc`]: GCD beat score ([`crate::bas::Variant::Gcd`]) per dancer, averaged over
//!   dancers (float32 mean, as `np.mean` of the float32 scores).
//! - [`tif`]: Trajectory Intersection Frequency, see its docs.

use crate::bas::{Variant, beat_align_score, clip_music_beats, try_motion_beats};
use crate::fid::{EPS_MINT, frechet_distance, normalize_by_gt};
use crate::{FRAME_LEN, FeatureError, NUM_JOINTS, diversity, frame_count};

/// GCD frame time (`1/30`, for both the group and the per-frame features).
pub const GCD_FRAME_TIME: f64 = 1.0 / 30.0;
/// `m = 1.5` in `log(1 + m·x)`.
pub const GCD_LOG_SCALE: f64 = 1.5;
/// `GroupKineticFeatures.sliding_window`.
pub const GROUP_SLIDING_WINDOW: usize = 1;
/// `KineticFeatures.sliding_window` of `extract_kinetic_features_per_frame` (GMC).
pub const PER_FRAME_SLIDING_WINDOW: usize = 2;

/// Checks that all dancers have the same whole number of frames (≥ `min`) and returns it.
fn scene_frames(dancers: &[&[f64]], min: usize, what: &'static str) -> Result<usize, FeatureError> {
    let mut frames = None;
    for d in dancers {
        let f = frame_count(d)?;
        match frames {
            None => frames = Some(f),
            Some(g) if g != f => {
                return Err(FeatureError::BadShape {
                    path: format!("{what}: dancers with different frame counts"),
                    shape: vec![g, f],
                });
            }
            _ => {}
        }
    }
    let frames = frames.unwrap_or(0);
    if frames < min {
        return Err(FeatureError::TooShort { what, min, frames });
    }
    Ok(frames)
}

#[inline]
fn p(joints: &[f64], t: usize, j: usize) -> [f64; 3] {
    let o = t * FRAME_LEN + j * 3;
    [joints[o], joints[o + 1], joints[o + 2]]
}

/// fairmotion/GCD `calc_average_velocity_{horizontal,vertical}` for frame `i`, joint `j`:
/// squared norms `(‖(v_x, v_z)‖², v_y²)` of the windowed mean velocity.
fn velocity_sq_hv(
    joints: &[f64],
    frames: usize,
    i: usize,
    j: usize,
    window: usize,
    dt: f64,
) -> (f64, f64) {
    let mut sum = [0.0; 3];
    let mut count = 0usize;
    for t in i.saturating_sub(window)..=i + window {
        if t == 0 || t >= frames {
            continue;
        }
        let (a, b) = (p(joints, t, j), p(joints, t - 1, j));
        for c in 0..3 {
            sum[c] += a[c] - b[c];
        }
        count += 1;
    }
    let d = count.max(1) as f64 * dt;
    let (hx, hz, vy) = (sum[0] / d, sum[2] / d, sum[1] / d);
    let h = (hx * hx + hz * hz).sqrt();
    let v = vy.abs();
    (h * h, v * v)
}

/// GCD's fixed `calc_average_acceleration` (norm of the windowed mean acceleration).
fn acceleration(joints: &[f64], frames: usize, i: usize, j: usize, window: usize, dt: f64) -> f64 {
    let mut acc = [0.0; 3];
    let mut count = 0usize;
    for t in i.saturating_sub(window)..=i + window {
        if t == 0 || t + 1 >= frames {
            continue;
        }
        let (next, cur, prev) = (p(joints, t + 1, j), p(joints, t, j), p(joints, t - 1, j));
        for c in 0..3 {
            let v2 = (next[c] - cur[c]) / dt;
            let v1 = (cur[c] - prev[c]) / dt;
            acc[c] += (v2 - v1) / dt;
        }
        count += 1;
    }
    let n = count.max(1) as f64;
    let m = [acc[0] / n, acc[1] / n, acc[2] / n];
    (m[0] * m[0] + m[1] * m[1] + m[2] * m[2]).sqrt()
}

fn log_scale(x: f64) -> f64 {
    (1.0 + GCD_LOG_SCALE * x).ln()
}

/// Group kinetic feature of a scene (GMR input), 72 values `[h, v, e]` per joint (module docs).
/// Needs `N ≥ 1` dancers and `T ≥ 2` frames.
pub fn group_kinetic_features(dancers: &[&[f64]]) -> Result<[f64; 72], FeatureError> {
    let frames = scene_frames(dancers, 2, "group kinetic features")?;
    if dancers.is_empty() {
        return Err(FeatureError::TooShort {
            what: "group kinetic features (dancers)",
            min: 1,
            frames: 0,
        });
    }
    let w = GROUP_SLIDING_WINDOW;
    let dt = GCD_FRAME_TIME;
    let n = dancers.len() as f64;
    let denom = frames as f64 - 1.0;
    let mut out = [0.0; 3 * NUM_JOINTS];
    for j in 0..NUM_JOINTS {
        let (mut eh, mut ev, mut ee) = (0.0, 0.0, 0.0);
        for d in dancers {
            for i in 1..frames {
                eh += velocity_sq_hv(d, frames, i, j, w, dt).0;
            }
        }
        for d in dancers {
            for i in 1..frames {
                ev += velocity_sq_hv(d, frames, i, j, w, dt).1;
            }
        }
        for d in dancers {
            for i in 1..frames {
                ee += acceleration(d, frames, i, j, w, dt);
            }
        }
        out[3 * j] = log_scale(eh / denom / n);
        out[3 * j + 1] = log_scale(ev / denom / n);
        out[3 * j + 2] = log_scale(ee / denom / n);
    }
    Ok(out)
}

/// GMR and `Dist_k`: `(FD(norm(gt), norm(generated)), diversity(norm(generated)))`, both sets
/// normalised with the GT statistics (GCD's `calculate_frechet_feature_distance(real, generated)`;
/// argument order matters). Inputs are [`group_kinetic_features`] vectors, one per scene. The
/// reference stacks float32 features; pass them cast through `f32` to reproduce it exactly.
pub fn gmr(gt: &[Vec<f64>], generated: &[Vec<f64>]) -> (f64, f64) {
    let (g, p) = normalize_by_gt(gt, generated);
    (frechet_distance(&g, &p, EPS_MINT), diversity(&p))
}

/// Per-frame kinetic features of one dancer (GMC input): `T − 1` rows (frames `1..T`) of 72
/// values `log(1 + 1.5·[h, v, e])` per joint, window 2, frame time 1/30, fixed acceleration.
pub fn per_frame_kinetic_features(joints: &[f64]) -> Result<Vec<[f64; 72]>, FeatureError> {
    let frames = scene_frames(&[joints], 2, "per-frame kinetic features")?;
    let (w, dt) = (PER_FRAME_SLIDING_WINDOW, GCD_FRAME_TIME);
    Ok((1..frames)
        .map(|i| {
            let mut row = [0.0; 72];
            for j in 0..NUM_JOINTS {
                let (h, v) = velocity_sq_hv(joints, frames, i, j, w, dt);
                row[3 * j] = log_scale(h);
                row[3 * j + 1] = log_scale(v);
                row[3 * j + 2] = log_scale(acceleration(joints, frames, i, j, w, dt));
            }
            row
        })
        .collect())
}

/// numpy's pairwise sum for a contiguous block of ≤ 128 values (8 accumulators).
fn numpy_sum_small(x: &[f64]) -> f64 {
    if x.len() < 8 {
        return x.iter().fold(0.0, |a, &b| a + b);
    }
    let mut r = [0.0; 8];
    r.copy_from_slice(&x[..8]);
    let mut i = 8;
    while i + 8 <= x.len() {
        for k in 0..8 {
            r[k] += x[i + k];
        }
        i += 8;
    }
    let mut s = ((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7]));
    for &v in &x[i..] {
        s += v;
    }
    s
}

/// `dtaidistance.dtw.best_path(dtw_ndim.warping_paths(a, b)[1])` for two flat `(T_a, 24, 3)` /
/// `(T_b, 24, 3)` joint arrays: the optimal warping path as `(frame_a, frame_b)` pairs from
/// `(0, 0)` to `(T_a − 1, T_b − 1)`.
pub fn dtw_best_path(a: &[f64], b: &[f64]) -> Result<Vec<(usize, usize)>, FeatureError> {
    let (r, c) = (frame_count(a)?, frame_count(b)?);
    if r == 0 || c == 0 {
        return Ok(Vec::new());
    }
    let w = c + 1;
    let mut m = vec![f64::INFINITY; (r + 1) * w];
    m[0] = 0.0;
    let mut diff = [0.0; FRAME_LEN];
    for i in 0..r {
        let fa = &a[i * FRAME_LEN..(i + 1) * FRAME_LEN];
        for j in 0..c {
            let fb = &b[j * FRAME_LEN..(j + 1) * FRAME_LEN];
            for k in 0..FRAME_LEN {
                let d = fa[k] - fb[k];
                diff[k] = d * d;
            }
            let d = numpy_sum_small(&diff);
            let prev = [m[i * w + j], m[i * w + j + 1], m[(i + 1) * w + j]];
            let best = if prev[0] < prev[1] && prev[0] < prev[2] {
                prev[0]
            } else if prev[1] < prev[2] {
                prev[1]
            } else {
                prev[2]
            };
            m[(i + 1) * w + j + 1] = d + best;
        }
    }
    for v in &mut m {
        *v = v.sqrt();
    }
    // best_path: start at the lower-right corner, argmin (first strict minimum) of
    // [diag, up, left]; the final step into row/column 0 is dropped.
    let (mut i, mut j) = (r, c);
    let mut path = vec![(i - 1, j - 1)];
    while i > 0 && j > 0 {
        let cand = [m[(i - 1) * w + j - 1], m[(i - 1) * w + j], m[i * w + j - 1]];
        let mut arg = 0;
        let mut vmin = f64::INFINITY;
        for (k, &v) in cand.iter().enumerate() {
            if v < vmin {
                arg = k;
                vmin = v;
            }
        }
        match arg {
            0 => {
                i -= 1;
                j -= 1;
            }
            1 => i -= 1,
            _ => j -= 1,
        }
        if i > 0 && j > 0 {
            path.push((i - 1, j - 1));
        }
    }
    path.reverse();
    Ok(path)
}

/// GMC of one dancer pair: `(mean dot product over matched frames, matched frame count)`.
/// `None` if no pair of the path has both indices `< T − 1` (the reference divides by zero).
pub fn gmc_pair(a: &[f64], b: &[f64]) -> Result<Option<(f64, usize)>, FeatureError> {
    let frames = scene_frames(&[a, b], 2, "GMC")?;
    let (fa, fb) = (
        per_frame_kinetic_features(a)?,
        per_frame_kinetic_features(b)?,
    );
    let path = dtw_best_path(a, b)?;
    let (mut val, mut pp) = (0.0, 0usize);
    for (t1, t2) in path {
        if t1 >= frames - 1 || t2 >= frames - 1 {
            continue;
        }
        val += fa[t1].iter().zip(&fb[t2]).map(|(x, y)| x * y).sum::<f64>();
        pp += 1;
    }
    Ok((pp > 0).then(|| (val / pp as f64, pp)))
}

/// GMC of a scene: mean of [`gmc_pair`] over dancer pairs `n1 < n2`. `None` with fewer than two
/// dancers or if a pair has no matched frames (the reference would divide by zero).
pub fn gmc(dancers: &[&[f64]]) -> Result<Option<f64>, FeatureError> {
    scene_frames(dancers, 2, "GMC")?;
    let (mut sum, mut cnt) = (0.0, 0usize);
    for n1 in 0..dancers.len() {
        for n2 in n1 + 1..dancers.len() {
            match gmc_pair(dancers[n1], dancers[n2])? {
                Some((v, _)) => sum += v,
                None => return Ok(None),
            }
            cnt += 1;
        }
    }
    Ok((cnt > 0).then(|| sum / cnt as f64))
}

/// Group MMC: GCD beat-align score ([`Variant::Gcd`], music beats cut to `T`) of each dancer,
/// averaged over dancers in float32. `music_beats` are frame indices at 30 fps. `None` if a
/// dancer's score is undefined (motion beats but no music beats) or there are no dancers.
pub fn group_mmc(dancers: &[&[f64]], music_beats: &[usize]) -> Result<Option<f64>, FeatureError> {
    let frames = scene_frames(dancers, 0, "group MMC")?;
    if dancers.is_empty() {
        return Ok(None);
    }
    let music = clip_music_beats(music_beats, frames, Variant::Gcd);
    let mut sum = 0.0f32;
    for d in dancers {
        let motion = try_motion_beats(d, Variant::Gcd)?;
        match beat_align_score(&music, &motion, Variant::Gcd) {
            Some(s) => sum += s as f32,
            None => return Ok(None),
        }
    }
    Ok(Some(f64::from(sum / dancers.len() as f32)))
}

/// Capsule radii (metres) for [`tif`]. Each SMPL bone (parent → child segment) is a capsule;
/// two dancers intersect in a frame if any capsule of one overlaps any capsule of the other,
/// i.e. the segment–segment distance is below the sum of the two radii.
///
/// TIF keeps its own bones and radii (one capsule per parent → child bone, coarser than the
/// self-penetration body of [`dancegen_motion::capsule_body::CAPSULES`]) so its values stay
/// what they were; the geometry ([`segment_distance_sq`]) is the shared one.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CapsuleRadii {
    /// Torso bones (pelvis–hips, spine chain, neck, collars): 0.10 m.
    pub torso: f64,
    /// Head bone (neck–head): 0.10 m.
    pub head: f64,
    /// Upper arms and forearms (shoulder–elbow, elbow–wrist): 0.05 m.
    pub arm: f64,
    /// Hands (wrist–hand): 0.04 m.
    pub hand: f64,
    /// Thighs and shins (hip–knee, knee–ankle): 0.07 m.
    pub leg: f64,
    /// Feet (ankle–foot): 0.04 m.
    pub foot: f64,
}

impl Default for CapsuleRadii {
    /// Rough adult SMPL limb half-thicknesses (our choice; the paper gives no numbers).
    fn default() -> Self {
        Self {
            torso: 0.10,
            head: 0.10,
            arm: 0.05,
            hand: 0.04,
            leg: 0.07,
            foot: 0.04,
        }
    }
}

/// SMPL-24 kinematic parents (`-1` for the root).
pub const SMPL_PARENTS: [i32; 24] = [
    -1, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 9, 9, 12, 13, 14, 16, 17, 18, 19, 20, 21,
];

/// Radius of the bone ending at SMPL joint `child` (1..24).
fn bone_radius(child: usize, r: &CapsuleRadii) -> f64 {
    match child {
        1..=3 | 6 | 9 | 12..=14 => r.torso,
        15 => r.head,
        16..=19 => r.arm,
        20..=23 => r.hand,
        4 | 5 => r.leg,
        7 | 8 => r.leg,
        10 | 11 => r.foot,
        _ => 0.0,
    }
}

/// Squared distance between two segments: the workspace's one capsule geometry, shared with
/// the self-penetration body ([`dancegen_motion::capsule_body`]).
pub use dancegen_motion::capsule_body::segment_distance_sq;

/// Whether dancers `a` and `b` intersect at frame `t` (any bone capsule pair overlaps).
pub fn bodies_intersect(a: &[f64], b: &[f64], t: usize, radii: &CapsuleRadii) -> bool {
    for (ca, &pa) in SMPL_PARENTS.iter().enumerate().skip(1) {
        let pa = pa as usize;
        let (a0, a1) = (p(a, t, pa), p(a, t, ca));
        let ra = bone_radius(ca, radii);
        for (cb, &pb) in SMPL_PARENTS.iter().enumerate().skip(1) {
            let pb = pb as usize;
            let rs = ra + bone_radius(cb, radii);
            if segment_distance_sq(a0, a1, p(b, t, pb), p(b, t, cb)) < rs * rs {
                return true;
            }
        }
    }
    false
}

/// Smallest surface gap (metres) between the capsule bodies of `a` and `b` at frame `t`:
/// segment distance minus the two radii over all bone pairs; negative where they intersect.
pub fn body_gap(a: &[f64], b: &[f64], t: usize, radii: &CapsuleRadii) -> f64 {
    let mut best = f64::INFINITY;
    for (ca, &pa) in SMPL_PARENTS.iter().enumerate().skip(1) {
        let (a0, a1) = (p(a, t, pa as usize), p(a, t, ca));
        let ra = bone_radius(ca, radii);
        for (cb, &pb) in SMPL_PARENTS.iter().enumerate().skip(1) {
            let d = segment_distance_sq(a0, a1, p(b, t, pb as usize), p(b, t, cb)).sqrt();
            best = best.min(d - ra - bone_radius(cb, radii));
        }
    }
    best
}

/// Per-frame flags: `true` where at least one pair of distinct dancers intersects.
pub fn intersection_frames(
    dancers: &[&[f64]],
    radii: &CapsuleRadii,
) -> Result<Vec<bool>, FeatureError> {
    let frames = scene_frames(dancers, 0, "TIF")?;
    Ok((0..frames)
        .map(|t| {
            (0..dancers.len()).any(|n1| {
                (n1 + 1..dancers.len())
                    .any(|n2| bodies_intersect(dancers[n1], dancers[n2], t, radii))
            })
        })
        .collect())
}

/// TIF (Trajectory Intersection Frequency), **our definition** (no reference code; the
/// AIOZ-GDance paper defines it as the frequency of frames in which dancers' bodies intersect):
/// the fraction of frames in which any two dancers' bodies intersect, each body being the 23
/// SMPL bones as capsules with [`CapsuleRadii`]. In `[0, 1]`; `None` for zero frames.
pub fn tif(dancers: &[&[f64]], radii: &CapsuleRadii) -> Result<Option<f64>, FeatureError> {
    let flags = intersection_frames(dancers, radii)?;
    if flags.is_empty() {
        return Ok(None);
    }
    let hits = flags.iter().filter(|&&f| f).count();
    Ok(Some(hits as f64 / flags.len() as f64))
}

/// Smallest horizontal distance (metres) between two dancers' roots (pelvis joint, x/z) over
/// all frames and pairs; `None` for fewer than two dancers or zero frames.
pub fn min_root_distance(dancers: &[&[f64]]) -> Result<Option<f64>, FeatureError> {
    let frames = scene_frames(dancers, 0, "min_distance")?;
    let mut best: Option<f64> = None;
    for t in 0..frames {
        for a in 0..dancers.len() {
            for b in a + 1..dancers.len() {
                let (pa, pb) = (p(dancers[a], t, 0), p(dancers[b], t, 0));
                let d = (pa[0] - pb[0]).hypot(pa[2] - pb[2]);
                best = Some(best.map_or(d, |x: f64| x.min(d)));
            }
        }
    }
    Ok(best)
}

/// Share of frames (in `[0, 1]`) with a **collision**: two dancers whose roots are closer than
/// `dancegen_refine::formation::MIN_SEPARATION_M` horizontally, or whose capsule bodies
/// intersect ([`bodies_intersect`], TIF's bodies). Group.md P10's collision-TIF; every pair
/// counts (generated dancers have no partners). `None` for zero frames.
pub fn collision_share(
    dancers: &[&[f64]],
    radii: &CapsuleRadii,
) -> Result<Option<f64>, FeatureError> {
    let frames = scene_frames(dancers, 0, "collision")?;
    if frames == 0 {
        return Ok(None);
    }
    let min = dancegen_refine::formation::MIN_SEPARATION_M;
    let hits = (0..frames)
        .filter(|&t| {
            (0..dancers.len()).any(|a| {
                (a + 1..dancers.len()).any(|b| {
                    let (pa, pb) = (p(dancers[a], t, 0), p(dancers[b], t, 0));
                    (pa[0] - pb[0]).hypot(pa[2] - pb[2]) < min
                        || bodies_intersect(dancers[a], dancers[b], t, radii)
                })
            })
        })
        .count();
    Ok(Some(hits as f64 / frames as f64))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A T-pose-ish standing skeleton at horizontal offset `(x, z)`.
    fn body(x: f64, z: f64) -> Vec<f64> {
        // Rough SMPL rest joint positions (metres, Y up).
        let rest: [[f64; 3]; 24] = [
            [0.0, 0.9, 0.0],
            [0.06, 0.82, 0.0],
            [-0.06, 0.82, 0.0],
            [0.0, 1.0, 0.0],
            [0.1, 0.45, 0.0],
            [-0.1, 0.45, 0.0],
            [0.0, 1.13, 0.0],
            [0.1, 0.07, 0.0],
            [-0.1, 0.07, 0.0],
            [0.0, 1.18, 0.0],
            [0.1, 0.0, 0.12],
            [-0.1, 0.0, 0.12],
            [0.0, 1.4, 0.0],
            [0.08, 1.32, 0.0],
            [-0.08, 1.32, 0.0],
            [0.0, 1.55, 0.0],
            [0.18, 1.36, 0.0],
            [-0.18, 1.36, 0.0],
            [0.45, 1.36, 0.0],
            [-0.45, 1.36, 0.0],
            [0.7, 1.36, 0.0],
            [-0.7, 1.36, 0.0],
            [0.78, 1.36, 0.0],
            [-0.78, 1.36, 0.0],
        ];
        rest.iter()
            .flat_map(|q| [q[0] + x, q[1], q[2] + z])
            .collect()
    }

    fn clip(frames: &[Vec<f64>]) -> Vec<f64> {
        frames.concat()
    }

    #[test]
    fn tif_far_apart_is_zero() {
        let a = clip(&vec![body(0.0, 0.0); 10]);
        let b = clip(&vec![body(5.0, 0.0); 10]);
        let r = CapsuleRadii::default();
        assert_eq!(tif(&[&a, &b], &r).unwrap(), Some(0.0));
        // Side by side with 0.3 m between fingertips: still no contact.
        let c = clip(&vec![body(1.86, 0.0); 10]);
        assert_eq!(tif(&[&a, &c], &r).unwrap(), Some(0.0));
    }

    #[test]
    fn tif_counts_overlapping_frames() {
        let r = CapsuleRadii::default();
        let a = clip(&vec![body(0.0, 0.0); 10]);
        let same = clip(&vec![body(0.05, 0.0); 10]);
        assert_eq!(tif(&[&a, &same], &r).unwrap(), Some(1.0));
        // Dancer b overlaps in frames 3..7 only (4 of 10), far otherwise.
        let b: Vec<Vec<f64>> = (0..10)
            .map(|t| {
                if (3..7).contains(&t) {
                    body(0.1, 0.1)
                } else {
                    body(0.0, 4.0)
                }
            })
            .collect();
        let b = clip(&b);
        let c = clip(&vec![body(-6.0, 0.0); 10]);
        let flags = intersection_frames(&[&a, &b, &c], &r).unwrap();
        assert_eq!(
            flags,
            (0..10).map(|t| (3..7).contains(&t)).collect::<Vec<_>>()
        );
        assert_eq!(tif(&[&a, &b, &c], &r).unwrap(), Some(0.4));
        // Single dancer: never intersects.
        assert_eq!(tif(&[&a], &r).unwrap(), Some(0.0));
    }

    #[test]
    fn segment_distance_cases() {
        let d = segment_distance_sq([0.0; 3], [1.0, 0.0, 0.0], [0.5, 1.0, 0.0], [0.5, 2.0, 0.0]);
        assert!((d - 1.0).abs() < 1e-12);
        let d = segment_distance_sq([0.0; 3], [1.0, 0.0, 0.0], [0.5, -1.0, 1.0], [0.5, 1.0, 1.0]);
        assert!((d - 1.0).abs() < 1e-12);
        let d = segment_distance_sq([0.0; 3], [0.0; 3], [3.0, 4.0, 0.0], [3.0, 4.0, 0.0]);
        assert!((d - 25.0).abs() < 1e-12);
    }

    #[test]
    fn dtw_identical_is_diagonal() {
        let a: Vec<f64> = (0..5).flat_map(|t| body(t as f64 * 0.1, 0.0)).collect();
        let path = dtw_best_path(&a, &a).unwrap();
        assert_eq!(path, (0..5).map(|t| (t, t)).collect::<Vec<_>>());
    }
}
