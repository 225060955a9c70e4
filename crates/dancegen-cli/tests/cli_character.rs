//! `generate --character`: the user's humanoid glTF dances the dance; characters that cannot
//! are clear errors naming the file and what is missing. (The retargeting itself is checked
//! in `dancegen-character`'s `tests/character_retarget.rs`; Blender imports the result in
//! `cli_blender.rs`.)

mod common;

use common::{dancegen, ok, shared, stderr};

fn robot() -> String {
    shared()
        .join("data/holistic/three-js-robot-expressive/RobotExpressive.glb")
        .display()
        .to_string()
}

fn glb_json(bytes: &[u8]) -> serde_json::Value {
    assert_eq!(&bytes[..4], b"glTF");
    let len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    serde_json::from_slice(&bytes[20..20 + len]).unwrap()
}

#[test]
fn the_character_dances_in_the_glb_and_keeps_its_meshes() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("robot.glb");
    let npy = dir.path().join("robot.npy");
    ok(&dancegen(&[
        "generate",
        "-q",
        "--end",
        "6",
        "--character",
        &robot(),
        "-o",
        out.to_str().unwrap(),
        "-o",
        npy.to_str().unwrap(),
    ]));
    let before = glb_json(&std::fs::read(robot()).unwrap());
    let after = glb_json(&std::fs::read(&out).unwrap());
    // The robot's own scene: every node, mesh, material and skin is still there.
    for key in ["nodes", "meshes", "materials", "skins"] {
        assert_eq!(
            before[key].as_array().map(Vec::len),
            after[key].as_array().map(Vec::len),
            "{key}"
        );
    }
    // Its 14 clips are replaced by the dance: 180 frames at 30 fps.
    let anims = after["animations"].as_array().unwrap();
    assert_eq!(anims.len(), 1);
    assert_eq!(anims[0]["name"], "dance");
    let sampler = &anims[0]["samplers"][0];
    let input = &after["accessors"][sampler["input"].as_u64().unwrap() as usize];
    assert_eq!(input["count"], 180);
    let max = input["max"][0].as_f64().unwrap();
    assert!((max - 179.0 / 30.0).abs() < 1e-4, "last key at {max} s");
    // The .npy is the dance itself, unchanged by the character.
    let a = dancegen_io::read_npy(&npy).unwrap();
    assert_eq!(a.shape, [180, 24, 3]);
}

#[test]
fn characters_that_cannot_dance_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.glb");
    let run = |character: &str, outputs: &[&str]| {
        let mut args = vec!["generate", "--end", "5", "--character", character];
        for o in outputs {
            args.extend(["-o", o]);
        }
        let o = dancegen(&args);
        assert!(!o.status.success());
        assert!(!out.exists(), "a failed run must leave no file");
        stderr(&o)
    };
    let out_s = out.to_str().unwrap();

    // A glTF without a skin: a single triangle.
    let plain = dir.path().join("plain.gltf");
    std::fs::write(
        &plain,
        r#"{"asset": {"version": "2.0"}, "scenes": [{"nodes": [0]}], "nodes": [{"name": "box"}]}"#,
    )
    .unwrap();
    let e = run(plain.to_str().unwrap(), &[out_s]);
    assert!(e.contains("plain.gltf") && e.contains("skin"), "{e}");

    let e = run("/nonexistent/hero.vrm", &[out_s]);
    assert!(e.contains("hero.vrm"), "{e}");

    let notes = dir.path().join("notes.glb");
    std::fs::write(&notes, b"not a model").unwrap();
    let e = run(notes.to_str().unwrap(), &[out_s]);
    assert!(e.contains("notes.glb") && e.contains("not a glTF"), "{e}");

    // A skinned figure whose bones are not a humanoid's: our own capsule figure with its
    // joints renamed bone0, bone1, …
    let figure = dir.path().join("figure.glb");
    ok(&dancegen(&[
        "generate",
        "-q",
        "--end",
        "5",
        "-o",
        figure.to_str().unwrap(),
    ]));
    let anonymous = dir.path().join("anonymous.glb");
    rewrite_glb_json(&figure, &anonymous, |json| {
        for (i, node) in json["nodes"].as_array_mut().unwrap().iter_mut().enumerate() {
            node["name"] = format!("bone{i}").into();
        }
    });
    let e = run(anonymous.to_str().unwrap(), &[out_s]);
    assert!(e.contains("anonymous.glb") && e.contains("bone3"), "{e}");

    // Our own figure, with its SMPL names, is a character too.
    let ours = dir.path().join("ours.glb");
    ok(&dancegen(&[
        "generate",
        "-q",
        "--end",
        "5",
        "--character",
        figure.to_str().unwrap(),
        "-o",
        ours.to_str().unwrap(),
    ]));

    // Several dancers cannot be one character: refused before any generation.
    let leader = shared().join("data/cmu-salsa/61_13_scaled.bvh");
    let o = dancegen(&[
        "generate",
        "--leader",
        leader.to_str().unwrap(),
        "--character",
        &robot(),
        "-o",
        out_s,
    ]);
    assert!(
        !o.status.success() && stderr(&o).contains("--follower-only"),
        "{}",
        stderr(&o)
    );
    assert!(!out.exists());

    let bvh = dir.path().join("x.bvh");
    let e = run(&robot(), &[bvh.to_str().unwrap()]);
    assert!(e.contains("add -o NAME.glb"), "{e}");

    // A joint 20 km from the origin in the rest pose is not a character standing on a floor.
    let far = dir.path().join("far.glb");
    rewrite_glb_json(&figure, &far, |json| {
        let nodes = json["nodes"].as_array_mut().unwrap();
        let wrist = nodes.iter_mut().find(|n| n["name"] == "lwrist").unwrap();
        wrist["translation"] = serde_json::json!([0.0, 0.0, 2.0e4]);
    });
    let e = run(far.to_str().unwrap(), &[out_s]);
    assert!(
        e.contains("far.glb") && e.contains("lwrist") && e.contains("MAX_JOINT_DISTANCE_M"),
        "{e}"
    );
}

/// Writes `from`'s GLB to `to` with its JSON chunk changed by `edit` (the binary chunk kept).
fn rewrite_glb_json(
    from: &std::path::Path,
    to: &std::path::Path,
    edit: impl FnOnce(&mut serde_json::Value),
) {
    let bytes = std::fs::read(from).unwrap();
    let mut json = glb_json(&bytes);
    edit(&mut json);
    let json_len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let bin = &bytes[20 + json_len..];
    let mut text = serde_json::to_vec(&json).unwrap();
    while !text.len().is_multiple_of(4) {
        text.push(b' ');
    }
    let mut glb = Vec::new();
    glb.extend_from_slice(b"glTF");
    glb.extend_from_slice(&2u32.to_le_bytes());
    glb.extend_from_slice(&((12 + 8 + text.len() + bin.len()) as u32).to_le_bytes());
    glb.extend_from_slice(&(text.len() as u32).to_le_bytes());
    glb.extend_from_slice(b"JSON");
    glb.extend_from_slice(&text);
    glb.extend_from_slice(bin);
    std::fs::write(to, glb).unwrap();
}
