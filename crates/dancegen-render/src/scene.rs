//! Camera, floor and figure rendering.

use dancegen_motion::skeleton::Skeleton;

use crate::math::{
    RayCapsule, V3, add, capsule_normal, cross, dot, normalize, scale, smoothstep, sub,
};
#[cfg(test)]
use crate::math::{ray_capsule, seg_dist_xz};
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
    /// Unit view ray per supersampled pixel, exactly [`Scene::ray`]: the figure and shadow
    /// loops read it instead of normalising (a square root and a division) per pixel and
    /// primitive.
    rays: Vec<V3>,
    /// World (x, z) where each supersampled pixel's ray meets the floor (meaningful where
    /// `floor_t` is finite), computed as the shadow pass always did.
    floor_xz: Vec<[f32; 2]>,
    /// Per [`SHADOW_TILE`]² tile of the supersampled frame (row-major, tiles aligned to the
    /// frame's top-left corner): the floor (x, z) box its floor pixels see, `None` if none.
    tile_floor: Vec<Option<[[f32; 2]; 2]>>,
    /// The background downsampled to the output size: a frame starts from a copy of it and
    /// only the rectangle the dancers and their shadows can touch is rendered again.
    background_image: RgbImage,
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
            rays: Vec::new(),
            floor_xz: Vec::new(),
            tile_floor: Vec::new(),
            background_image: RgbImage {
                width: 0,
                height: 0,
                data: Vec::new(),
            },
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
        let mut rays = vec![[0.0; 3]; n];
        let mut fxz = vec![[0.0; 2]; n];
        for py in 0..self.sh {
            let v = py as f32 / (self.sh - 1).max(1) as f32;
            let sky = add(SKY_TOP, scale(sub(SKY_BOTTOM, SKY_TOP), v));
            for px in 0..self.sw {
                let i = py * self.sw + px;
                let d = self.ray(px, py);
                rays[i] = d;
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
                fxz[i] = [x, z];
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
        self.background_image = self.downsample(&bg);
        self.background = bg;
        self.floor_t = ft;
        self.rays = rays;
        self.floor_xz = fxz;
        self.tile_floor = self.tile_floor_boxes();
    }

    /// The floor box of every shadow tile (see `tile_floor`).
    fn tile_floor_boxes(&self) -> Vec<Option<[[f32; 2]; 2]>> {
        let (tw, th) = (self.sw.div_ceil(SHADOW_TILE), self.sh.div_ceil(SHADOW_TILE));
        let mut out = vec![None; tw * th];
        for py in 0..self.sh {
            for px in 0..self.sw {
                let i = py * self.sw + px;
                if !self.floor_t[i].is_finite() {
                    continue;
                }
                let q = self.floor_xz[i];
                let b = out[(py / SHADOW_TILE) * tw + px / SHADOW_TILE].get_or_insert([q, q]);
                for k in 0..2 {
                    b[0][k] = b[0][k].min(q[k]);
                    b[1][k] = b[1][k].max(q[k]);
                }
            }
        }
        out
    }

    /// Renders the scene at time `t` seconds.
    ///
    /// The frame is the precomputed downsampled background with only the rectangle that the
    /// figures and their shadows can touch rendered again (at the supersampled resolution,
    /// aligned to whole output pixels). Inside it the arithmetic is the same as drawing the
    /// whole frame, so the pixels are identical; the savings come from skipping work that
    /// cannot change a pixel:
    /// - the view rays and floor points come from per-pixel tables built with the background;
    /// - a primitive tests only the pixels of each box row that lie near its projected 2D
    ///   segment (a bound that over-covers the projected capsule, see [`StadiumSpan`]);
    /// - a shadow tile only visits the shadow primitives whose reach overlaps the tile's
    ///   floor area.
    pub fn render_at(&self, t: f32) -> RgbImage {
        let poses: Vec<Vec<V3>> = self.figures.iter().map(|f| f.track.pose_at(t)).collect();
        let mut prims = Vec::new();
        for (fig, pose) in self.figures.iter().zip(&poses) {
            let r = fig.radius;
            for (j, p) in fig.track.parents.iter().enumerate() {
                if let Some(p) = *p {
                    prims.extend(self.screen_prim(pose[p], pose[j], r, fig.colour));
                }
                let rs = if Some(j) == fig.head {
                    r * 2.1
                } else if fig.has_bones {
                    r * 1.15
                } else {
                    r * 1.6
                };
                prims.extend(self.screen_prim(pose[j], pose[j], rs, fig.colour));
            }
        }
        let shadow = if self.opts.shadows {
            self.shadow_setup(&poses)
        } else {
            None
        };
        // The dirty rectangle: union of every box that can be written, widened to whole
        // output pixels so the downsampling reads only rendered samples.
        let (mut x0, mut y0, mut x1, mut y1) = (self.sw, self.sh, 0, 0);
        let boxes = prims
            .iter()
            .map(|p| p.bbox)
            .chain(shadow.as_ref().map(|s| s.bbox));
        for [bx0, by0, bx1, by1] in boxes {
            if bx0 < bx1 && by0 < by1 {
                x0 = x0.min(bx0);
                y0 = y0.min(by0);
                x1 = x1.max(bx1);
                y1 = y1.max(by1);
            }
        }
        let mut img = self.background_image.clone();
        if x0 >= x1 || y0 >= y1 {
            return img;
        }
        let ss = self.ss();
        let rect = Rect {
            x0: x0 / ss * ss,
            y0: y0 / ss * ss,
            x1: x1.div_ceil(ss) * ss,
            y1: y1.div_ceil(ss) * ss,
        };
        let w = rect.x1 - rect.x0;
        let mut col = Vec::with_capacity(w * (rect.y1 - rect.y0));
        let mut depth = Vec::with_capacity(col.capacity());
        for y in rect.y0..rect.y1 {
            let row = y * self.sw;
            col.extend_from_slice(&self.background[row + rect.x0..row + rect.x1]);
            depth.extend_from_slice(&self.floor_t[row + rect.x0..row + rect.x1]);
        }
        if let Some(sh) = &shadow {
            self.draw_shadows_fast(sh, &rect, &mut col);
        }
        let mut owner = vec![NO_OWNER; col.len()];
        for (k, p) in prims.iter().enumerate() {
            self.cast_prim(k as u32, p, &rect, &mut depth, &mut owner);
        }
        self.shade_owned(&prims, &rect, &depth, &owner, &mut col);
        self.downsample_rect(&col, &rect, &mut img);
        img
    }

    fn ss(&self) -> usize {
        self.opts.supersample.clamp(1, 4) as usize
    }

    /// Screen-space data of one capsule (a sphere when `a == b`), or `None` when it reaches
    /// behind the camera (never drawn, as before).
    fn screen_prim(&self, a: V3, b: V3, r: f32, colour: V3) -> Option<ScreenPrim> {
        let (za, xa, ya) = self.project(a);
        let (zb, xb, yb) = self.project(b);
        let zmin = za.min(zb) - r;
        if zmin <= 1e-4 {
            return None;
        }
        let pr = r * self.focal / zmin + 2.0;
        let bx0 = (xa.min(xb) - pr).floor().max(0.0) as usize;
        let by0 = (ya.min(yb) - pr).floor().max(0.0) as usize;
        let bx1 = ((xa.max(xb) + pr).ceil().max(0.0) as usize).min(self.sw);
        let by1 = ((ya.max(yb) + pr).ceil().max(0.0) as usize).min(self.sh);
        // Off-axis, perspective stretches a sphere's image by up to sqrt(1 + tan²θ) beyond
        // r·focal/z, θ the angle between the axis and the sphere centre; the angle is largest
        // at an end of the segment.
        let (cx, cy) = (self.sw as f64 * 0.5, self.sh as f64 * 0.5);
        let off = |x: f32, y: f32| (x as f64 - cx).hypot(y as f64 - cy) / self.focal as f64;
        let tan = off(xa, ya).max(off(xb, yb));
        let reach = r as f64 * self.focal as f64 / zmin as f64 * (1.0 + tan * tan).sqrt();
        Some(ScreenPrim {
            a,
            b,
            colour,
            ray: RayCapsule::new(self.cam, a, b, r),
            bbox: [bx0, by0, bx1, by1],
            span: StadiumSpan::new(
                [xa as f64, ya as f64],
                [xb as f64, yb as f64],
                reach * SPAN_SLACK_REL + SPAN_SLACK_PX,
            ),
        })
    }

    /// [`Scene::draw_capsule`]'s depth test on the dirty rectangle, row by row over the part
    /// of the box that [`StadiumSpan`] leaves: where prim `k` is nearer than what the pixel
    /// holds, it takes the pixel (`owner`). Shading is left to [`Scene::shade_owned`], once per
    /// pixel, instead of once per primitive that was nearest when drawn: the drawing order is
    /// the same and the comparison the same strict `<`, so every pixel ends with the same
    /// primitive and distance as when each one was shaded on the spot.
    fn cast_prim(&self, k: u32, p: &ScreenPrim, rect: &Rect, depth: &mut [f32], owner: &mut [u32]) {
        let [bx0, by0, bx1, by1] = p.bbox;
        if bx0 >= bx1 || by0 >= by1 {
            // Off screen (left out of the dirty rectangle).
            return;
        }
        let w = rect.x1 - rect.x0;
        for py in by0..by1 {
            let Some((sx0, sx1)) = p.span.row(py as f64 + 0.5) else {
                continue;
            };
            let px0 = bx0.max(sx0);
            let px1 = bx1.min(sx1);
            if px0 >= px1 {
                continue;
            }
            let rays = &self.rays[py * self.sw + px0..py * self.sw + px1];
            let buf = (py - rect.y0) * w + px0 - rect.x0;
            let depth = &mut depth[buf..buf + rays.len()];
            let owner = &mut owner[buf..buf + rays.len()];
            for ((d, z), o) in rays.iter().zip(depth).zip(owner) {
                let Some(t) = p.ray.hit(*d) else {
                    continue;
                };
                if t < *z {
                    *z = t;
                    *o = k;
                }
            }
        }
    }

    /// Shades every pixel of the dirty rectangle that a primitive took in [`Scene::cast_prim`].
    fn shade_owned(
        &self,
        prims: &[ScreenPrim],
        rect: &Rect,
        depth: &[f32],
        owner: &[u32],
        col: &mut [V3],
    ) {
        let light = normalize([0.45, 0.85, 0.55]);
        let w = rect.x1 - rect.x0;
        for y in rect.y0..rect.y1 {
            let buf = (y - rect.y0) * w;
            let rays = &self.rays[y * self.sw + rect.x0..y * self.sw + rect.x1];
            for (x, d) in rays.iter().enumerate() {
                let k = owner[buf + x];
                if k == NO_OWNER {
                    continue;
                }
                let p = &prims[k as usize];
                col[buf + x] = shade(self.cam, *d, depth[buf + x], p.a, p.b, p.colour, light);
            }
        }
    }

    /// The shadow primitives of a frame and the supersampled box they can darken, exactly as
    /// the full-frame pass computes them (`None`: no finite shadow).
    fn shadow_setup(&self, poses: &[Vec<V3>]) -> Option<Shadows> {
        let mut prims: Vec<ShadowPrim> = Vec::new();
        for (fig, pose) in self.figures.iter().zip(poses) {
            let r = fig.radius;
            for (j, p) in fig.track.parents.iter().enumerate() {
                let (a, b, rr) = match *p {
                    Some(p) => (pose[p], pose[j], r * 1.3),
                    None => (pose[j], pose[j], r * 1.8),
                };
                let h = ((a[1] + b[1]) * 0.5 - self.floor_y).max(0.0);
                let soft = rr + h * 0.25;
                prims.push(ShadowPrim {
                    a: [a[0], a[2]],
                    b: [b[0], b[2]],
                    soft,
                    inner: rr * 0.3,
                    outer: soft * 1.5,
                    strength: (rr / soft).sqrt(),
                });
            }
        }
        let mut lo = [f32::INFINITY; 2];
        let mut hi = [f32::NEG_INFINITY; 2];
        for p in &prims {
            for q in [p.a, p.b] {
                for k in 0..2 {
                    lo[k] = lo[k].min(q[k] - p.soft * 1.5);
                    hi[k] = hi[k].max(q[k] + p.soft * 1.5);
                }
            }
        }
        if !(lo[0].is_finite() && hi[0].is_finite()) {
            return None;
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
        let bbox = [
            bx0.floor().max(0.0) as usize,
            by0.floor().max(0.0) as usize,
            (bx1.ceil().max(0.0) as usize).min(self.sw),
            (by1.ceil().max(0.0) as usize).min(self.sh),
        ];
        Some(Shadows {
            prims,
            lo,
            hi,
            bbox,
        })
    }

    /// The shadow pass over [`SHADOW_TILE`]-sized tiles of the shadow box: each tile keeps
    /// the primitives whose reach (`outer`, with a safety margin) overlaps the floor area its
    /// pixels see; the others would fail `dist < outer` at every pixel of the tile. The
    /// darkening is the maximum over primitives, so leaving out ones that add nothing does
    /// not change it.
    fn draw_shadows_fast(&self, sh: &Shadows, rect: &Rect, col: &mut [V3]) {
        let [bx0, by0, bx1, by1] = sh.bbox;
        let (lo, hi) = (sh.lo, sh.hi);
        let w = rect.x1 - rect.x0;
        let all: Vec<ShadowConsts> = sh.prims.iter().map(ShadowConsts::new).collect();
        let mut near: Vec<ShadowConsts> = Vec::with_capacity(all.len());
        let tiles_x = self.sw.div_ceil(SHADOW_TILE);
        for ty in by0 / SHADOW_TILE..by1.div_ceil(SHADOW_TILE) {
            let (py0, py1) = (
                (ty * SHADOW_TILE).max(by0),
                ((ty + 1) * SHADOW_TILE).min(by1),
            );
            for tx in bx0 / SHADOW_TILE..bx1.div_ceil(SHADOW_TILE) {
                let (px0, px1) = (
                    (tx * SHADOW_TILE).max(bx0),
                    ((tx + 1) * SHADOW_TILE).min(bx1),
                );
                let Some([tlo, thi]) = self.tile_floor[ty * tiles_x + tx] else {
                    continue;
                };
                near.clear();
                near.extend(all.iter().filter(|c| c.reaches(tlo, thi)));
                if near.is_empty() {
                    continue;
                }
                for py in py0..py1 {
                    for x0 in (px0..px1).step_by(LANES) {
                        // Up to LANES pixels of the row; the ones off the floor, outside the
                        // shadow's floor box or past the tile stay unmarked.
                        let mut q = PixelLanes::EMPTY;
                        let mut any = false;
                        for (k, px) in (x0..px1.min(x0 + LANES)).enumerate() {
                            let i = py * self.sw + px;
                            if !self.floor_t[i].is_finite() {
                                continue;
                            }
                            let p = self.floor_xz[i];
                            if p[0] < lo[0] || p[0] > hi[0] || p[1] < lo[1] || p[1] > hi[1] {
                                continue;
                            }
                            q.x[k] = p[0];
                            q.z[k] = p[1];
                            q.on[k] = true;
                            any = true;
                        }
                        if !any {
                            continue;
                        }
                        let occ = q.occlusion(&near);
                        for (k, px) in (x0..px1.min(x0 + LANES)).enumerate() {
                            if q.on[k] && occ[k] > 0.0 {
                                let c = &mut col[(py - rect.y0) * w + px - rect.x0];
                                *c = scale(*c, 1.0 - 0.45 * occ[k]);
                            }
                        }
                    }
                }
            }
        }
    }

    /// [`Scene::downsample`] of the dirty rectangle into `img` (the rest of `img` already is
    /// the downsampled background).
    fn downsample_rect(&self, col: &[V3], rect: &Rect, img: &mut RgbImage) {
        let ss = self.ss();
        let w = self.opts.width as usize;
        let bw = rect.x1 - rect.x0;
        let norm = 1.0 / (ss * ss) as f32;
        for y in rect.y0 / ss..rect.y1 / ss {
            for x in rect.x0 / ss..rect.x1 / ss {
                let mut acc = [0.0f32; 3];
                for dy in 0..ss {
                    let row = (y * ss + dy - rect.y0) * bw + x * ss - rect.x0;
                    for c in &col[row..row + ss] {
                        acc = add(acc, *c);
                    }
                }
                let o = (y * w + x) * 3;
                for (out, a) in img.data[o..o + 3].iter_mut().zip(acc) {
                    *out = (a * norm * 255.0 + 0.5).clamp(0.0, 255.0) as u8;
                }
            }
        }
    }

    /// The renderer as it was before [`Scene::render_at`] learned to draw only the changed
    /// rectangle: the whole supersampled frame, every pixel of every primitive's box, every
    /// shadow primitive per floor pixel. Kept for the tests, which require identical frames.
    #[cfg(test)]
    pub(crate) fn render_full_at(&self, t: f32) -> RgbImage {
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

    #[cfg(test)]
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
                col[i] = shade(self.cam, d, t, a, b, colour, light);
            }
        }
    }

    #[cfg(test)]
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

/// Lambert shading plus a sky/ground ambient term and a rim light, at the hit `cam + t d` of a
/// capsule `a`–`b`.
fn shade(cam: V3, d: V3, t: f32, a: V3, b: V3, colour: V3, light: V3) -> V3 {
    let hit = add(cam, scale(d, t));
    let n = capsule_normal(hit, a, b);
    let diff = dot(n, light).max(0.0);
    let hemi = 0.5 + 0.5 * n[1];
    // A little rim light against the view direction separates overlapping limbs.
    let rim = (1.0 + dot(n, d)).clamp(0.0, 1.0).powi(3) * 0.15;
    let k = 0.22 + 0.2 * hemi + 0.62 * diff;
    [
        (colour[0] * k + rim).min(1.0),
        (colour[1] * k + rim).min(1.0),
        (colour[2] * k + rim).min(1.0),
    ]
}

/// Side of the square tiles (supersampled pixels) over which shadow primitives are culled:
/// small enough that a tile sees only a few of a figure's bones, large enough that the cull
/// costs little next to the pixels.
const SHADOW_TILE: usize = 16;
/// Safety margin of the shadow cull, relative to a primitive's reach and absolute (world
/// units): the cull compares boxes in exact terms while the per-pixel distance is rounded,
/// so a primitive is only left out when it is clearly too far.
const SHADOW_CULL_REL: f32 = 1e-3;
const SHADOW_CULL_ABS: f32 = 1e-5;
/// Widening of a primitive's 2D reach (relative, then in supersampled pixels) so that the row
/// spans cover every pixel the exact ray test can hit, rounding of that f32 test included
/// (its error is well under 1 % of the radius).
const SPAN_SLACK_REL: f64 = 1.05;
const SPAN_SLACK_PX: f64 = 2.0;

/// A rectangle of supersampled pixels, `x0..x1` × `y0..y1`.
struct Rect {
    x0: usize,
    y0: usize,
    x1: usize,
    y1: usize,
}

/// [`Scene::cast_prim`]'s mark of a pixel that no primitive took (the floor or sky stays).
const NO_OWNER: u32 = u32::MAX;

/// One capsule of a frame, ready to draw.
struct ScreenPrim {
    a: V3,
    b: V3,
    colour: V3,
    /// The ray test from the camera (`ray_capsule`, or `ray_sphere` when `a == b`).
    ray: RayCapsule,
    /// `[x0, y0, x1, y1]`: the pixel box the full-frame renderer tests (it may be empty).
    bbox: [usize; 4],
    span: StadiumSpan,
}

/// The pixels near a projected segment: every point within `reach` of the 2D segment `a`–`b`
/// (a "stadium", convex, so each pixel row meets it in one interval).
///
/// A ray hits a capsule (radius r around segment AB, nearest depth `zmin` > 0) at a point
/// h = c + v with c on AB and |v| ≤ r. Perspective maps AB onto the 2D segment between the
/// projected ends, so P(c) lies on it, and |P(c + v) − P(c)| ≤ focal·r·sqrt(1 + |u|²)/z_h,
/// where u = (c_x/c_z, c_y/c_z) (the norm of v ↦ (v_x − u_x v_z, v_y − u_y v_z) is
/// sqrt(1 + |u|²)) and z_h ≥ zmin. So every hit pixel is within that reach of the 2D segment;
/// |u| is largest at one of the ends. The reach is widened by [`SPAN_SLACK_REL`] and
/// [`SPAN_SLACK_PX`] for rounding.
struct StadiumSpan {
    a: [f64; 2],
    b: [f64; 2],
    reach: f64,
}

impl StadiumSpan {
    fn new(a: [f64; 2], b: [f64; 2], reach: f64) -> Self {
        StadiumSpan { a, b, reach }
    }

    /// Pixel columns `x0..x1` whose centres lie within the reach on the row whose pixel
    /// centres are at height `y` (with one pixel to spare each side), or `None`.
    fn row(&self, y: f64) -> Option<(usize, usize)> {
        let (a, b, r) = (self.a, self.b, self.reach);
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        // The two end disks.
        for c in [a, b] {
            let dy = y - c[1];
            if dy.abs() <= r {
                let half = (r * r - dy * dy).max(0.0).sqrt();
                lo = lo.min(c[0] - half);
                hi = hi.max(c[0] + half);
            }
        }
        // The band between them: 0 ≤ (p − a)·D ≤ |D|² and |D × (p − a)| ≤ r |D|, each
        // linear in x on the row.
        let d = [b[0] - a[0], b[1] - a[1]];
        let dd = d[0] * d[0] + d[1] * d[1];
        if dd > 0.0 {
            let dy = y - a[1];
            // (x − a_x) D_x + dy D_y ∈ [0, dd]
            let along = linear_range(d[0], dy * d[1], 0.0, dd);
            // D_x dy − D_y (x − a_x) ∈ [−r|D|, r|D|]
            let rl = r * dd.sqrt();
            let across = linear_range(-d[1], d[0] * dy, -rl, rl);
            if let (Some(p), Some(q)) = (along, across) {
                let (l, h) = (p.0.max(q.0), p.1.min(q.1));
                if l <= h {
                    lo = lo.min(a[0] + l);
                    hi = hi.max(a[0] + h);
                }
            }
        }
        // Both still infinite (or NaN) when the row misses.
        if lo.partial_cmp(&hi).is_none_or(|o| o.is_gt()) {
            return None;
        }
        // Pixel px has its centre at px + 0.5.
        let x0 = (lo - 0.5 - 1.0).floor().max(0.0);
        let x1 = (hi - 0.5 + 1.0).ceil() + 1.0;
        if x1 <= x0 {
            return None;
        }
        Some((x0 as usize, x1 as usize))
    }
}

/// The offsets `s` with `k s + c ∈ [lo, hi]`: `Some((s0, s1))`, unbounded sides as
/// infinities, `None` when no `s` qualifies.
fn linear_range(k: f64, c: f64, lo: f64, hi: f64) -> Option<(f64, f64)> {
    if k == 0.0 {
        return (c >= lo && c <= hi).then_some((f64::NEG_INFINITY, f64::INFINITY));
    }
    let (s0, s1) = ((lo - c) / k, (hi - c) / k);
    Some((s0.min(s1), s0.max(s1)))
}

/// One figure bone (or joint) as a floor shadow, with the values the pixel loop needs.
struct ShadowPrim {
    /// Floor-plane (x, z) ends.
    a: [f32; 2],
    b: [f32; 2],
    soft: f32,
    /// `rr * 0.3` and `soft * 1.5`: the smoothstep edges (full shadow inside, none beyond).
    inner: f32,
    outer: f32,
    /// `sqrt(rr / soft)`: high bones cast fainter shadows.
    strength: f32,
}

/// Floor pixels per block of the shadow loop: the loop over a block's lanes has no branches,
/// so the compiler runs it on SIMD registers (IEEE division and square root are correctly
/// rounded there too, so each lane computes what the scalar code computes). Blocks run along a
/// row, so one primitive's values are shared by the whole block and the darkening is a
/// lane-wise maximum (no reduction across lanes per pixel).
const LANES: usize = 8;

/// One shadow primitive's values as [`seg_dist_xz`] and the smoothstep use them.
#[derive(Clone, Copy)]
struct ShadowConsts {
    ax: f32,
    az: f32,
    /// `b − a`, and its squared length.
    bax: f32,
    baz: f32,
    bb: f32,
    inner: f32,
    outer: f32,
    /// `outer − inner`, the smoothstep's denominator.
    width: f32,
    strength: f32,
    /// The floor box `lo`..`hi` within which `dist < outer` can hold: the segment's box
    /// widened by `outer` plus the cull's safety margin.
    lo: [f32; 2],
    hi: [f32; 2],
}

impl ShadowConsts {
    /// Whether the primitive may darken any point of the floor box `lo`..`hi`; when not,
    /// every point there fails `dist < outer` (the margin covers the rounding of `dist`).
    fn reaches(&self, lo: [f32; 2], hi: [f32; 2]) -> bool {
        (0..2).all(|k| self.lo[k] <= hi[k] && self.hi[k] >= lo[k])
    }

    fn new(p: &ShadowPrim) -> Self {
        let ba = [p.b[0] - p.a[0], p.b[1] - p.a[1]];
        let m = p.outer * (1.0 + SHADOW_CULL_REL) + SHADOW_CULL_ABS;
        ShadowConsts {
            ax: p.a[0],
            az: p.a[1],
            bax: ba[0],
            baz: ba[1],
            bb: ba[0] * ba[0] + ba[1] * ba[1],
            inner: p.inner,
            outer: p.outer,
            width: p.outer - p.inner,
            strength: p.strength,
            lo: [0, 1].map(|k| p.a[k].min(p.b[k]) - m),
            hi: [0, 1].map(|k| p.a[k].max(p.b[k]) + m),
        }
    }
}

/// [`LANES`] floor points of one pixel row; `on` marks the pixels the shadow may darken.
struct PixelLanes {
    x: [f32; LANES],
    z: [f32; LANES],
    on: [bool; LANES],
}

impl PixelLanes {
    const EMPTY: PixelLanes = PixelLanes {
        x: [0.0; LANES],
        z: [0.0; LANES],
        on: [false; LANES],
    };

    /// The largest darkening of each floor point by the primitives (see
    /// [`PixelLanes::occlusion_lanes`]), on 256-bit vectors where the CPU has AVX2: the same
    /// IEEE operations on wider registers (no fused multiply-add is enabled), so the same
    /// values as the 128-bit baseline build, about twice as fast.
    fn occlusion(&self, prims: &[ShadowConsts]) -> [f32; LANES] {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the running CPU supports AVX2, checked just above.
            return unsafe { self.occlusion_avx2(prims) };
        }
        self.occlusion_lanes(prims)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn occlusion_avx2(&self, prims: &[ShadowConsts]) -> [f32; LANES] {
        self.occlusion_lanes(prims)
    }

    /// Per primitive exactly `seg_dist_xz`, then `1 − smoothstep(inner, outer, dist)` times
    /// the strength where `dist < outer`, else nothing; the maximum over primitives. Every
    /// value is finite and ≥ 0 (or NaN, which `>` skips, as `f32::max` would), so the maximum
    /// does not depend on the primitives' order.
    // Lanes index several arrays in lockstep; `max(0).min(1)` is `clamp(0, 1)` for the
    // non-NaN values here and vectorises where `clamp` did not.
    #[allow(clippy::needless_range_loop, clippy::manual_clamp)]
    #[inline(always)]
    fn occlusion_lanes(&self, prims: &[ShadowConsts]) -> [f32; LANES] {
        let mut m = [0.0f32; LANES];
        for p in prims {
            // Written as straight-line selects (both sides of every `if` are computed) so
            // that the loop vectorises; the selected values are the scalar code's.
            for k in 0..LANES {
                let pax = self.x[k] - p.ax;
                let paz = self.z[k] - p.az;
                let hq = (pax * p.bax + paz * p.baz) / p.bb;
                let hc = hq.max(0.0).min(1.0);
                let h = if p.bb > 0.0 { hc } else { 0.0 };
                let dx = pax - p.bax * h;
                let dz = paz - p.baz * h;
                let dist = (dx * dx + dz * dz).sqrt();
                let tq = (dist - p.inner) / p.width;
                let t = tq.max(0.0).min(1.0);
                let s = 1.0 - t * t * (3.0 - 2.0 * t);
                let c = s * p.strength;
                let v = if dist < p.outer { c } else { 0.0 };
                m[k] = if v > m[k] { v } else { m[k] };
            }
        }
        m
    }
}

/// The shadow primitives of one frame, their floor box and its supersampled pixel box.
struct Shadows {
    prims: Vec<ShadowPrim>,
    lo: [f32; 2],
    hi: [f32; 2],
    bbox: [usize; 4],
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
