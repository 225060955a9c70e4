//! The `.fbx` dancegen writes, opened by two programs users import it into besides Blender
//! (`dancegen-cli`'s `cli_blender.rs`) and ufbx (`fbx_ufbx.rs`): Assimp, the importer behind
//! many engines and viewers (the `assimp` command of Debian's `assimp-utils`), and three.js's
//! `FBXLoader` in headless Chromium. Each must find the animation and, played, put every joint
//! where dancegen's forward kinematics (what `.npy` holds) puts it.
//!
//! Needs `assimp` (Debian: `apt-get install assimp-utils`; `tools/test.sh` installs it),
//! Chromium and npm ([`threejs_page`]). Without them the tests fail and say what is missing.

mod threejs_page;

use std::path::Path;
use std::process::Command;

use dancegen_formats::aistpp::load_motion;
use dancegen_formats::fbx::{FbxOptions, write_fbx};
use dancegen_formats::gltf::DancerAnimation;
use dancegen_motion::fk::{LocalRotations, forward_kinematics};
use dancegen_motion::skeleton::Skeleton;

/// Frames of the real clip written (a few seconds keeps the files small).
const FRAMES: usize = 150;
/// Largest joint position error accepted from a client, metres. The file holds `f32` Euler
/// degrees (about 1e-5° of rounding) and the clients play them in `f32`: over a 24-joint chain
/// that is micrometres (Assimp measured 1.8e-6 m, FBXLoader 2.2e-7 m), so 1e-4 leaves room
/// for another client version's rounding and still fails a wrong axis, order or unit.
const TOL_M: f64 = 1e-4;

/// A real dance (AIST++ break, first [`FRAMES`] frames): local axis-angle rotations, the root
/// translation, the frame rate, and its FK joint positions `(T, 24, 3)`.
struct Clip {
    rot: Vec<f32>,
    trans: Vec<f32>,
    fps: f32,
    positions: Vec<f64>,
}

fn clip() -> Clip {
    let shared = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared");
    let m = load_motion(shared.join("data/aistpp/motions/gBR_sBM_cAll_d04_mBR2_ch08.pkl"))
        .unwrap()
        .to_smpl_motion();
    let rot = m.poses[..FRAMES * 72].to_vec();
    let trans = m.trans[..FRAMES * 3].to_vec();
    let r64: Vec<f64> = rot.iter().map(|&v| f64::from(v)).collect();
    let t64: Vec<f64> = trans.iter().map(|&v| f64::from(v)).collect();
    let fk = forward_kinematics(
        &Skeleton::smpl24(),
        LocalRotations::AxisAngle(&r64),
        &t64,
        false,
    )
    .unwrap();
    Clip {
        rot,
        trans,
        fps: m.fps,
        positions: fk.positions,
    }
}

/// Writes the clip as `.fbx` into `dir` and returns its path.
fn write(dir: &Path, c: &Clip) -> std::path::PathBuf {
    let path = dir.join("dance.fbx");
    write_fbx(
        &path,
        &Skeleton::smpl24(),
        &[DancerAnimation {
            local_rotations_axis_angle: &c.rot,
            root_translation: &c.trans,
        }],
        c.fps,
        &FbxOptions::default(),
    )
    .unwrap();
    path
}

/// Runs `assimp` with `args` and returns what it printed (its log, `-l`, goes to stderr);
/// fails the test, saying how to install it, when it is missing.
fn assimp(args: &[&std::ffi::OsStr]) -> String {
    let out = Command::new("assimp")
        .args(args)
        .output()
        .unwrap_or_else(|e| {
            panic!("this test needs assimp (Debian: apt-get install assimp-utils): {e}")
        });
    assert!(
        out.status.success(),
        "assimp {args:?} failed:\n{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    )
}

/// Assimp imports the animation: one clip of the file's length with a channel per joint, no
/// parser or DOM complaint in its log, and, from its dump, the root's position keys and every
/// joint's rotation keys at frames {0, 1, T/2, T − 1} posing the joints where FK does.
#[test]
fn assimp_imports_the_fbx_animation() {
    let c = clip();
    let dir = tempfile::tempdir().unwrap();
    let fbx = write(dir.path(), &c);
    let info = assimp(&["info".as_ref(), fbx.as_os_str(), "-l".as_ref()]);
    let complaints: Vec<&str> = info
        .lines()
        .filter(|l| l.contains("FBX-Parser") || l.contains("FBX-DOM"))
        .collect();
    assert!(
        complaints.is_empty(),
        "assimp's FBX reader complained:\n{complaints:#?}"
    );
    let count = |key: &str| -> usize {
        info.lines()
            .find_map(|l| l.strip_prefix(key))
            .and_then(|v| v.trim().parse().ok())
            .unwrap_or_else(|| panic!("no {key:?} in assimp's report:\n{info}"))
    };
    assert_eq!(count("Animations:"), 1, "{info}");
    assert_eq!(count("Animation Channels:"), 24, "{info}");

    let xml = dir.path().join("dump.xml");
    assimp(&["dump".as_ref(), fbx.as_os_str(), xml.as_os_str()]);
    let dump = std::fs::read_to_string(&xml).unwrap();
    let sk = Skeleton::smpl24();
    let keys = node_keys(&dump);
    let frames = c.trans.len() / 3;
    let ticks = animation_ticks_per_second(&dump);
    let mut worst = 0.0f64;
    for f in [0, 1, frames / 2, frames - 1] {
        let time = f as f64 / f64::from(c.fps) * ticks;
        // Local rotations from the dump, the root's translation from its position keys.
        let mut rot = Vec::with_capacity(72);
        for name in sk.names() {
            let k = keys
                .get(name.as_str())
                .unwrap_or_else(|| panic!("assimp has no channel for joint {name}"));
            let q = at(&k.rotations, time, name);
            let aa = dancegen_motion::rotation::Quat::new(q[0], q[1], q[2], q[3])
                .normalize()
                .to_axis_angle();
            rot.extend(aa);
        }
        let root = at(&keys[sk.names()[0].as_str()].positions, time, "root");
        let got = forward_kinematics(&sk, LocalRotations::AxisAngle(&rot), &root, false)
            .unwrap()
            .positions;
        let want = &c.positions[f * 72..(f + 1) * 72];
        let err = got
            .iter()
            .zip(want)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        worst = worst.max(err);
        assert!(
            err < TOL_M,
            "frame {f}: assimp's pose is {err:.2e} m off FK"
        );
    }
    println!("assimp: 1 animation, 24 channels; worst joint error at 4 frames {worst:.1e} m");
}

/// One joint's keys from an assimp XML dump: `(time, value)` with rotations as `[w, x, y, z]`.
#[derive(Default)]
struct Keys {
    positions: Vec<(f64, Vec<f64>)>,
    rotations: Vec<(f64, Vec<f64>)>,
}

/// The value keyed at `time` (within a tenth of a tick).
fn at(keys: &[(f64, Vec<f64>)], time: f64, what: &str) -> Vec<f64> {
    keys.iter()
        .find(|(t, _)| (t - time).abs() < 0.1)
        .map(|(_, v)| v.clone())
        .unwrap_or_else(|| panic!("{what}: no key at {time} ticks"))
}

/// Ticks per second of the dump's first animation (`tick_cnt`).
fn animation_ticks_per_second(dump: &str) -> f64 {
    dump.split("tick_cnt=\"")
        .nth(1)
        .and_then(|s| s.split('"').next())
        .and_then(|v| v.parse().ok())
        .filter(|&t: &f64| t > 0.0)
        .unwrap_or_else(|| panic!("no tick_cnt in assimp's dump"))
}

/// Every animated node's position and rotation keys in an assimp XML (`assxml`) dump, where a
/// key is `<PositionKey time="t">` (or `RotationKey`) and its values on the next line
/// (quaternions as `x y z w`).
fn node_keys(dump: &str) -> std::collections::HashMap<String, Keys> {
    let attr = |line: &str, name: &str| -> Option<String> {
        let rest = line.split(&format!("{name}=\"")).nth(1)?;
        Some(rest.split('"').next()?.to_string())
    };
    let mut out: std::collections::HashMap<String, Keys> = Default::default();
    let mut node = None;
    let mut lines = dump.lines();
    while let Some(line) = lines.next() {
        let line = line.trim();
        if line.starts_with("<NodeAnim ") {
            node = attr(line, "node");
            continue;
        }
        let rotation = line.starts_with("<RotationKey ");
        if !(rotation || line.starts_with("<PositionKey ")) {
            continue;
        }
        let name = node.clone().expect("a key outside a NodeAnim");
        let time: f64 = attr(line, "time").and_then(|t| t.parse().ok()).unwrap();
        let v: Vec<f64> = lines
            .next()
            .unwrap_or("")
            .split_whitespace()
            .map(|x| x.parse().unwrap())
            .collect();
        let keys = out.entry(name).or_default();
        if rotation {
            assert_eq!(v.len(), 4, "{line}");
            keys.rotations.push((time, vec![v[3], v[0], v[1], v[2]]));
        } else {
            assert_eq!(v.len(), 3, "{line}");
            keys.positions.push((time, v));
        }
    }
    out
}

const FBX_PAGE: &str = r#"<!doctype html><html><head>IMPORT_MAP</head>
<body><pre id="out">pending</pre><script type="module">
import * as THREE from 'three';
import {FBXLoader} from 'three/addons/loaders/FBXLoader.js';
const out = document.getElementById('out');
new FBXLoader().load('/dance.fbx', (obj) => {
  const result = {clips: obj.animations.length, poses: {}};
  if (obj.animations.length) {
    const clip = obj.animations[0];
    result.duration = clip.duration;
    result.tracks = clip.tracks.length;
    const mixer = new THREE.AnimationMixer(obj);
    mixer.clipAction(clip).play();
    for (const f of FRAMES) {
      mixer.setTime(f / FPS);
      obj.updateMatrixWorld(true);
      const bones = {};
      obj.traverse((o) => { if (o.isBone) bones[o.name] = o.getWorldPosition(new THREE.Vector3()).toArray(); });
      result.poses[f] = bones;
    }
  }
  out.textContent = JSON.stringify(result);
}, undefined, (e) => { out.textContent = JSON.stringify({error: String(e)}); });
</script></body></html>"#;

/// three.js's FBXLoader finds the clip, of the dance's length, and played with an
/// AnimationMixer poses every bone where FK puts the joint at frames {0, 1, T/2, T − 2} (not
/// the last: a looping clip is at its start again there).
#[test]
fn threejs_fbxloader_plays_the_fbx_animation() {
    let c = clip();
    let dir = tempfile::tempdir().unwrap();
    let fbx = std::fs::read(write(dir.path(), &c)).unwrap();
    let frames = c.trans.len() / 3;
    let check = [0, 1, frames / 2, frames - 2];
    let page = FBX_PAGE
        .replace("IMPORT_MAP", threejs_page::IMPORT_MAP)
        .replace("FRAMES", &format!("{check:?}"))
        .replace("FPS", &c.fps.to_string());
    let r = threejs_page::page_json(threejs_page::serve(page, "/dance.fbx", fbx));
    assert!(r.get("error").is_none(), "FBXLoader failed: {r}");
    assert_eq!(r["clips"], 1, "{r}");
    let duration = r["duration"].as_f64().unwrap();
    let want = (frames - 1) as f64 / f64::from(c.fps);
    assert!(
        (duration - want).abs() < 1e-3,
        "clip of {duration} s, not {want} s"
    );
    let sk = Skeleton::smpl24();
    let mut worst = 0.0f64;
    for f in check {
        let bones = &r["poses"][f.to_string()];
        for (j, name) in sk.names().iter().enumerate() {
            let p = bones[name.as_str()]
                .as_array()
                .unwrap_or_else(|| panic!("FBXLoader has no bone {name}: {bones}"));
            let want = &c.positions[(f * 24 + j) * 3..][..3];
            let err = (0..3)
                .map(|k| (p[k].as_f64().unwrap() - want[k]).abs())
                .fold(0.0, f64::max);
            worst = worst.max(err);
            assert!(
                err < TOL_M,
                "frame {f} joint {name}: three.js {p:?}, FK {want:?}"
            );
        }
    }
    println!(
        "FBXLoader: 1 clip of {duration:.3} s, {} tracks; worst joint error {worst:.1e} m",
        r["tracks"]
    );
}
