//! A written `.glb` opens in three.js: headless Chromium loads it with three's GLTFLoader from a
//! page served on 127.0.0.1, poses it at mid-clip, renders one frame and takes a screenshot, and
//! the figure's pixels must be there.
//!
//! Needs Chromium and npm ([`threejs_page`]); without them the test fails and says what is
//! missing.

mod threejs_page;

use std::path::Path;

use dancegen_formats::aistpp::load_motion;
use dancegen_formats::gltf::{GlbOptions, write_glb};
use dancegen_motion::skeleton::Skeleton;
use threejs_page::{IMPORT_MAP, headless_chromium, page_json, serve};

const SIZE: u32 = 400;

const PAGE: &str = r#"<!doctype html><html><head><style>body{margin:0;background:#fff}</style>
IMPORT_MAP</head>
<body><script type="module">
import * as THREE from 'three';
import {GLTFLoader} from 'three/addons/loaders/GLTFLoader.js';
const W = 400, H = 400;
const renderer = new THREE.WebGLRenderer({preserveDrawingBuffer: true});
renderer.setSize(W, H); renderer.setClearColor(0xffffff);
document.body.appendChild(renderer.domElement);
const scene = new THREE.Scene();
scene.add(new THREE.AmbientLight(0xffffff, 1.0));
const light = new THREE.DirectionalLight(0xffffff, 2.0); light.position.set(1, 2, 3); scene.add(light);
new GLTFLoader().load('/model.glb', (g) => {
  scene.add(g.scene);
  const mixer = new THREE.AnimationMixer(g.scene);
  if (g.animations.length) { const clip = g.animations[0]; mixer.clipAction(clip).play(); mixer.setTime(clip.duration * 0.5); }
  g.scene.updateMatrixWorld(true);
  const box = new THREE.Box3();
  g.scene.traverse((o) => { if (o.isBone) box.expandByPoint(o.getWorldPosition(new THREE.Vector3())); });
  const c = box.getCenter(new THREE.Vector3()), s = box.getSize(new THREE.Vector3());
  const cam = new THREE.PerspectiveCamera(40, W / H, 0.01, 1000);
  cam.position.set(c.x, c.y, c.z + Math.max(s.x, s.y, s.z) * 2.2 + 0.5); cam.lookAt(c);
  renderer.render(scene, cam);
  document.title = 'rendered';
}, undefined, (e) => { document.title = 'error ' + e; });
</script></body></html>"#;

#[test]
fn glb_renders_in_threejs_headless_chromium() {
    let shared = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared");
    let m = load_motion(shared.join("data/aistpp/motions/gBR_sBM_cAll_d04_mBR2_ch08.pkl")).unwrap();
    let motion = m.to_smpl_motion();
    let dir = tempfile::tempdir().unwrap();
    let glb_path = dir.path().join("model.glb");
    write_glb(
        &glb_path,
        &Skeleton::smpl24(),
        &motion.poses,
        &motion.trans,
        motion.fps,
        &GlbOptions::default(),
    )
    .unwrap();
    let page = PAGE.replace("IMPORT_MAP", IMPORT_MAP);
    let port = serve(page, "/model.glb", std::fs::read(&glb_path).unwrap());
    let shot = dir.path().join("shot.png");
    let out = headless_chromium(dir.path())
        .args(["--use-angle=swiftshader", "--enable-unsafe-swiftshader"])
        .arg(format!("--window-size={SIZE},{SIZE}"))
        .arg(format!("--screenshot={}", shot.display()))
        .arg(format!("http://127.0.0.1:{port}/index.html"))
        .output()
        .unwrap();
    assert!(
        shot.exists(),
        "no screenshot; chromium said:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&shot).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    let ch = info.color_type.samples();
    let (w, h) = (info.width as usize, info.height as usize);
    // The camera frames the skeleton's bounding box, so the figure fills the central area.
    let (mut figure, mut total) = (0usize, 0usize);
    for y in h / 5..h * 4 / 5 {
        for x in w / 5..w * 4 / 5 {
            let p = &buf[(y * w + x) * ch..(y * w + x) * ch + 3];
            total += 1;
            if p.iter().any(|&c| c < 200) {
                figure += 1;
            }
        }
    }
    let share = figure as f64 / total as f64;
    println!(
        "figure pixels in the central region: {figure} of {total} ({:.1} %)",
        share * 100.0
    );
    assert!(
        share > 0.02,
        "the figure is not visible ({:.2} % of the centre)",
        share * 100.0
    );
}

const FACE_PAGE: &str = r#"<!doctype html><html><head>
IMPORT_MAP</head>
<body><pre id="out">pending</pre><script type="module">
import * as THREE from 'three';
import {GLTFLoader} from 'three/addons/loaders/GLTFLoader.js';
const out = document.getElementById('out');
new GLTFLoader().load('/model.glb', (g) => {
  let face = null;
  g.scene.traverse((o) => { if (o.isMesh && o.morphTargetDictionary) face = o; });
  const mixer = new THREE.AnimationMixer(g.scene);
  mixer.clipAction(g.animations[0]).play();
  mixer.setTime(10 / 30);
  const names = Object.entries(face.morphTargetDictionary).sort((a, b) => a[1] - b[1]).map((e) => e[0]);
  out.textContent = JSON.stringify({names, influences: Array.from(face.morphTargetInfluences),
    parent: face.parent ? face.parent.name : null});
}, undefined, (e) => { out.textContent = 'error ' + e; });
</script></body></html>"#;

/// three.js loads the face: 52 morph targets named after ARKit, and the animation mixer drives
/// their influences to the weights written for that frame.
#[test]
fn face_morph_targets_play_in_threejs_headless_chromium() {
    use dancegen_formats::gltf::{DancerAnimation, FaceAnimation, glb_bytes_with_face};
    use dancegen_motion::face::{ARKIT_COUNT, ARKIT_NAMES, FaceWeights};
    let sk = Skeleton::smplh52_approx();
    let frames = 20;
    let rot = vec![0.0f32; frames * 52 * 3];
    let trans: Vec<f32> = (0..frames).flat_map(|_| [0.0, 0.9, 0.0]).collect();
    let w: Vec<f32> = (0..frames * ARKIT_COUNT)
        .map(|i| 0.5 + 0.5 * ((i / ARKIT_COUNT) as f32 * 0.4 + (i % ARKIT_COUNT) as f32).sin())
        .collect();
    let face = FaceWeights::new(w, 30.0).unwrap();
    let glb = glb_bytes_with_face(
        &sk,
        DancerAnimation {
            local_rotations_axis_angle: &rot,
            root_translation: &trans,
        },
        FaceAnimation {
            weights: &face,
            head_joint: 15,
        },
        30.0,
        &GlbOptions::default(),
    )
    .unwrap();
    let r = page_json(serve(
        FACE_PAGE.replace("IMPORT_MAP", IMPORT_MAP),
        "/model.glb",
        glb,
    ));
    let names: Vec<&str> = r["names"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    assert_eq!(names, ARKIT_NAMES);
    assert_eq!(r["parent"], "head");
    let inf: Vec<f64> = r["influences"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    let worst = inf
        .iter()
        .zip(face.frame(10))
        .map(|(a, b)| (a - *b as f64).abs())
        .fold(0.0, f64::max);
    println!("three.js influences at frame 10 vs written weights: max error {worst:.1e}");
    assert!(worst < 1e-4, "{worst}");
}
