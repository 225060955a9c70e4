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

/// Nearest positive hit of the ray `o + t d` (`d` unit) with a sphere, if any.
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
