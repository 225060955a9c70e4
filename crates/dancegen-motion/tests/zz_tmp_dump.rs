use dancegen_motion::gltf::{GlbOptions, glb_bytes};
use dancegen_motion::skeleton::Skeleton;
#[test]
fn dump() {
    let sk = Skeleton::smpl24();
    for (name, frames) in [("a", 1usize), ("b", 45)] {
        let mut rot = Vec::new();
        let mut tr = Vec::new();
        for f in 0..frames {
            for j in 0..24 {
                let a = 0.7 * ((f as f32) * 0.3 + j as f32).sin();
                rot.extend([a, -0.4 * a, 0.2 + a * 0.1 * j as f32]);
            }
            tr.extend([0.01 * f as f32, 0.9, -0.02 * f as f32]);
        }
        let mut o = GlbOptions::default();
        if name == "b" {
            o.sides = 5;
            o.base_color = [0.1, 0.2, 0.3, 1.0];
            o.animation_name = "x".into();
        }
        let b = glb_bytes(&sk, &rot, &tr, 30.0, &o).unwrap();
        let out = std::env::var("GLB_DUMP").unwrap();
        std::fs::write(format!("{out}/{name}.glb"), b).unwrap();
    }
}
