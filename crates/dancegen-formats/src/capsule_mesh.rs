//! The bind-pose body both exporters ([`crate::gltf`], [`crate::fbx`]) skin to the skeleton: one
//! tapered capsule per bone, weighted 100% to the bone's parent joint (the joint whose rotation
//! moves the bone). Kept in one place so a `.glb` and an `.fbx` of the same motion show the same
//! figure, vertex for vertex.

use dancegen_motion::skeleton::Skeleton;
use dancegen_motion::vec3::{add, cross, norm, scale, sub};

/// The bind-pose body: one capsule per bone, in the rest pose, metres (Y-up).
pub(crate) struct CapsuleMesh {
    /// `V×3` vertex positions.
    pub positions: Vec<f32>,
    /// `V×3` unit vertex normals.
    pub normals: Vec<f32>,
    /// Joint of each vertex.
    pub joints: Vec<u16>,
    /// Triangle list, counter-clockwise seen from outside.
    pub indices: Vec<u32>,
}

impl CapsuleMesh {
    pub fn vertex_count(&self) -> usize {
        self.joints.len()
    }

    fn push(&mut self, p: [f64; 3], n: [f64; 3], joint: usize) -> u32 {
        self.positions.extend(p.map(|v| v as f32));
        self.normals.extend(n.map(|v| v as f32));
        self.joints.push(joint as u16);
        (self.joints.len() - 1) as u32
    }
}

/// Shape of the capsules; callers validate the values (positive radius and taper, `sides ≥ 3`).
#[derive(Debug, Clone, Copy)]
pub(crate) struct CapsuleShape {
    /// Radius at the parent end of each bone, metres (capped at 35% of the bone length).
    pub bone_radius: f32,
    /// Radius at the child end relative to the parent end.
    pub taper: f32,
    /// Sides of each capsule.
    pub sides: usize,
}

/// Latitudes (radians) of the capsule rings: three on the parent-end hemisphere (including its
/// equator), three on the child-end one.
const CAP_LATITUDES: [f64; 3] = [
    -std::f64::consts::FRAC_PI_3,
    -std::f64::consts::FRAC_PI_6,
    0.0,
];

/// Builds the body for the rest world positions `rest` (one per joint). Bones shorter than a
/// micrometre get no capsule.
pub(crate) fn build_capsule_mesh(
    skeleton: &Skeleton,
    rest: &[[f64; 3]],
    shape: CapsuleShape,
) -> CapsuleMesh {
    let mut m = CapsuleMesh {
        positions: Vec::new(),
        normals: Vec::new(),
        joints: Vec::new(),
        indices: Vec::new(),
    };
    let sides = shape.sides;
    for (j, parent) in skeleton.parents().iter().enumerate() {
        let Some(p) = *parent else { continue };
        let (a, b) = (rest[p], rest[j]);
        let d = sub(b, a);
        let len = norm(d);
        if len < 1e-6 {
            continue;
        }
        let axis = scale(d, 1.0 / len);
        // Any unit vector perpendicular to the axis, then v = axis × u so that (u, v, axis)
        // is right-handed.
        let helper = if axis[1].abs() < 0.9 {
            [0.0, 1.0, 0.0]
        } else {
            [1.0, 0.0, 0.0]
        };
        let u = cross(helper, axis);
        let u = scale(u, 1.0 / norm(u));
        let v = cross(axis, u);
        let r0 = (shape.bone_radius as f64).min(0.35 * len);
        let r1 = r0 * shape.taper as f64;
        // Rings from the parent-end pole to the child-end pole.
        let mut rings: Vec<([f64; 3], f64, f64)> = Vec::new(); // (centre, radius, latitude)
        for &lat in &CAP_LATITUDES {
            rings.push((a, r0, lat));
        }
        for &lat in CAP_LATITUDES.iter().rev() {
            rings.push((b, r1, -lat));
        }
        let start_pole = m.push(add(a, scale(axis, -r0)), scale(axis, -1.0), p);
        let first = m.joints.len() as u32;
        for &(c, r, lat) in &rings {
            for s in 0..sides {
                let th = std::f64::consts::TAU * s as f64 / sides as f64;
                let radial = add(scale(u, th.cos()), scale(v, th.sin()));
                let n = add(scale(radial, lat.cos()), scale(axis, lat.sin()));
                m.push(add(c, scale(n, r)), n, p);
            }
        }
        let end_pole = m.push(add(b, scale(axis, r1)), axis, p);
        let s = sides as u32;
        let at = |ring: u32, side: u32| first + ring * s + side % s;
        for side in 0..s {
            m.indices.extend([start_pole, at(0, side + 1), at(0, side)]);
            for ring in 0..rings.len() as u32 - 1 {
                let (a0, b0) = (at(ring, side), at(ring, side + 1));
                let (c0, d0) = (at(ring + 1, side + 1), at(ring + 1, side));
                m.indices.extend([a0, b0, c0, a0, c0, d0]);
            }
            let last = rings.len() as u32 - 1;
            m.indices
                .extend([at(last, side), at(last, side + 1), end_pole]);
        }
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn triangles_face_outwards() {
        let sk = Skeleton::smpl24();
        let rest = sk.rest_positions();
        let shape = CapsuleShape {
            bone_radius: 0.045,
            taper: 0.7,
            sides: 8,
        };
        let m = build_capsule_mesh(&sk, &rest, shape);
        assert_eq!(m.vertex_count(), 23 * (6 * 8 + 2));
        let p = |i: u32| {
            let k = i as usize * 3;
            [0, 1, 2].map(|c| m.positions[k + c] as f64)
        };
        let n = |i: u32| {
            let k = i as usize * 3;
            [0, 1, 2].map(|c| m.normals[k + c] as f64)
        };
        for t in m.indices.chunks_exact(3) {
            let face = cross(sub(p(t[1]), p(t[0])), sub(p(t[2]), p(t[0])));
            let avg = add(add(n(t[0]), n(t[1])), n(t[2]));
            let dot: f64 = (0..3).map(|k| face[k] * avg[k]).sum();
            assert!(dot > 0.0, "triangle {t:?} faces inwards");
        }
        for i in 0..m.vertex_count() as u32 {
            assert!((norm(n(i)) - 1.0).abs() < 1e-5);
        }
    }
}
