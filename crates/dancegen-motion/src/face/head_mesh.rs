//! A simple head mesh with the 52 ARKit blendshapes as morph targets, so a `.glb` carries a
//! face that plays its `weights` animation in any glTF viewer and imports into Blender as shape
//! keys named after ARKit.
//!
//! It is a stand-in face, not a sculpted one: an ellipsoid (in the head joint's frame: Y up, Z
//! forward, the dancer's left = +X, metres) whose vertices near the eyes, brows, mouth, jaw,
//! cheeks and nose move with each blendshape. Each target is a sum of Gaussian "bumps": the
//! vertices within about `sigma` of a centre on the face move by `delta`, fading with distance.
//! Tools that retarget ARKit weights by name (Live Link, VRM Perfect Sync) need only the names;
//! the geometry is there so a viewer shows the face move.

use super::arkit::{ARKIT_COUNT, ARKIT_NAMES};

/// Head semi-axes (x, y, z), metres, and the centre's offset from the head joint.
const RADII: [f64; 3] = [0.075, 0.105, 0.09];
const CENTRE: [f64; 3] = [0.0, 0.07, 0.015];
/// Rings and segments of the ellipsoid's latitude–longitude grid.
const RINGS: usize = 24;
const SEGMENTS: usize = 32;

/// The head: bind-pose geometry in the head joint's frame and one displacement field per ARKit
/// blendshape.
pub struct HeadMesh {
    /// `V×3`.
    pub positions: Vec<f32>,
    /// `V×3` unit normals.
    pub normals: Vec<f32>,
    /// Triangles, counter-clockwise from outside.
    pub indices: Vec<u32>,
    /// Per blendshape (ARKit order), `V×3` displacements at weight 1.
    pub targets: Vec<Vec<f32>>,
    /// `V×3` linear RGB: skin, with dark eyes and brows and red lips painted where the
    /// blendshapes move them, so a viewer can see the expressions (the bare shape's bumps
    /// do not show at viewing distance).
    pub colors: Vec<f32>,
}

/// A face feature: a point on the front of the head (x, y relative to the centre; it is
/// projected onto the ellipsoid's front) and its spread.
#[derive(Clone, Copy)]
struct Bump {
    at: [f64; 2],
    sigma: f64,
    delta: [f64; 3],
}

const fn bump(x: f64, y: f64, sigma: f64, delta: [f64; 3]) -> Bump {
    Bump {
        at: [x, y],
        sigma,
        delta,
    }
}

/// Vertex colours (linear RGB): skin, and the painted features with their half-widths (x, y)
/// on the face, metres.
const SKIN: [f32; 3] = [0.85, 0.7, 0.6];
const EYE_COLOR: [f32; 3] = [0.03, 0.025, 0.02];
const BROW_COLOR: [f32; 3] = [0.08, 0.05, 0.03];
const LIP_COLOR: [f32; 3] = [0.45, 0.06, 0.06];
const EYE_SIZE: [f64; 2] = [0.011, 0.008];
const BROW_SIZE: [f64; 2] = [0.016, 0.005];
const LIP_SIZE: [f64; 2] = [0.026, 0.009];

/// Feature positions on the face (x = dancer's left, y = up, relative to the head centre).
const EYE: [f64; 2] = [0.032, 0.02];
const BROW: [f64; 2] = [0.032, 0.045];
const MOUTH_CORNER: [f64; 2] = [0.025, -0.045];
const MOUTH: [f64; 2] = [0.0, -0.045];
const CHIN: [f64; 2] = [0.0, -0.08];
const CHEEK: [f64; 2] = [0.045, -0.015];
const NOSE_SIDE: [f64; 2] = [0.012, -0.012];

/// The bumps of a left-side (or central) blendshape, by name without its side; `s` = +1 for
/// the dancer's left, −1 for the right (x mirrored).
fn bumps(base: &str, s: f64) -> Vec<Bump> {
    let m = 0.001; // millimetre
    let side = |p: [f64; 2]| [s * p[0], p[1]];
    let at = |p: [f64; 2], sigma: f64, d: [f64; 3]| {
        let q = side(p);
        bump(q[0], q[1], sigma, [s * d[0], d[1], d[2]])
    };
    match base {
        "eyeBlink" => vec![at(
            [EYE[0], EYE[1] + 0.006],
            0.012,
            [0.0, -12.0 * m, 1.0 * m],
        )],
        "eyeLookDown" => vec![at(EYE, 0.008, [0.0, -3.0 * m, 0.0])],
        "eyeLookIn" => vec![at(EYE, 0.008, [-3.0 * m, 0.0, 0.0])],
        "eyeLookOut" => vec![at(EYE, 0.008, [3.0 * m, 0.0, 0.0])],
        "eyeLookUp" => vec![at(EYE, 0.008, [0.0, 3.0 * m, 0.0])],
        "eyeSquint" => vec![at([EYE[0], EYE[1] - 0.008], 0.01, [0.0, 4.0 * m, 0.0])],
        "eyeWide" => vec![at([EYE[0], EYE[1] + 0.008], 0.01, [0.0, 4.0 * m, 0.0])],
        "jawForward" => vec![at(CHIN, 0.03, [0.0, 0.0, 8.0 * m])],
        "jawOpen" => vec![at(CHIN, 0.035, [0.0, -22.0 * m, -4.0 * m])],
        "jawSide" => vec![at(CHIN, 0.03, [8.0 * m, 0.0, 0.0])],
        "mouthClose" => vec![at([0.0, MOUTH[1] - 0.01], 0.015, [0.0, 6.0 * m, 0.0])],
        "mouthFunnel" => vec![at(MOUTH, 0.016, [0.0, 0.0, 7.0 * m])],
        "mouthPucker" => vec![
            at(MOUTH, 0.014, [0.0, 0.0, 9.0 * m]),
            at(MOUTH_CORNER, 0.01, [-6.0 * m, 0.0, 0.0]),
        ],
        "mouthSide" => vec![at(MOUTH, 0.02, [8.0 * m, 0.0, 0.0])],
        "mouthSmile" => vec![at(MOUTH_CORNER, 0.012, [6.0 * m, 7.0 * m, -2.0 * m])],
        "mouthFrown" => vec![at(MOUTH_CORNER, 0.012, [0.0, -7.0 * m, 0.0])],
        "mouthDimple" => vec![at(MOUTH_CORNER, 0.01, [3.0 * m, 0.0, -3.0 * m])],
        "mouthStretch" => vec![at(MOUTH_CORNER, 0.012, [6.0 * m, -3.0 * m, 0.0])],
        "mouthRollLower" => vec![at([0.0, MOUTH[1] - 0.006], 0.01, [0.0, 0.0, -4.0 * m])],
        "mouthRollUpper" => vec![at([0.0, MOUTH[1] + 0.006], 0.01, [0.0, 0.0, -4.0 * m])],
        "mouthShrugLower" => vec![at([0.0, MOUTH[1] - 0.01], 0.012, [0.0, 4.0 * m, 2.0 * m])],
        "mouthShrugUpper" => vec![at([0.0, MOUTH[1] + 0.008], 0.012, [0.0, 3.0 * m, 2.0 * m])],
        "mouthPress" => vec![at([0.012, MOUTH[1]], 0.01, [0.0, 0.0, -3.0 * m])],
        "mouthLowerDown" => vec![at([0.012, MOUTH[1] - 0.008], 0.01, [0.0, -5.0 * m, 0.0])],
        "mouthUpperUp" => vec![at([0.012, MOUTH[1] + 0.008], 0.01, [0.0, 5.0 * m, 0.0])],
        "browDown" => vec![at(BROW, 0.014, [0.0, -6.0 * m, 0.0])],
        "browInnerUp" => vec![
            at([0.012, BROW[1]], 0.012, [0.0, 7.0 * m, 0.0]),
            at([-0.012, BROW[1]], 0.012, [0.0, 7.0 * m, 0.0]),
        ],
        "browOuterUp" => vec![at([BROW[0] + 0.012, BROW[1]], 0.012, [0.0, 7.0 * m, 0.0])],
        "cheekPuff" => vec![
            at(CHEEK, 0.02, [6.0 * m, 0.0, 4.0 * m]),
            at([-CHEEK[0], CHEEK[1]], 0.02, [-6.0 * m, 0.0, 4.0 * m]),
        ],
        "cheekSquint" => vec![at(CHEEK, 0.015, [0.0, 5.0 * m, 0.0])],
        "noseSneer" => vec![at(NOSE_SIDE, 0.008, [0.0, 4.0 * m, 0.0])],
        "tongueOut" => vec![at(MOUTH, 0.008, [0.0, -2.0 * m, 12.0 * m])],
        other => unreachable!("no bumps for {other}"),
    }
}

/// The bumps of ARKit blendshape `i`.
fn target_bumps(i: usize) -> Vec<Bump> {
    let name = ARKIT_NAMES[i];
    let (base, s) = if let Some(b) = name.strip_suffix("Left") {
        (b, 1.0)
    } else if let Some(b) = name.strip_suffix("Right") {
        (b, -1.0)
    } else {
        (name, 1.0)
    };
    match base {
        // Whole-jaw and whole-mouth shifts: "Left" moves toward the dancer's left.
        "jaw" => bumps("jawSide", s),
        "mouth" => bumps("mouthSide", s),
        // Central shapes are drawn once, not mirrored.
        _ => bumps(base, s),
    }
}

/// Builds the head (see the module documentation).
pub fn build_head_mesh() -> HeadMesh {
    let mut positions = Vec::new();
    let mut normals = Vec::new();
    for r in 0..=RINGS {
        let lat = std::f64::consts::PI * (r as f64 / RINGS as f64) - std::f64::consts::FRAC_PI_2;
        for sgm in 0..=SEGMENTS {
            let lon = std::f64::consts::TAU * sgm as f64 / SEGMENTS as f64;
            // Unit sphere point: y up, z forward at lon = 0.
            let u = [lat.cos() * lon.sin(), lat.sin(), lat.cos() * lon.cos()];
            let p = [
                CENTRE[0] + RADII[0] * u[0],
                CENTRE[1] + RADII[1] * u[1],
                CENTRE[2] + RADII[2] * u[2],
            ];
            // Ellipsoid normal ∝ (x/a², y/b², z/c²).
            let n = [u[0] / RADII[0], u[1] / RADII[1], u[2] / RADII[2]];
            let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            positions.extend(p.map(|v| v as f32));
            normals.extend(n.map(|v| (v / len) as f32));
        }
    }
    let row = (SEGMENTS + 1) as u32;
    let mut indices = Vec::new();
    for r in 0..RINGS as u32 {
        for s in 0..SEGMENTS as u32 {
            let (a, b) = (r * row + s, r * row + s + 1);
            let (c, d) = (a + row, b + row);
            // Counter-clockwise from outside (latitude grows upward, longitude toward +X).
            indices.extend([a, b, d, a, d, c]);
        }
    }
    let vertex = |k: usize| {
        [
            positions[k * 3] as f64,
            positions[k * 3 + 1] as f64,
            positions[k * 3 + 2] as f64,
        ]
    };
    let n = positions.len() / 3;
    let targets = (0..ARKIT_COUNT)
        .map(|i| {
            let bumps = target_bumps(i);
            let mut d = vec![0.0f32; n * 3];
            for k in 0..n {
                let v = vertex(k);
                // Only the front half of the head carries a face.
                if v[2] - CENTRE[2] <= 0.0 {
                    continue;
                }
                for b in &bumps {
                    let dx = v[0] - CENTRE[0] - b.at[0];
                    let dy = v[1] - CENTRE[1] - b.at[1];
                    let w = (-(dx * dx + dy * dy) / (2.0 * b.sigma * b.sigma)).exp();
                    if w > 1e-3 {
                        for a in 0..3 {
                            d[k * 3 + a] += (w * b.delta[a]) as f32;
                        }
                    }
                }
            }
            d
        })
        .collect();
    let colors = (0..n).flat_map(|k| vertex_color(vertex(k))).collect();
    HeadMesh {
        positions,
        normals,
        indices,
        targets,
        colors,
    }
}

/// The colour of the vertex at `v`: a feature's where `v` is on the front of the head within
/// the feature's oval (both eyes and brows, the lips), blended into the skin at its rim.
fn vertex_color(v: [f64; 3]) -> [f32; 3] {
    if v[2] - CENTRE[2] <= 0.0 {
        return SKIN;
    }
    let (x, y) = (v[0] - CENTRE[0], v[1] - CENTRE[1]);
    let features = [
        (EYE, EYE_SIZE, EYE_COLOR),
        (BROW, BROW_SIZE, BROW_COLOR),
        (MOUTH, LIP_SIZE, LIP_COLOR),
    ];
    let mut color = SKIN;
    for (at, size, paint) in features {
        // Both sides: the features are symmetric (the mouth is on the centre line).
        let dx = x.abs() - at[0];
        let d = ((dx / size[0]).powi(2) + ((y - at[1]) / size[1]).powi(2)).sqrt();
        // 1 inside the oval, fading to 0 at 1.5 times its size.
        let w = ((1.5 - d) / 0.5).clamp(0.0, 1.0) as f32;
        for c in 0..3 {
            color[c] += w * (paint[c] - color[c]);
        }
    }
    color
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::face::arkit::arkit_index;

    /// The painted features are where the blendshapes that move them act: the vertices
    /// `eyeBlinkLeft` moves most are dark, those `jawOpen` moves most around the mouth are red,
    /// the back of the head is skin.
    #[test]
    fn eyes_and_lips_are_painted_where_their_blendshapes_move() {
        let h = build_head_mesh();
        let n = h.positions.len() / 3;
        assert_eq!(h.colors.len(), n * 3);
        let color = |k: usize| [h.colors[k * 3], h.colors[k * 3 + 1], h.colors[k * 3 + 2]];
        let most_moved = |name: &str| {
            let t = &h.targets[arkit_index(name).unwrap()];
            (0..n)
                .max_by(|&a, &b| {
                    let m =
                        |k: usize| t[k * 3].powi(2) + t[k * 3 + 1].powi(2) + t[k * 3 + 2].powi(2);
                    m(a).total_cmp(&m(b))
                })
                .unwrap()
        };
        let eye = color(most_moved("eyeBlinkLeft"));
        assert!(eye.iter().all(|&c| c < 0.2), "the blinking eye is {eye:?}");
        let lip = color(most_moved("mouthPucker"));
        assert!(
            lip[0] > 2.0 * lip[1] && lip[1] < 0.3,
            "the pursed lips are {lip:?}"
        );
        let back = (0..n).find(|&k| h.positions[k * 3 + 2] < -0.05).unwrap();
        assert_eq!(color(back), SKIN);
    }

    #[test]
    fn every_blendshape_moves_the_face_and_sides_mirror() {
        let h = build_head_mesh();
        let n = h.positions.len() / 3;
        assert_eq!(h.normals.len(), n * 3);
        assert_eq!(h.targets.len(), 52);
        let max = |t: &[f32]| {
            t.chunks_exact(3)
                .map(|d| (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt())
                .fold(0.0, f32::max)
        };
        for (i, t) in h.targets.iter().enumerate() {
            let m = max(t);
            assert!(
                (0.0015..0.03).contains(&m),
                "{}: largest move {m} m",
                ARKIT_NAMES[i]
            );
        }
        // Left and right shapes are mirror images: same largest move, centres on opposite sides.
        let centroid_x = |t: &[f32]| {
            let (mut sx, mut sw) = (0.0f64, 0.0f64);
            for (k, d) in t.chunks_exact(3).enumerate() {
                let w = ((d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) as f64).sqrt();
                sx += w * h.positions[k * 3] as f64;
                sw += w;
            }
            sx / sw
        };
        for (i, name) in ARKIT_NAMES.iter().enumerate() {
            if let Some(b) = name.strip_suffix("Left") {
                let j = arkit_index(&format!("{b}Right")).unwrap();
                assert!(
                    (max(&h.targets[i]) - max(&h.targets[j])).abs() < 1e-4,
                    "{name}"
                );
                if b == "jaw" || b == "mouth" {
                    // Whole-jaw / whole-mouth shifts: centred, moving toward their side.
                    let dx = |t: &[f32]| t.chunks_exact(3).map(|d| d[0]).sum::<f32>();
                    assert!(dx(&h.targets[i]) > 0.0 && dx(&h.targets[j]) < 0.0, "{name}");
                } else {
                    assert!(
                        centroid_x(&h.targets[i]) > 0.003 && centroid_x(&h.targets[j]) < -0.003,
                        "{name}"
                    );
                }
            }
        }
        // The jaw opens downward; a blink lowers the upper lid.
        let mean_dy = |name: &str| {
            let t = &h.targets[arkit_index(name).unwrap()];
            t.chunks_exact(3).map(|d| d[1]).sum::<f32>()
        };
        assert!(
            mean_dy("jawOpen") < 0.0
                && mean_dy("eyeBlinkLeft") < 0.0
                && mean_dy("mouthSmileLeft") > 0.0
        );
        assert!(h.indices.iter().all(|&i| (i as usize) < n));
    }
}
