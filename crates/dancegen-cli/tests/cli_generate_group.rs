//! The `generate --system group` contract with the bundled group model (issue #17): `.npy`
//! `(N, T, 24, 3)` world joints (metres, Y-up, 30 fps), one `.bvh` per dancer, a `.json` with
//! the root trajectories and the orders, formation control, and clear errors.

mod common;

use common::*;

fn song() -> String {
    shared()
        .join("data/music/sectoid/feelings.ogg")
        .to_str()
        .unwrap()
        .to_string()
}

fn json(path: &std::path::Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

#[test]
fn a_group_dance_writes_every_dancer_and_its_stage_record() {
    let dir = tempfile::tempdir().unwrap();
    let out = |n: &str| dir.path().join(n).to_str().unwrap().to_string();
    let o = dancegen(&[
        "-q",
        "generate",
        &song(),
        "--system",
        "group",
        "--dancers",
        "3",
        "--start",
        "10",
        "--end",
        "16",
        "--steps",
        "4",
        "--seed",
        "3",
        "-o",
        &out("g.npy"),
        "-o",
        &out("g.json"),
        "-o",
        &out("g.bvh"),
        "-o",
        &out("g.glb"),
    ]);
    ok(&o);
    let a = dancegen_io::read_npy(&dir.path().join("g.npy")).unwrap();
    assert_eq!(a.shape, vec![3, 180, 24, 3]);
    assert!(a.data.iter().all(|v| v.is_finite()));
    for k in 0..3 {
        assert!(dir.path().join(format!("g_{k}.bvh")).is_file(), "g_{k}.bvh");
    }
    assert!(!dir.path().join("g.bvh").exists());
    assert!(!dir.path().join("g_3.bvh").exists());
    assert!(dir.path().join("g.glb").is_file());
    let j = json(&dir.path().join("g.json"));
    let traj = j["trajectories"].as_array().unwrap();
    assert_eq!(traj.len(), 3);
    for (k, tr) in traj.iter().enumerate() {
        let tr = tr.as_array().unwrap();
        assert_eq!(tr.len(), 180);
        for (t, p) in tr.iter().enumerate() {
            let root = (k * 180 + t) * 72;
            assert!((p[0].as_f64().unwrap() - a.data[root]).abs() < 1e-5);
            assert!((p[1].as_f64().unwrap() - a.data[root + 2]).abs() < 1e-5);
        }
    }
    let order = |key: &str, t: usize| {
        let got: Vec<u64> = j[key]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_u64().unwrap())
            .collect();
        let mut want: Vec<u64> = (0..3).collect();
        want.sort_by(|&x, &y| {
            a.data[(x as usize * 180 + t) * 72]
                .total_cmp(&a.data[(y as usize * 180 + t) * 72])
                .then(x.cmp(&y))
        });
        assert_eq!(got, want, "{key}");
    };
    order("start_order", 0);
    order("end_order", 179);
    // Same seed, same dance.
    let o = dancegen(&[
        "-q",
        "generate",
        &song(),
        "--system",
        "group",
        "--dancers",
        "3",
        "--start",
        "10",
        "--end",
        "16",
        "--steps",
        "4",
        "--seed",
        "3",
        "-o",
        &out("h.npy"),
    ]);
    ok(&o);
    assert_eq!(
        std::fs::read(dir.path().join("g.npy")).unwrap(),
        std::fs::read(dir.path().join("h.npy")).unwrap()
    );
}

#[test]
fn a_formation_is_followed() {
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("formation.json");
    // Two dancers drift apart and forward over 5 s, a third is free.
    std::fs::write(
        &f,
        r#"{"keyframes": [
            {"t": 20.0, "positions": [[-1.0, 0.0], [1.0, 0.0], null]},
            {"t": 25.0, "positions": [[-1.5, 1.0], [1.5, 1.0], null]}
        ]}"#,
    )
    .unwrap();
    let npy = dir.path().join("f.npy");
    let js = dir.path().join("f.json");
    let o = dancegen(&[
        "-q",
        "generate",
        &song(),
        "--system",
        "group",
        "--dancers",
        "3",
        "--start",
        "20",
        "--end",
        "25",
        "--steps",
        "4",
        "--formation",
        f.to_str().unwrap(),
        "-o",
        npy.to_str().unwrap(),
        "-o",
        js.to_str().unwrap(),
    ]);
    ok(&o);
    let a = dancegen_io::read_npy(&npy).unwrap();
    let t = a.shape[1];
    assert_eq!(t, 150);
    let root = |d: usize, f: usize| [a.data[(d * t + f) * 72], a.data[(d * t + f) * 72 + 2]];
    for (d, want) in [(0usize, [-1.0, 0.0]), (1, [1.0, 0.0])] {
        let p = root(d, 0);
        assert!(
            (p[0] - want[0]).hypot(p[1] - want[1]) < 0.15,
            "dancer {d} at the start: {p:?}"
        );
    }
    for (d, want) in [(0usize, [-1.5, 1.0]), (1, [1.5, 1.0])] {
        let p = root(d, t - 1);
        assert!(
            (p[0] - want[0]).hypot(p[1] - want[1]) < 0.15,
            "dancer {d} at the end: {p:?}"
        );
    }
    let j = json(&js);
    assert!(j["trajectory_error_mean_m"].as_f64().unwrap() < 0.15);
    assert!(j["requested"][2][0].is_null(), "the third dancer is free");
}

#[test]
fn bad_group_requests_say_what_is_wrong() {
    let dir = tempfile::tempdir().unwrap();
    let write = |name: &str, text: &str| {
        let p = dir.path().join(name);
        std::fs::write(&p, text).unwrap();
        p.to_str().unwrap().to_string()
    };
    let out = dir.path().join("x.npy");
    let out = out.to_str().unwrap();
    let song = song();
    let run = |extra: &[&str]| {
        let mut args = vec!["-q", "generate", &song, "--system", "group", "-o", out];
        args.extend_from_slice(extra);
        let o = dancegen(&args);
        assert!(!o.status.success(), "{extra:?} should fail");
        assert!(!std::path::Path::new(out).exists());
        stderr(&o)
    };
    assert!(run(&["--dancers", "6"]).contains("2 to 5"));
    assert!(run(&["--dancers", "1"]).contains("2 to 5"));
    assert!(run(&[]).contains("--dancers"));
    let three = write(
        "three.json",
        r#"{"keyframes": [{"t": 1, "positions": [[0, 0], [1, 0], [2, 0]]}]}"#,
    );
    let e = run(&["--dancers", "2", "--formation", &three]);
    assert!(e.contains("three.json"), "{e}");
    let late = write(
        "late.json",
        r#"{"keyframes": [{"t": 9999, "positions": [[0, 0], [1, 0]]}]}"#,
    );
    let e = run(&["--dancers", "2", "--formation", &late]);
    assert!(e.contains("late.json"), "{e}");
    let close = write(
        "close.json",
        r#"{"keyframes": [{"t": 1, "positions": [[0, 0], [0.2, 0]]}]}"#,
    );
    let e = run(&["--dancers", "2", "--formation", &close]);
    assert!(e.contains("close.json") && e.contains("0.45"), "{e}");
    let nan = write(
        "nan.json",
        r#"{"keyframes": [{"t": 1, "positions": [[NaN, 0], [1, 0]]}]}"#,
    );
    assert!(run(&["--dancers", "2", "--formation", &nan]).contains("nan.json"));
    let e = run(&["--dancers", "2", "--start", "0", "--end", "1"]);
    assert!(e.contains("at least"), "{e}");
    let o = dancegen(&["-q", "generate", &song, "--formation", &close, "-o", out]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("--system group"));
}
