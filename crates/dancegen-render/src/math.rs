//! Minimal 3-vector arithmetic on `[f32; 3]`.

pub type V3 = [f32; 3];

pub fn add(a: V3, b: V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

pub fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

pub fn scale(a: V3, s: f32) -> V3 {
    [a[0] * s, a[1] * s, a[2] * s]
}

pub fn dot(a: V3, b: V3) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

pub fn cross(a: V3, b: V3) -> V3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

pub fn normalize(a: V3) -> V3 {
    let n = dot(a, a).sqrt();
    if n > 0.0 { scale(a, 1.0 / n) } else { a }
}

/// Nearest positive hit of the ray `o + t d` (`d` unit) with a sphere, if any. (Frames use
/// [`RayCapsule`]; this form is the reference the tests hold it to.)
#[cfg(test)]
pub fn ray_sphere(o: V3, d: V3, c: V3, r: f32) -> Option<f32> {
    let oc = sub(o, c);
    let b = dot(d, oc);
    let cc = dot(oc, oc) - r * r;
    let h = b * b - cc;
    if h < 0.0 {
        return None;
    }
    let t = -b - h.sqrt();
    (t > 0.0).then_some(t)
}

/// Nearest positive hit of the ray with the capsule of radius `r` around segment `a`–`b`.
/// (Frames use [`RayCapsule`]; this form is the reference the tests hold it to.)
#[cfg(test)]
pub fn ray_capsule(o: V3, d: V3, a: V3, b: V3, r: f32) -> Option<f32> {
    let ba = sub(b, a);
    let oa = sub(o, a);
    let baba = dot(ba, ba);
    let bard = dot(ba, d);
    let baoa = dot(ba, oa);
    let rdoa = dot(d, oa);
    let oaoa = dot(oa, oa);
    let qa = baba - bard * bard;
    if baba > 1e-12 && qa > 1e-9 * baba {
        let qb = baba * rdoa - baoa * bard;
        let qc = baba * oaoa - baoa * baoa - r * r * baba;
        let h = qb * qb - qa * qc;
        if h < 0.0 {
            return None;
        }
        let t = (-qb - h.sqrt()) / qa;
        let y = baoa + t * bard;
        if y > 0.0 && y < baba && t > 0.0 {
            return Some(t);
        }
    }
    match (ray_sphere(o, d, a, r), ray_sphere(o, d, b, r)) {
        (Some(x), Some(y)) => Some(x.min(y)),
        (x, y) => x.or(y),
    }
}

/// [`ray_capsule`] (or [`ray_sphere`] when `a == b`) for many rays from one origin: what does
/// not depend on the ray direction is computed once, the rest with the same operations in the
/// same order, so every hit distance is bit-identical to those functions' (a frame casts one
/// ray per supersampled pixel from the camera; the per-ray work drops by about half).
#[derive(Debug, Clone, Copy)]
pub struct RayCapsule {
    ba: V3,
    /// `o − a` and `o − b`.
    oa: V3,
    ob: V3,
    baba: f32,
    baoa: f32,
    /// `baba·|oa|² − baoa² − r²·baba`: the body's quadratic constant term.
    qc: f32,
    /// `|oa|² − r²` and `|ob|² − r²`: the end spheres' constant terms.
    cc_a: f32,
    cc_b: f32,
    sphere: bool,
}

impl RayCapsule {
    pub fn new(o: V3, a: V3, b: V3, r: f32) -> Self {
        let ba = sub(b, a);
        let oa = sub(o, a);
        let ob = sub(o, b);
        let baba = dot(ba, ba);
        let baoa = dot(ba, oa);
        let oaoa = dot(oa, oa);
        RayCapsule {
            ba,
            oa,
            ob,
            baba,
            baoa,
            qc: baba * oaoa - baoa * baoa - r * r * baba,
            cc_a: oaoa - r * r,
            cc_b: dot(ob, ob) - r * r,
            sphere: a == b,
        }
    }

    /// Nearest positive hit along the unit direction `d`.
    #[inline]
    pub fn hit(&self, d: V3) -> Option<f32> {
        // `ray_sphere(o, d, a, r)`: its `dot(d, o − a)` is `rdoa`.
        let rdoa = dot(d, self.oa);
        let sphere_a = || sphere_hit(rdoa, self.cc_a);
        if self.sphere {
            return sphere_a();
        }
        let bard = dot(self.ba, d);
        let qa = self.baba - bard * bard;
        if self.baba > 1e-12 && qa > 1e-9 * self.baba {
            let qb = self.baba * rdoa - self.baoa * bard;
            let h = qb * qb - qa * self.qc;
            if h < 0.0 {
                return None;
            }
            let t = (-qb - h.sqrt()) / qa;
            let y = self.baoa + t * bard;
            if y > 0.0 && y < self.baba && t > 0.0 {
                return Some(t);
            }
        }
        match (sphere_a(), sphere_hit(dot(d, self.ob), self.cc_b)) {
            (Some(x), Some(y)) => Some(x.min(y)),
            (x, y) => x.or(y),
        }
    }
}

/// The end of [`ray_sphere`] from `b = d·(o − c)` and `cc = |o − c|² − r²`.
#[inline]
fn sphere_hit(b: f32, cc: f32) -> Option<f32> {
    let h = b * b - cc;
    if h < 0.0 {
        return None;
    }
    let t = -b - h.sqrt();
    (t > 0.0).then_some(t)
}

/// Outward unit normal of the capsule `a`–`b` at surface point `p`.
pub fn capsule_normal(p: V3, a: V3, b: V3) -> V3 {
    let ba = sub(b, a);
    let pa = sub(p, a);
    let baba = dot(ba, ba);
    let h = if baba > 0.0 {
        (dot(pa, ba) / baba).clamp(0.0, 1.0)
    } else {
        0.0
    };
    normalize(sub(pa, scale(ba, h)))
}

/// Distance in the floor plane (x, z) from point `p` to segment `a`–`b`, and the segment
/// parameter of the nearest point. (The frame renderer runs the same arithmetic on blocks of
/// primitives; this scalar form is the full-frame reference's.)
#[cfg(test)]
pub fn seg_dist_xz(p: [f32; 2], a: [f32; 2], b: [f32; 2]) -> (f32, f32) {
    let ba = [b[0] - a[0], b[1] - a[1]];
    let pa = [p[0] - a[0], p[1] - a[1]];
    let bb = ba[0] * ba[0] + ba[1] * ba[1];
    let h = if bb > 0.0 {
        ((pa[0] * ba[0] + pa[1] * ba[1]) / bb).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let dx = pa[0] - ba[0] * h;
    let dz = pa[1] - ba[1] * h;
    ((dx * dx + dz * dz).sqrt(), h)
}

pub fn smoothstep(e0: f32, e1: f32, x: f32) -> f32 {
    let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small deterministic generator (xorshift), so the test needs no dependency.
    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> f32 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            (self.0 >> 40) as f32 / (1u64 << 24) as f32 * 2.0 - 1.0
        }
        fn v3(&mut self, s: f32) -> V3 {
            [self.next() * s, self.next() * s, self.next() * s]
        }
    }

    #[test]
    fn ray_capsule_from_one_origin_is_bit_identical() {
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
        let mut hits = 0;
        for case in 0..2000 {
            let o = rng.v3(5.0);
            let a = add(rng.v3(1.0), [0.0, 0.0, -3.0]);
            // Every fifth case a sphere, some nearly degenerate segments.
            let b = match case % 5 {
                0 => a,
                1 => add(a, rng.v3(1e-4)),
                _ => add(a, rng.v3(0.6)),
            };
            let r = 0.02 + rng.next().abs() * 0.3;
            let pre = RayCapsule::new(o, a, b, r);
            for _ in 0..50 {
                // Rays aimed near the capsule, so that hits, misses and grazes all occur.
                let target = add(scale(add(a, b), 0.5), rng.v3(0.8));
                let d = normalize(sub(target, o));
                let want = if a == b {
                    ray_sphere(o, d, a, r)
                } else {
                    ray_capsule(o, d, a, b, r)
                };
                let got = pre.hit(d);
                assert_eq!(
                    got.map(f32::to_bits),
                    want.map(f32::to_bits),
                    "case {case}: o {o:?} a {a:?} b {b:?} r {r} d {d:?}"
                );
                hits += usize::from(got.is_some());
            }
        }
        assert!(hits > 5_000 && hits < 95_000, "{hits} hits of 100000 rays");
    }
}
