//! Camera, floor and figure rendering.

use dancegen_motion::skeleton::Skeleton;

use crate::math::{
    V3, add, capsule_normal, cross, dot, normalize, ray_capsule, scale, seg_dist_xz, smoothstep,
    sub,
};
use crate::{FrameStream, RenderError, RgbImage};

/// One dancer: world joint positions over time (Y-up).
#[derive(Debug, Clone)]
pub struct DancerTrack {
    /// `T × J × 3` positions, row-major.
    pub joints: Vec<f32>,
    /// Parent of every joint (`J` entries); all `None` draws spheres only.
    pub parents: Vec<Option<usize>>,
    /// Frame rate of `joints`.
    pub fps: f32,
}

impl DancerTrack {
    pub fn num_joints(&self) -> usize {
        self.parents.len()
    }

    pub fn frames(&self) -> usize {
        let j = self.num_joints();
        if j == 0 {
            0
        } else {
            self.joints.len() / (j * 3)
        }
    }

    fn joint(&self, f: usize, j: usize) -> V3 {
        let i = (f * self.num_joints() + j) * 3;
        [self.joints[i], self.joints[i + 1], self.joints[i + 2]]
    }

    /// Joint positions at time `t` seconds, linearly interpolated, held at the ends.
    fn pose_at(&self, t: f32) -> Vec<V3> {
        let n = self.frames();
        let x = (t * self.fps).max(0.0);
        let i0 = (x.floor() as usize).min(n - 1);
        let i1 = (i0 + 1).min(n - 1);
        let w = (x - i0 as f32).clamp(0.0, 1.0);
        (0..self.num_joints())
            .map(|j| {
                let a = self.joint(i0, j);
                let b = self.joint(i1, j);
                add(a, scale(sub(b, a), w))
            })
            .collect()
    }

    fn duration(&self) -> f32 {
        (self.frames().saturating_sub(1)) as f32 / self.fps
    }
}

/// Image size and quality.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RenderOptions {
    pub width: u32,
    pub height: u32,
    /// Supersampling factor per axis (1 = no anti-aliasing, 2 = 4 samples per pixel).
    pub supersample: u32,
    /// Soft blob shadows on the floor.
    pub shadows: bool,
}

impl RenderOptions {
    /// `width × height` with 2×2 supersampling and shadows.
    pub fn new(width: u32, height: u32) -> Self {
        RenderOptions {
            width,
            height,
            supersample: 2,
            shadows: true,
        }
    }
}

/// Dancer colours, in order (blue, orange, green, red, purple, teal, brown, pink).
pub const PALETTE: [[u8; 3]; 8] = [
    [52, 110, 235],
    [245, 130, 32],
    [40, 170, 75],
    [220, 45, 50],
    [150, 80, 200],
    [20, 170, 175],
    [150, 95, 55],
    [235, 90, 170],
];

struct Figure {
    track: DancerTrack,
    has_bones: bool,
    radius: f32,
    head: Option<usize>,
    colour: V3,
}

/// A clip ready to render: fixed camera, floor and per-dancer sizes.
pub struct Scene {
    figures: Vec<Figure>,
    opts: RenderOptions,
    cam: V3,
    fwd: V3,
    right: V3,
    up: V3,
    /// Focal length in supersampled pixels.
    focal: f32,
    floor_y: f32,
    /// Supersampled width and height.
    sw: usize,
    sh: usize,
    /// Background (sky + floor + grid) per supersampled pixel.
    background: Vec<V3>,
    /// Ray distance to the floor per supersampled pixel (infinite where the floor is not seen).
    floor_t: Vec<f32>,
    duration: f32,
}

const SKY_TOP: V3 = [0.60, 0.68, 0.78];
const SKY_BOTTOM: V3 = [0.88, 0.90, 0.93];
const FLOOR: V3 = [0.80, 0.80, 0.78];
const GRID: V3 = [0.50, 0.50, 0.50];

impl Scene {
    pub fn new(tracks: &[DancerTrack], opts: &RenderOptions) -> Result<Scene, RenderError> {
        if tracks.is_empty() {
            return Err(RenderError::Empty("no dancers".into()));
        }
        if opts.width < 8 || opts.height < 8 || opts.width > 8192 || opts.height > 8192 {
            return Err(RenderError::Invalid(format!(
                "image size {}x{} (use 8..8192)",
                opts.width, opts.height
            )));
        }
        let mut figures = Vec::new();
        for (k, t) in tracks.iter().enumerate() {
            let j = t.num_joints();
            if j == 0 || t.frames() == 0 || t.joints.len() != t.frames() * j * 3 {
                return Err(RenderError::Invalid(format!(
                    "dancer {k}: {} values do not hold whole frames of {j} joints",
                    t.joints.len()
                )));
            }
            if !(t.fps.is_finite() && t.fps > 0.0) {
                return Err(RenderError::Invalid(format!(
                    "dancer {k}: frame rate {}",
                    t.fps
                )));
            }
            if t.parents
                .iter()
                .enumerate()
                .any(|(i, p)| p.is_some_and(|p| p >= j || p == i))
            {
                return Err(RenderError::Invalid(format!(
                    "dancer {k}: bad parent index"
                )));
            }
            let mut track = t.clone();
            // Non-finite joints would poison the camera fit; pin them to the root.
            for f in 0..track.frames() {
                for jj in 0..j {
                    let p = track.joint(f, jj);
                    if !p.iter().all(|v| v.is_finite()) {
                        let i = (f * j + jj) * 3;
                        track.joints[i..i + 3].copy_from_slice(&[0.0; 3]);
                    }
                }
            }
            let size = figure_size(&track);
            let has_bones = track.parents.iter().any(|p| p.is_some());
            let head = if has_bones { head_joint(&track) } else { None };
            let c = PALETTE[k % PALETTE.len()];
            figures.push(Figure {
                track,
                has_bones,
                radius: 0.032 * size,
                head,
                colour: [
                    c[0] as f32 / 255.0,
                    c[1] as f32 / 255.0,
                    c[2] as f32 / 255.0,
                ],
            });
        }
        let size = figures
            .iter()
            .map(|f| f.radius / 0.032)
            .fold(0.0f32, f32::max)
            .max(1e-3);
        let max_r = figures.iter().map(|f| f.radius).fold(0.0f32, f32::max);

        // Bounding box over all (sampled) frames.
        let mut lo = [f32::INFINITY; 3];
        let mut hi = [f32::NEG_INFINITY; 3];
        let mut pts = Vec::new();
        for fig in &figures {
            let n = fig.track.frames();
            let step = n.div_ceil(600).max(1);
            for f in (0..n).step_by(step).chain(std::iter::once(n - 1)) {
                for jj in 0..fig.track.num_joints() {
                    let p = fig.track.joint(f, jj);
                    for a in 0..3 {
                        lo[a] = lo[a].min(p[a]);
                        hi[a] = hi[a].max(p[a]);
                    }
                    pts.push(p);
                }
            }
        }
        let floor_y = lo[1] - max_r;
        // Include the floor under the dancers in the fit.
        pts.push([lo[0], floor_y, lo[2]]);
        pts.push([hi[0], floor_y, hi[2]]);
        pts.push([lo[0], floor_y, hi[2]]);
        pts.push([hi[0], floor_y, lo[2]]);
        let target = scale(add([lo[0], floor_y, lo[2]], hi), 0.5);

        let (sw, sh) = (
            (opts.width * opts.supersample.clamp(1, 4)) as usize,
            (opts.height * opts.supersample.clamp(1, 4)) as usize,
        );
        let back = normalize([0.55, 0.32, 1.0]);
        let fwd = scale(back, -1.0);
        let right = normalize(cross(fwd, [0.0, 1.0, 0.0]));
        let up = cross(right, fwd);
        let ty = (20.0f32).to_radians().tan();
        let tx = ty * opts.width as f32 / opts.height as f32;
        let margin = 0.88;
        let pad = max_r * 2.4;
        let mut dist = size * 0.5;
        for p in &pts {
            let q = sub(*p, target);
            let x = dot(q, right).abs() + pad;
            let y = dot(q, up).abs() + pad;
            let need = (x / (tx * margin)).max(y / (ty * margin)) - dot(q, fwd);
            dist = dist.max(need);
        }
        let cam = add(target, scale(back, dist));
        let focal = (sh as f32 * 0.5) / ty;

        let mut scene = Scene {
            figures,
            opts: *opts,
            cam,
            fwd,
            right,
            up,
            focal,
            floor_y,
            sw,
            sh,
            background: Vec::new(),
            floor_t: Vec::new(),
            duration: 0.0,
        };
        scene.duration = scene
            .figures
            .iter()
            .map(|f| f.track.duration())
            .fold(0.0, f32::max);
        scene.build_background(lo, hi, size);
        Ok(scene)
    }

    /// Clip length in seconds (the longest dancer; shorter ones hold their last pose).
    pub fn duration(&self) -> f32 {
        self.duration
    }

    /// Number of frames at `fps` covering the clip.
    pub fn frame_count(&self, fps: f32) -> usize {
        (self.duration * fps + 1e-3).floor() as usize + 1
    }

    /// All frames at `fps`, rendered in parallel batches.
    pub fn stream(&self, fps: f32) -> FrameStream<'_> {
        let times = (0..self.frame_count(fps)).map(|k| k as f32 / fps).collect();
        self.stream_times(times)
    }

    /// The frames at the given times (seconds).
    pub fn stream_times(&self, times: Vec<f32>) -> FrameStream<'_> {
        FrameStream {
            scene: self,
            times,
            next: 0,
            batch: Vec::new().into_iter(),
        }
    }

    fn ray(&self, px: usize, py: usize) -> V3 {
        let x = px as f32 + 0.5 - self.sw as f32 * 0.5;
        let y = self.sh as f32 * 0.5 - (py as f32 + 0.5);
        normalize(add(
            scale(self.fwd, self.focal),
            add(scale(self.right, x), scale(self.up, y)),
        ))
    }

    /// Camera-space depth and supersampled pixel position of a world point.
    fn project(&self, p: V3) -> (f32, f32, f32) {
        let q = sub(p, self.cam);
        let z = dot(q, self.fwd);
        let x = dot(q, self.right);
        let y = dot(q, self.up);
        let s = self.focal / z.max(1e-6);
        (
            z,
            self.sw as f32 * 0.5 + x * s,
            self.sh as f32 * 0.5 - y * s,
        )
    }

    fn build_background(&mut self, lo: V3, hi: V3, size: f32) {
        let spacing = nice_spacing(size * 0.3);
        let line_w = size * 0.008;
        let ext = size * 1.2;
        let (x0, x1, z0, z1) = (lo[0] - ext, hi[0] + ext, lo[2] - ext, hi[2] + ext);
        let fade = size * 1.5;
        let n = self.sw * self.sh;
        let mut bg = vec![[0.0; 3]; n];
        let mut ft = vec![f32::INFINITY; n];
        for py in 0..self.sh {
            let v = py as f32 / (self.sh - 1).max(1) as f32;
            let sky = add(SKY_TOP, scale(sub(SKY_BOTTOM, SKY_TOP), v));
            for px in 0..self.sw {
                let i = py * self.sw + px;
                let d = self.ray(px, py);
                bg[i] = sky;
                if d[1] >= -1e-6 {
                    continue;
                }
                let t = (self.floor_y - self.cam[1]) / d[1];
                if t <= 0.0 {
                    continue;
                }
                let hit = add(self.cam, scale(d, t));
                let (x, z) = (hit[0], hit[2]);
                // Distance outside the floor rectangle fades the floor into the sky.
                let ox = (x0 - x).max(x - x1).max(0.0);
                let oz = (z0 - z).max(z - z1).max(0.0);
                let out = (ox * ox + oz * oz).sqrt();
                let alpha = 1.0 - smoothstep(0.0, fade, out);
                if alpha <= 0.0 {
                    continue;
                }
                ft[i] = t;
                // World size of one pixel on the floor.
                let foot = t / self.focal / (-d[1]).max(0.08);
                let mut line = 0.0f32;
                for c in [x, z] {
                    let u = c / spacing;
                    let dist = (u - u.round()).abs() * spacing;
                    let cov = ((line_w * 0.5 + foot * 0.5 - dist) / foot).clamp(0.0, 1.0)
                        * (line_w / foot).clamp(0.35, 1.0);
                    line = line.max(cov);
                }
                // Fade the grid out where lines get denser than a few pixels (no moire).
                line *= 1.0 - smoothstep(spacing * 0.08, spacing * 0.25, foot);
                let floor = add(FLOOR, scale(sub(GRID, FLOOR), line));
                bg[i] = add(sky, scale(sub(floor, sky), alpha));
            }
        }
        self.background = bg;
        self.floor_t = ft;
    }

    /// Renders the scene at time `t` seconds.
    pub fn render_at(&self, t: f32) -> RgbImage {
        let mut col = self.background.clone();
        let mut depth = self.floor_t.clone();
        let poses: Vec<Vec<V3>> = self.figures.iter().map(|f| f.track.pose_at(t)).collect();
        if self.opts.shadows {
            self.draw_shadows(&poses, &mut col);
        }
        let light = normalize([0.45, 0.85, 0.55]);
        for (fig, pose) in self.figures.iter().zip(&poses) {
            let r = fig.radius;
            for (j, p) in fig.track.parents.iter().enumerate() {
                if let Some(p) = *p {
                    self.draw_capsule(pose[p], pose[j], r, fig.colour, light, &mut col, &mut depth);
                }
                let rs = if Some(j) == fig.head {
                    r * 2.1
                } else if fig.has_bones {
                    r * 1.15
                } else {
                    r * 1.6
                };
                self.draw_capsule(
                    pose[j], pose[j], rs, fig.colour, light, &mut col, &mut depth,
                );
            }
        }
        self.downsample(&col)
    }

    #[allow(clippy::too_many_arguments)]
    fn draw_capsule(
        &self,
        a: V3,
        b: V3,
        r: f32,
        colour: V3,
        light: V3,
        col: &mut [V3],
        depth: &mut [f32],
    ) {
        let (za, xa, ya) = self.project(a);
        let (zb, xb, yb) = self.project(b);
        let zmin = za.min(zb) - r;
        if zmin <= 1e-4 {
            return;
        }
        let pr = r * self.focal / zmin + 2.0;
        let bx0 = (xa.min(xb) - pr).floor().max(0.0) as usize;
        let by0 = (ya.min(yb) - pr).floor().max(0.0) as usize;
        let bx1 = ((xa.max(xb) + pr).ceil().max(0.0) as usize).min(self.sw);
        let by1 = ((ya.max(yb) + pr).ceil().max(0.0) as usize).min(self.sh);
        for py in by0..by1 {
            for px in bx0..bx1 {
                let d = self.ray(px, py);
                let Some(t) = ray_capsule(self.cam, d, a, b, r) else {
                    continue;
                };
                let i = py * self.sw + px;
                if t >= depth[i] {
                    continue;
                }
                depth[i] = t;
                let hit = add(self.cam, scale(d, t));
                let n = capsule_normal(hit, a, b);
                let diff = dot(n, light).max(0.0);
                let hemi = 0.5 + 0.5 * n[1];
                // A little rim light against the view direction separates overlapping limbs.
                let rim = (1.0 + dot(n, d)).clamp(0.0, 1.0).powi(3) * 0.15;
                let k = 0.22 + 0.2 * hemi + 0.62 * diff;
                col[i] = [
                    (colour[0] * k + rim).min(1.0),
                    (colour[1] * k + rim).min(1.0),
                    (colour[2] * k + rim).min(1.0),
                ];
            }
        }
    }

    fn draw_shadows(&self, poses: &[Vec<V3>], col: &mut [V3]) {
        // Shadow primitives: (xz segment, radius, softness).
        let mut prims: Vec<([f32; 2], [f32; 2], f32, f32)> = Vec::new();
        for (fig, pose) in self.figures.iter().zip(poses) {
            let r = fig.radius;
            for (j, p) in fig.track.parents.iter().enumerate() {
                let (a, b, rr) = match *p {
                    Some(p) => (pose[p], pose[j], r * 1.3),
                    None => (pose[j], pose[j], r * 1.8),
                };
                let h = ((a[1] + b[1]) * 0.5 - self.floor_y).max(0.0);
                prims.push(([a[0], a[2]], [b[0], b[2]], rr, rr + h * 0.25));
            }
        }
        let mut lo = [f32::INFINITY; 2];
        let mut hi = [f32::NEG_INFINITY; 2];
        for (a, b, _, soft) in &prims {
            for p in [a, b] {
                for k in 0..2 {
                    lo[k] = lo[k].min(p[k] - soft * 1.5);
                    hi[k] = hi[k].max(p[k] + soft * 1.5);
                }
            }
        }
        if !(lo[0].is_finite() && hi[0].is_finite()) {
            return;
        }
        let (mut bx0, mut by0, mut bx1, mut by1) = (
            f32::INFINITY,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NEG_INFINITY,
        );
        for (x, z) in [
            (lo[0], lo[1]),
            (lo[0], hi[1]),
            (hi[0], lo[1]),
            (hi[0], hi[1]),
        ] {
            let (zc, px, py) = self.project([x, self.floor_y, z]);
            if zc <= 1e-4 {
                // A corner behind the camera: shade the whole frame.
                (bx0, by0, bx1, by1) = (0.0, 0.0, self.sw as f32, self.sh as f32);
                break;
            }
            bx0 = bx0.min(px);
            by0 = by0.min(py);
            bx1 = bx1.max(px);
            by1 = by1.max(py);
        }
        let bx0 = bx0.floor().max(0.0) as usize;
        let by0 = by0.floor().max(0.0) as usize;
        let bx1 = (bx1.ceil().max(0.0) as usize).min(self.sw);
        let by1 = (by1.ceil().max(0.0) as usize).min(self.sh);
        for py in by0..by1 {
            for px in bx0..bx1 {
                let i = py * self.sw + px;
                let t = self.floor_t[i];
                if !t.is_finite() {
                    continue;
                }
                let hit = add(self.cam, scale(self.ray(px, py), t));
                let q = [hit[0], hit[2]];
                if q[0] < lo[0] || q[0] > hi[0] || q[1] < lo[1] || q[1] > hi[1] {
                    continue;
                }
                let mut occ = 0.0f32;
                for (a, b, rr, soft) in &prims {
                    let (dist, _) = seg_dist_xz(q, *a, *b);
                    if dist < soft * 1.5 {
                        let s = 1.0 - smoothstep(rr * 0.3, soft * 1.5, dist);
                        occ = occ.max(s * (rr / soft).sqrt());
                    }
                }
                if occ > 0.0 {
                    col[i] = scale(col[i], 1.0 - 0.45 * occ);
                }
            }
        }
    }

    fn downsample(&self, col: &[V3]) -> RgbImage {
        let ss = self.opts.supersample.clamp(1, 4) as usize;
        let (w, h) = (self.opts.width as usize, self.opts.height as usize);
        let mut data = vec![0u8; w * h * 3];
        let norm = 1.0 / (ss * ss) as f32;
        for y in 0..h {
            for x in 0..w {
                let mut acc = [0.0f32; 3];
                for dy in 0..ss {
                    let row = (y * ss + dy) * self.sw + x * ss;
                    for c in &col[row..row + ss] {
                        acc = add(acc, *c);
                    }
                }
                let o = (y * w + x) * 3;
                for k in 0..3 {
                    data[o + k] = (acc[k] * norm * 255.0 + 0.5).clamp(0.0, 255.0) as u8;
                }
            }
        }
        RgbImage {
            width: self.opts.width,
            height: self.opts.height,
            data,
        }
    }
}

/// 1, 2 or 5 times a power of ten, close to `x`.
fn nice_spacing(x: f32) -> f32 {
    let p = 10f32.powf(x.log10().floor());
    let m = x / p;
    let k = if m < 1.5 {
        1.0
    } else if m < 3.5 {
        2.0
    } else if m < 7.5 {
        5.0
    } else {
        10.0
    };
    k * p
}

/// Typical figure size: median over frames of the largest axis extent of the pose.
fn figure_size(t: &DancerTrack) -> f32 {
    let n = t.frames();
    let step = n.div_ceil(200).max(1);
    let mut ext: Vec<f32> = (0..n)
        .step_by(step)
        .map(|f| {
            let mut lo = [f32::INFINITY; 3];
            let mut hi = [f32::NEG_INFINITY; 3];
            for j in 0..t.num_joints() {
                let p = t.joint(f, j);
                for a in 0..3 {
                    lo[a] = lo[a].min(p[a]);
                    hi[a] = hi[a].max(p[a]);
                }
            }
            (0..3).map(|a| hi[a] - lo[a]).fold(0.0, f32::max)
        })
        .collect();
    ext.sort_by(f32::total_cmp);
    let m = ext[ext.len() / 2];
    if m > 0.0 { m } else { 1.0 }
}

/// The head: joint 15 of SMPL 24, else the leaf that is highest above the skeleton's mean.
fn head_joint(t: &DancerTrack) -> Option<usize> {
    let smpl = Skeleton::smpl24();
    if t.parents == smpl.parents() {
        return smpl.index_of("head").or(Some(15));
    }
    let j = t.num_joints();
    let mut leaf = vec![true; j];
    for p in t.parents.iter().flatten() {
        leaf[*p] = false;
    }
    let n = t.frames();
    let step = n.div_ceil(100).max(1);
    let mut score = vec![0.0f32; j];
    for f in (0..n).step_by(step) {
        let mean = (0..j).map(|k| t.joint(f, k)[1]).sum::<f32>() / j as f32;
        for (k, s) in score.iter_mut().enumerate() {
            *s += t.joint(f, k)[1] - mean;
        }
    }
    (0..j)
        .filter(|&k| leaf[k] && t.parents[k].is_some())
        .max_by(|&a, &b| score[a].total_cmp(&score[b]))
}
