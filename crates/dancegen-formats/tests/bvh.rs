use dancegen_formats::bvh::{
    Bvh, BvhErrorKind, BvhReadOptions, BvhWriteOptions, Channel, parse_bvh, parse_bvh_bytes,
    read_bvh, write_bvh, write_bvh_file,
};
use std::path::{Path, PathBuf};

const SALSA: &str = "/work/shared/data/cmu-salsa";

fn salsa_files() -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(SALSA)
        .expect("salsa dir")
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "bvh"))
        .collect();
    v.sort();
    v
}

fn opts() -> BvhReadOptions {
    BvhReadOptions::default()
}

fn kind(text: &str) -> BvhErrorKind {
    match parse_bvh(text, &opts()) {
        Ok(_) => panic!("expected an error for:\n{text}"),
        Err(e) => e.kind,
    }
}

#[test]
fn salsa_files_parse() {
    let files = salsa_files();
    assert_eq!(files.len(), 26, "13 takes × 2 partners");
    for f in &files {
        let b = read_bvh(f, &opts()).unwrap_or_else(|e| panic!("{e}"));
        let name = f.file_name().unwrap().to_str().unwrap();
        // 43 joints with channels (1 ROOT + 42 JOINT) and 14 end sites: 57 nodes in total.
        assert_eq!(b.joints.len(), 43, "{name}");
        assert_eq!(b.joints.iter().filter(|j| j.end_site.is_some()).count(), 14);
        assert_eq!(b.num_channels(), 132, "{name}");
        assert_eq!(b.data.len(), b.frames * 132);
        assert!(
            (b.frame_time - 1.0 / 120.0).abs() < 1e-5,
            "{}",
            b.frame_time
        );
        assert_eq!(b.nominal_fps(), 120.0);
        assert_eq!(b.joints[0].name, "hip");
        assert_eq!(
            b.joints[0].channels,
            [
                Channel::Xposition,
                Channel::Yposition,
                Channel::Zposition,
                Channel::Zrotation,
                Channel::Yrotation,
                Channel::Xrotation
            ]
        );
        assert_eq!(b.euler_order(0).unwrap(), "ZYX");
        for j in 1..b.joints.len() {
            assert_eq!(b.euler_order(j).unwrap(), "ZXY", "{name} joint {j}");
            assert!(b.position(j, 0).is_none());
        }
        assert!(b.position(0, 0).is_some());
        assert_eq!(b.channel_offset(1), Some(6));
        assert_eq!(b.channel_offset(42), Some(129));
        assert!(b.frame(b.frames).is_none());
        b.validate().unwrap();
    }
    // Partners of a take have equal frame counts.
    for f in files
        .iter()
        .filter(|f| f.to_str().unwrap().contains("/60_"))
    {
        let g = PathBuf::from(f.to_str().unwrap().replace("/60_", "/61_"));
        let a = read_bvh(f, &opts()).unwrap();
        let b = read_bvh(&g, &opts()).unwrap();
        assert_eq!(a.frames, b.frames, "{f:?} vs {g:?}");
        let names_a: Vec<_> = a.joints.iter().map(|j| &j.name).collect();
        let names_b: Vec<_> = b.joints.iter().map(|j| &j.name).collect();
        assert_eq!(names_a, names_b);
    }
}

#[test]
fn salsa_print_skeleton() {
    let b = read_bvh(Path::new(SALSA).join("60_01_scaled.bvh"), &opts()).unwrap();
    for (i, j) in b.joints.iter().enumerate() {
        println!(
            "{i:2} {:12} parent={:?} offset={:?} end={:?} {:?}",
            j.name,
            j.parent,
            j.offset,
            j.end_site,
            b.euler_order(i).unwrap()
        );
    }
    println!("root pos f0 {:?}", b.position(0, 0));
}

fn assert_close(a: &Bvh, b: &Bvh, tol: f64) {
    assert_eq!(a.joints.len(), b.joints.len());
    for (x, y) in a.joints.iter().zip(&b.joints) {
        assert_eq!(x.name, y.name);
        assert_eq!(x.parent, y.parent);
        assert_eq!(x.channels, y.channels);
        for k in 0..3 {
            assert!((x.offset[k] - y.offset[k]).abs() <= tol);
        }
        assert_eq!(x.end_site.is_some(), y.end_site.is_some());
        if let (Some(e), Some(f)) = (x.end_site, y.end_site) {
            for k in 0..3 {
                assert!((e[k] - f[k]).abs() <= tol);
            }
        }
    }
    assert_eq!(a.frames, b.frames);
    assert_eq!(a.frame_time, b.frame_time);
    assert_eq!(a.data.len(), b.data.len());
    let worst = a
        .data
        .iter()
        .zip(&b.data)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max);
    assert!(worst <= tol, "max diff {worst}");
}

#[test]
fn salsa_round_trip() {
    for f in salsa_files() {
        let a = read_bvh(&f, &opts()).unwrap();
        let text = write_bvh(&a, &BvhWriteOptions::default()).unwrap();
        let b = parse_bvh(&text, &opts()).unwrap();
        assert_close(&a, &b, 1e-6);
        // The source files use 6 decimals, so the default writer reproduces values exactly.
        assert_eq!(a, b);
        // Lossless mode.
        let text = write_bvh(&a, &BvhWriteOptions { precision: None }).unwrap();
        assert_eq!(parse_bvh(&text, &opts()).unwrap(), a);
    }
}

#[test]
fn write_file_and_scale() {
    let dir = tempfile::tempdir().unwrap();
    let a = read_bvh(Path::new(SALSA).join("61_10_scaled.bvh"), &opts()).unwrap();
    let out = dir.path().join("out.bvh");
    write_bvh_file(&out, &a, &BvhWriteOptions::default()).unwrap();
    assert_eq!(read_bvh(&out, &opts()).unwrap(), a);

    let s = read_bvh(
        &out,
        &BvhReadOptions {
            scale: 2.0,
            ..opts()
        },
    )
    .unwrap();
    assert_eq!(s.joints[3].offset[1], a.joints[3].offset[1] * 2.0);
    assert_eq!(
        s.joints[5].end_site.unwrap()[0],
        a.joints[5].end_site.unwrap()[0] * 2.0
    );
    assert_eq!(
        s.position(0, 7).unwrap()[1],
        a.position(0, 7).unwrap()[1] * 2.0
    );
    assert_eq!(s.rotation_xyz(0, 7), a.rotation_xyz(0, 7));
    assert_eq!(s.rotation_xyz(9, 7), a.rotation_xyz(9, 7));
}

const ODD: &str = "HIERARCHY\r\n\
ROOT Hips {\r\n\
\tOFFSET 1e-3\t-2.5E+1 +0.5\r\n\
  CHANNELS 3 Yrotation Xposition zrotation\r\n\
\tJOINT Left Upper Leg\r\n\
\t{\r\n\
\t\tOFFSET .5 0 0\r\n\
\t\tCHANNELS 6 Xrotation Zposition Yrotation Yposition Zrotation Xposition\r\n\
\t\tEnd Site\r\n\
\t\t{\r\n\
\t\t\tOFFSET 0 -1 0\r\n\
\t\t}\r\n\
\t}\r\n\
\tJOINT nochan\r\n\
\t{\r\n\
\t\tOFFSET 0 1 0\r\n\
\t\tCHANNELS 0\r\n\
\t\tJOINT leaf\r\n\
\t\t{\r\n\
\t\t\tOFFSET 0 2 0\r\n\
\t\t\tCHANNELS 2 Xrotation Yrotation\r\n\
\t\t}\r\n\
\t}\r\n\
}\r\n\
MOTION\r\n\
Frames:\t2\r\n\
Frame Time:   0.0333333\r\n\
10 1 20 1 2 3 4 5 6 7 8\r\n\
\r\n\
-1e1 -1 -2e+1 -1 -2 -3 -4 -5 -6 -7 -8   \r\n\
\r\n";

#[test]
fn unusual_channels() {
    let b = parse_bvh(ODD, &opts()).unwrap();
    assert_eq!(b.joints.len(), 4);
    assert_eq!(b.joints[0].offset, [1e-3, -25.0, 0.5]);
    assert_eq!(b.joints[1].name, "Left Upper Leg");
    assert_eq!(b.joints[1].parent, Some(0));
    assert_eq!(b.joints[1].end_site, Some([0.0, -1.0, 0.0]));
    assert_eq!(b.joints[2].parent, Some(0));
    assert_eq!(b.joints[3].parent, Some(2));
    assert_eq!(b.children(0), vec![1, 2]);
    assert_eq!(b.num_channels(), 11);
    assert_eq!(b.frames, 2);
    assert!((b.fps() - 30.0).abs() < 1e-3);
    assert_eq!(b.nominal_fps(), 30.0);
    assert_eq!(b.euler_order(0).unwrap(), "YZ");
    assert_eq!(b.euler_order(1).unwrap(), "XYZ");
    assert_eq!(b.euler_order(2).unwrap(), "");
    assert_eq!(b.euler_order(3).unwrap(), "XY");
    assert_eq!(b.euler_order(4), None);
    assert_eq!(b.channel_offset(0), Some(0));
    assert_eq!(b.channel_offset(1), Some(3));
    assert_eq!(b.channel_offset(2), Some(9));
    assert_eq!(b.channel_offset(3), Some(9));
    assert_eq!(b.channel_offset(4), None);
    // Root: Yrotation=10 Xposition=1 Zrotation=20.
    assert_eq!(b.position(0, 0), Some([1.0, 0.0, 0.0]));
    assert_eq!(b.rotation_xyz(0, 0), Some([0.0, 10.0, 20.0]));
    // Joint 1: Xrot=1 Zpos=2 Yrot=3 Ypos=4 Zrot=5 Xpos=6.
    assert_eq!(b.position(1, 0), Some([6.0, 4.0, 2.0]));
    assert_eq!(b.rotation_xyz(1, 0), Some([1.0, 3.0, 5.0]));
    assert_eq!(b.position(1, 1), Some([-6.0, -4.0, -2.0]));
    assert_eq!(b.rotation_xyz(2, 0), None);
    assert_eq!(b.rotation_xyz(3, 1), Some([-7.0, -8.0, 0.0]));
    assert_eq!(b.channel_value(1, 1, Channel::Zposition), Some(-2.0));
    assert_eq!(b.channel_value(1, 2, Channel::Zposition), None);
    assert_eq!(b.position(0, 2), None);

    // Scale touches positions and offsets only.
    let s = parse_bvh(
        ODD,
        &BvhReadOptions {
            scale: 10.0,
            ..opts()
        },
    )
    .unwrap();
    assert_eq!(s.position(1, 0), Some([60.0, 40.0, 20.0]));
    assert_eq!(s.rotation_xyz(1, 0), Some([1.0, 3.0, 5.0]));
    assert_eq!(s.joints[1].offset, [5.0, 0.0, 0.0]);
    assert_eq!(s.joints[1].end_site, Some([0.0, -10.0, 0.0]));

    for precision in [Some(6), None] {
        let text = write_bvh(&b, &BvhWriteOptions { precision }).unwrap();
        let c = parse_bvh(&text, &opts()).unwrap();
        assert_eq!(b, c, "{text}");
    }
    let text = write_bvh(&b, &BvhWriteOptions::default()).unwrap();
    println!("{text}");
    assert!(text.starts_with("HIERARCHY\nROOT Hips\n{\n\tOFFSET 0.001000 -25.000000 0.500000\n"));
    assert!(
        text.contains("\t\tEnd Site\n\t\t{\n\t\t\tOFFSET 0.000000 -1.000000 0.000000\n\t\t}\n")
    );
    assert!(text.contains("MOTION\nFrames: 2\nFrame Time: 0.0333333\n"));
}

#[test]
fn lossless_writer_precision() {
    let mut b = parse_bvh(ODD, &opts()).unwrap();
    b.data[0] = 1.0 / 3.0;
    b.data[1] = 1e-9;
    b.joints[0].offset[0] = 123456.789012345;
    let text = write_bvh(&b, &BvhWriteOptions { precision: None }).unwrap();
    assert_eq!(parse_bvh(&text, &opts()).unwrap(), b);
}

const HEAD: &str =
    "HIERARCHY\nROOT a\n{\n OFFSET 0 0 0\n CHANNELS 3 Xposition Yposition Zposition\n}\n";

#[test]
fn zero_frames_is_rest_pose() {
    let b = parse_bvh(
        &format!("{HEAD}MOTION\nFrames: 0\nFrame Time: 0.01\n"),
        &opts(),
    )
    .unwrap();
    assert_eq!(b.frames, 0);
    assert!(b.data.is_empty());
    let b = parse_bvh(
        &format!("{HEAD}MOTION\nFrames: 0\nFrame Time: 0\n"),
        &opts(),
    )
    .unwrap();
    assert_eq!(b.fps(), 0.0);
    let text = write_bvh(&b, &BvhWriteOptions::default()).unwrap();
    assert_eq!(parse_bvh(&text, &opts()).unwrap(), b);
}

#[test]
fn errors() {
    use BvhErrorKind as K;
    let motion = |frames: &str, lines: &str| {
        format!("{HEAD}MOTION\nFrames: {frames}\nFrame Time: 0.01\n{lines}")
    };
    // Truncated: fewer frame lines than Frames.
    assert!(matches!(
        kind(&motion("3", "1 2 3\n4 5 6\n")),
        K::Truncated {
            expected: 3,
            found: 2,
            ..
        }
    ));
    // Too many frame lines.
    assert!(matches!(
        kind(&motion("1", "1 2 3\n4 5 6\n")),
        K::TooManyFrames {
            line: 11,
            expected: 1
        }
    ));
    // Wrong value count, with the message format.
    let k = kind(&motion("2", "1 2 3\n4 5\n"));
    assert_eq!(
        k,
        K::WrongValueCount {
            line: 11,
            expected: 3,
            found: 2
        }
    );
    assert_eq!(k.to_string(), "line 11: expected 3 values, found 2");
    assert!(matches!(
        kind(&motion("1", "1 2 3 4\n")),
        K::WrongValueCount { found: 4, .. }
    ));
    // NaN / inf.
    for bad in ["NaN", "inf", "-infinity", "1e999"] {
        assert!(
            matches!(
                kind(&motion("1", &format!("1 {bad} 3\n"))),
                K::NonFinite { line: 10, .. }
            ),
            "{bad}"
        );
    }
    assert!(matches!(
        kind(&HEAD.replace("OFFSET 0 0 0", "OFFSET 0 nan 0")),
        K::NonFinite { line: 4, .. }
    ));
    assert!(matches!(
        kind(&motion("1", "1 x 3\n")),
        K::BadNumber { line: 10, .. }
    ));
    // Unknown channel.
    assert_eq!(
        kind(&motion("0", "").replace("Zposition", "Wrotation")),
        K::UnknownChannel {
            line: 5,
            name: "Wrotation".into()
        }
    );
    assert!(matches!(
        kind(&motion("0", "").replace("Zposition", "Xposition")),
        K::DuplicateChannel { line: 5, .. }
    ));
    assert!(matches!(
        kind(&motion("0", "").replace("CHANNELS 3", "CHANNELS 7")),
        K::BadChannelCount { .. }
    ));
    // Missing MOTION.
    assert_eq!(kind(HEAD), K::MissingMotion);
    assert!(matches!(
        kind(&format!("{HEAD}MOTION\n")),
        K::UnexpectedEof { .. }
    ));
    assert!(matches!(
        kind(&format!("{HEAD}MOTION\nFrames: 1\n")),
        K::UnexpectedEof { .. }
    ));
    assert!(matches!(
        kind(&format!("{HEAD}MOTION\nFrames: -1\nFrame Time: 0.01\n")),
        K::BadNumber { line: 8, .. }
    ));
    assert!(matches!(
        kind(&motion("1", "1 2 3\n").replace("0.01", "-0.01")),
        K::BadFrameTime { line: 9, .. }
    ));
    // Unbalanced braces.
    let extra_close = HEAD.replace("}\n", "}\n}\n");
    assert!(matches!(
        kind(&format!(
            "{extra_close}MOTION\nFrames: 0\nFrame Time: 0.01\n"
        )),
        K::UnbalancedBraces { line: 7, .. }
    ));
    let missing_close = HEAD.replace("}\n", "");
    assert!(matches!(
        kind(&format!(
            "{missing_close}MOTION\nFrames: 0\nFrame Time: 0.01\n"
        )),
        K::UnbalancedBraces { line: 6, .. }
    ));
    assert!(matches!(kind(&missing_close), K::UnbalancedBraces { .. }));
    // Multiple roots.
    assert_eq!(
        kind(&format!("{HEAD}{}", &HEAD["HIERARCHY\n".len()..])),
        K::MultipleRoots { line: 7 }
    );
    // No root / empty / garbage.
    assert_eq!(kind("HIERARCHY\nMOTION\n"), K::NoRoot);
    assert!(matches!(kind(""), K::UnexpectedEof { .. }));
    assert!(matches!(kind("hello"), K::Unexpected { line: 1, .. }));
    assert!(matches!(
        kind("HIERARCHY\nROOT a\n{\nCHANNELS 0\n}\nMOTION\nFrames: 0\nFrame Time: 1\n"),
        K::MissingOffset { line: 2, .. }
    ));
    assert!(matches!(
        kind("HIERARCHY\nROOT\n{\n"),
        K::Unexpected {
            line: 2,
            expected: "joint name",
            ..
        }
    ));
    // Non-UTF-8, with line number.
    let mut bytes = motion("1", "1 2 3\n").into_bytes();
    bytes.extend_from_slice(b"\xff\xfe\n");
    let e = parse_bvh_bytes(&bytes, &opts()).unwrap_err();
    assert_eq!(e.kind, K::NonUtf8 { line: 11 });
    // Errors from files carry the path.
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("bad.bvh");
    std::fs::write(&p, motion("2", "1 2 3\n4 5\n")).unwrap();
    let e = read_bvh(&p, &opts()).unwrap_err();
    assert_eq!(e.path.as_deref(), Some(p.as_path()));
    let msg = e.to_string();
    assert!(
        msg.ends_with("bad.bvh: line 11: expected 3 values, found 2"),
        "{msg}"
    );
    let e = read_bvh(dir.path().join("missing.bvh"), &opts()).unwrap_err();
    assert!(matches!(e.kind, K::Io(_)));
    // Invalid scale.
    assert!(matches!(
        parse_bvh(
            HEAD,
            &BvhReadOptions {
                scale: f64::NAN,
                ..opts()
            }
        )
        .unwrap_err()
        .kind,
        K::Invalid(_)
    ));
}

#[test]
fn salsa_error_line_numbers() {
    // Drop one value from line 812 of a real file.
    let text = std::fs::read_to_string(Path::new(SALSA).join("60_01_scaled.bvh")).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let l = &mut lines[811];
    let cut = l.trim_end().rfind(' ').unwrap();
    l.truncate(cut);
    let bad = lines.join("\n");
    let e = parse_bvh(&bad, &opts()).unwrap_err();
    assert_eq!(e.to_string(), "line 812: expected 132 values, found 131");
    // Truncated file.
    let cut = &text[..text.len() / 2];
    let cut = &cut[..cut.rfind('\n').unwrap() + 1];
    assert!(matches!(
        parse_bvh(cut, &opts()).unwrap_err().kind,
        BvhErrorKind::Truncated { expected: 2242, .. }
    ));
}

#[test]
fn validate_rejects_bad_structures() {
    let mut b = parse_bvh(ODD, &opts()).unwrap();
    b.data.pop();
    assert!(write_bvh(&b, &BvhWriteOptions::default()).is_err());
    let mut b = parse_bvh(ODD, &opts()).unwrap();
    b.joints[3].parent = Some(1); // not depth-first any more
    assert!(b.validate().is_err());
    let mut b = parse_bvh(ODD, &opts()).unwrap();
    b.joints[2].parent = Some(99);
    assert!(b.validate().is_err());
    let mut b = parse_bvh(ODD, &opts()).unwrap();
    b.data[3] = f64::NAN;
    assert!(b.validate().is_err());
}

/// Never panics on mangled input: every prefix and many byte edits of a small file.
#[test]
fn no_panic_on_mangled_input() {
    let src = ODD.as_bytes();
    for n in 0..src.len() {
        let _ = parse_bvh_bytes(&src[..n], &opts());
    }
    let mut state = 0x9e3779b97f4a7c15u64;
    let mut rnd = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    let alphabet = b"{} \n\t\r0123456789.-eE+NaJOINTEndSiteMOTION:\xff";
    for _ in 0..20000 {
        let mut v = src.to_vec();
        for _ in 0..(1 + rnd() % 4) {
            let i = (rnd() as usize) % v.len();
            let c = alphabet[(rnd() as usize) % alphabet.len()];
            match rnd() % 3 {
                0 => v[i] = c,
                1 => v.insert(i, c),
                _ => {
                    v.remove(i);
                }
            }
        }
        if let Ok(b) = parse_bvh_bytes(&v, &opts()) {
            // Whatever parses must write and re-parse identically.
            let t = write_bvh(&b, &BvhWriteOptions { precision: None }).unwrap();
            assert_eq!(parse_bvh(&t, &opts()).unwrap(), b);
        }
    }
    // Deep nesting does not overflow the stack.
    let mut deep = String::from("HIERARCHY\nROOT r\n{\nOFFSET 0 0 0\n");
    for i in 0..100_000 {
        deep.push_str(&format!("JOINT j{i}\n{{\nOFFSET 0 0 0\n"));
    }
    let _ = parse_bvh(&deep, &opts());
    // A huge Frames: count does not allocate up front.
    let _ = parse_bvh(
        &format!("{HEAD}MOTION\nFrames: 18446744073709551615\nFrame Time: 0.01\n1 2 3\n"),
        &opts(),
    );
}

#[test]
#[ignore = "throughput measurement; run with --release -- --ignored --nocapture"]
fn salsa_parse_throughput() {
    let files = salsa_files();
    let texts: Vec<String> = files
        .iter()
        .map(|f| std::fs::read_to_string(f).unwrap())
        .collect();
    let bytes: usize = texts.iter().map(|t| t.len()).sum();
    let reps = 3;
    let t0 = std::time::Instant::now();
    let mut frames = 0usize;
    for _ in 0..reps {
        for t in &texts {
            frames += parse_bvh(t, &opts()).unwrap().frames;
        }
    }
    let s = t0.elapsed().as_secs_f64();
    println!(
        "parse: {} files, {:.1} MB, {} frames x{reps}: {:.3} s, {:.1} MB/s, {:.0} frames/s",
        files.len(),
        bytes as f64 / 1e6,
        frames / reps,
        s,
        (bytes * reps) as f64 / 1e6 / s,
        frames as f64 / s
    );
    let parsed: Vec<Bvh> = texts
        .iter()
        .map(|t| parse_bvh(t, &opts()).unwrap())
        .collect();
    let t0 = std::time::Instant::now();
    let mut out = 0usize;
    for b in &parsed {
        out += write_bvh(b, &BvhWriteOptions::default()).unwrap().len();
    }
    let s = t0.elapsed().as_secs_f64();
    println!(
        "write: {:.1} MB in {:.3} s, {:.1} MB/s",
        out as f64 / 1e6,
        s,
        out as f64 / 1e6 / s
    );
}

/// A header's rate can be wrong (the CMU salsa BVHs say 120 fps for a 60 fps capture) or
/// missing: `BvhReadOptions::frame_time` replaces it; without it, a zero or missing frame time
/// is an error with its line.
#[test]
fn a_given_frame_time_replaces_a_wrong_zero_or_missing_header() {
    use BvhErrorKind as K;
    let with_time = |t: &str| format!("{HEAD}MOTION\nFrames: 2\nFrame Time: {t}\n1 2 3\n4 5 6\n");
    let sixty = BvhReadOptions {
        frame_time: Some(1.0 / 60.0),
        ..opts()
    };
    // Wrong header: the frames stay, their times change.
    let header = parse_bvh(&with_time("0.008333"), &opts()).unwrap();
    let given = parse_bvh(&with_time("0.008333"), &sixty).unwrap();
    assert_eq!(
        (header.data.clone(), header.frames),
        (given.data.clone(), given.frames)
    );
    assert_eq!(given.nominal_fps(), 60.0);
    // Zero in the header: an error at its line, unless a frame time is given.
    assert!(matches!(
        kind(&with_time("0")),
        K::BadFrameTime { line: 9, .. }
    ));
    assert_eq!(parse_bvh(&with_time("0"), &sixty).unwrap().data, given.data);
    // No `Frame Time:` line at all.
    let missing = format!("{HEAD}MOTION\nFrames: 2\n1 2 3\n4 5 6\n");
    assert!(matches!(kind(&missing), K::MissingFrameTime { line: 9 }));
    assert_eq!(parse_bvh(&missing, &sixty).unwrap().data, given.data);
    // A given frame time must be a time.
    for bad in [0.0, -0.01, f64::NAN, f64::INFINITY] {
        let o = BvhReadOptions {
            frame_time: Some(bad),
            ..opts()
        };
        assert!(parse_bvh(&with_time("0.01"), &o).is_err(), "{bad}");
    }
}
