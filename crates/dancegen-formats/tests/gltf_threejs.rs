//! A written `.glb` opens in three.js: headless Chromium loads it with three's GLTFLoader from a
//! page served on 127.0.0.1, poses it at mid-clip, renders one frame and takes a screenshot, and
//! the figure's pixels must be there.
//!
//! Needs Chromium (`/usr/bin/chromium`, Debian package `chromium`; `.ci/run` installs it) and
//! npm (three.js is installed into `$CARGO_TARGET_TMPDIR/threejs` on first use). Without them
//! the test fails and says what is missing.

use std::io::{BufRead, BufReader, Write};
use std::net::TcpListener;
use std::path::{Path, PathBuf};
use std::process::Command;

use dancegen_formats::aistpp::load_motion;
use dancegen_formats::gltf::{GlbOptions, write_glb};
use dancegen_motion::skeleton::Skeleton;

/// three.js release the page is written against.
const THREE_PACKAGE: &str = "three@0.181.0";
const SIZE: u32 = 400;

const PAGE: &str = r#"<!doctype html><html><head><style>body{margin:0;background:#fff}</style>
<script type="importmap">{"imports":{"three":"/three/build/three.module.js","three/addons/":"/three/examples/jsm/"}}</script></head>
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

fn ensure_three() -> PathBuf {
    // The tests of this file run in parallel threads: two `npm install`s into one prefix on a
    // fresh target directory make one of them fail (seen on a cold run), so one installs at a
    // time and the others find the package.
    static INSTALL: std::sync::Mutex<()> = std::sync::Mutex::new(());
    let _one_at_a_time = INSTALL.lock().unwrap_or_else(|e| e.into_inner());
    let prefix = Path::new(env!("CARGO_TARGET_TMPDIR")).join("threejs");
    let module = prefix.join("node_modules/three/build/three.module.js");
    if !module.exists() {
        let out = Command::new("npm")
            .args(["install", "--silent", "--no-audit", "--no-fund", "--prefix"])
            .arg(&prefix)
            .arg(THREE_PACKAGE)
            .output()
            .unwrap_or_else(|e| panic!("this test needs npm (Node.js) on the PATH: {e}"));
        assert!(
            out.status.success() && module.exists(),
            "`npm install {THREE_PACKAGE}` failed:\n{}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    prefix.join("node_modules/three")
}

/// Serves `page`, `glb` and the three.js package on 127.0.0.1 until the test ends.
fn serve(page: &'static str, glb: Vec<u8>, three: PathBuf) -> u16 {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let port = listener.local_addr().unwrap().port();
    std::thread::spawn(move || {
        for stream in listener.incoming().flatten() {
            let mut reader = BufReader::new(stream.try_clone().unwrap());
            let mut request = String::new();
            if reader.read_line(&mut request).is_err() {
                continue;
            }
            // Drain the headers.
            let mut line = String::new();
            while reader.read_line(&mut line).is_ok_and(|n| n > 2) {
                line.clear();
            }
            let path = request.split_whitespace().nth(1).unwrap_or("/").to_string();
            let (status, ctype, body) = match path.as_str() {
                "/" | "/index.html" => ("200 OK", "text/html", page.as_bytes().to_vec()),
                "/model.glb" => ("200 OK", "model/gltf-binary", glb.clone()),
                p if p.starts_with("/three/") && !p.contains("..") => {
                    match std::fs::read(three.join(&p["/three/".len()..])) {
                        Ok(b) => ("200 OK", "text/javascript", b),
                        Err(_) => ("404 Not Found", "text/plain", b"missing".to_vec()),
                    }
                }
                _ => ("404 Not Found", "text/plain", b"missing".to_vec()),
            };
            let mut s = stream;
            let _ = write!(
                s,
                "HTTP/1.1 {status}\r\nContent-Type: {ctype}\r\nContent-Length: {}\r\nConnection: close\r\n\r\n",
                body.len()
            );
            let _ = s.write_all(&body);
        }
    });
    port
}

/// The Chromium binary (Debian's package).
fn chromium() -> &'static str {
    ["/usr/bin/chromium", "/usr/bin/chromium-browser"]
        .into_iter()
        .find(|p| Path::new(p).exists())
        .expect("this test needs Chromium (Debian: apt-get install chromium; .ci/run does)")
}

/// Headless Chromium with a throw-away profile in `dir`, no network beyond the page, and 15 s
/// of virtual time for the page's scripts.
fn headless_chromium(dir: &Path) -> Command {
    let mut c = Command::new(chromium());
    c.args([
        "--headless=new",
        "--no-sandbox",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
        "--no-first-run",
        "--disable-quic",
        "--virtual-time-budget=15000",
    ])
    .arg(format!("--user-data-dir={}", dir.join("profile").display()));
    c
}

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
    let port = serve(PAGE, std::fs::read(&glb_path).unwrap(), ensure_three());
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
<script type="importmap">{"imports":{"three":"/three/build/three.module.js","three/addons/":"/three/examples/jsm/"}}</script></head>
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
    let port = serve(FACE_PAGE, glb, ensure_three());
    let dir = tempfile::tempdir().unwrap();
    let out = headless_chromium(dir.path())
        .args(["--disable-gpu", "--dump-dom"])
        .arg(format!("http://127.0.0.1:{port}/index.html"))
        .output()
        .unwrap();
    let dom = String::from_utf8_lossy(&out.stdout);
    let json = dom
        .split("<pre id=\"out\">")
        .nth(1)
        .and_then(|s| s.split("</pre>").next())
        .unwrap_or_else(|| {
            panic!(
                "no result in the page:\n{dom}\n{}",
                String::from_utf8_lossy(&out.stderr)
            )
        });
    let r: serde_json::Value = serde_json::from_str(&json.replace("&quot;", "\""))
        .unwrap_or_else(|e| panic!("{e}: {json}"));
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
