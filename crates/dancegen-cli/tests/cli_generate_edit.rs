//! The editing contract of `generate` (issue 44) through the binary: an `.npz` it wrote
//! records what made it, so `--edit DANCE.npz --regenerate A-B` needs no song; the frames
//! outside the range come back unchanged; `--continue-from` starts with the motion's last
//! second; and every bad edit is refused with the flag or file named and no output written.

mod common;

use common::*;

fn song() -> String {
    shared()
        .join("data/music/sectoid/feelings.ogg")
        .to_str()
        .unwrap()
        .to_string()
}

fn npy(path: &std::path::Path) -> (Vec<usize>, Vec<f64>) {
    let a = dancegen_io::read_npy(path).unwrap();
    (a.shape, a.data)
}

fn refused(args: &[&str], words: &[&str]) {
    let o = dancegen(args);
    assert!(!o.status.success(), "{args:?} succeeded");
    let e = stderr(&o);
    for w in words {
        assert!(e.contains(w), "{args:?}: {w:?} not in {e}");
    }
}

#[test]
fn an_edit_keeps_the_rest_of_the_dance_and_reads_the_song_from_its_record() {
    let dir = tempfile::tempdir().unwrap();
    let p = |n: &str| dir.path().join(n).to_str().unwrap().to_string();
    let s = song();
    ok(&dancegen(&[
        "-q",
        "generate",
        &s,
        "--start",
        "60",
        "--end",
        "72",
        "--seed",
        "0",
        "-o",
        &p("base.npz"),
        "-o",
        &p("base.npy"),
    ]));
    // No song, no --start: both come from the record.
    ok(&dancegen(&[
        "-q",
        "generate",
        "--edit",
        &p("base.npz"),
        "--regenerate",
        "4-7",
        "--seed",
        "5",
        "-o",
        &p("edit.npy"),
        "-o",
        &p("edit.npz"),
    ]));
    let (shape, base) = npy(dir.path().join("base.npy").as_path());
    let (shape2, edit) = npy(dir.path().join("edit.npy").as_path());
    assert_eq!(shape, shape2);
    assert_eq!(shape[0], 360);
    let frame = |j: &[f64], f: usize| j[f * 72..(f + 1) * 72].to_vec();
    for f in (0..120).chain(210..360) {
        let worst = frame(&base, f)
            .iter()
            .zip(frame(&edit, f))
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(worst <= 1e-4, "kept frame {f} moved {worst} m");
    }
    let moved = (120..210)
        .map(|f| (frame(&base, f)[21 * 3] - frame(&edit, f)[21 * 3]).abs())
        .fold(0.0, f64::max);
    assert!(
        moved > 0.05,
        "the regenerated range is the old one (wrist moved {moved} m)"
    );

    // The edited file is a dancegen dance too, and can be edited again.
    ok(&dancegen(&[
        "-q",
        "generate",
        "--edit",
        &p("edit.npz"),
        "--regenerate",
        "9-10.5",
        "-o",
        &p("again.npy"),
    ]));

    // A foreign dance (here: a BVH of it) needs the song; with it the edit runs.
    ok(&dancegen(&[
        "-q",
        "convert",
        &p("base.npz"),
        "-o",
        &p("base.bvh"),
    ]));
    refused(
        &[
            "-q",
            "generate",
            "--edit",
            &p("base.bvh"),
            "--regenerate",
            "1-2",
            "-o",
            &p("x.npy"),
        ],
        &["base.bvh", "no dancegen record", "SONG"],
    );
    ok(&dancegen(&[
        "-q",
        "generate",
        &s,
        "--start",
        "60",
        "--edit",
        &p("base.bvh"),
        "--regenerate",
        "1-2",
        "-o",
        &p("foreign.npy"),
    ]));

    // Bad edits: named, and nothing written.
    let none = p("never.npy");
    let base = p("base.npz");
    for (extra, words) in [
        (
            vec!["--regenerate", "10-13"],
            vec!["--regenerate 10-13", "outside the dance"],
        ),
        (
            vec!["--regenerate", "2-2.3"],
            vec!["--regenerate 2-2.3", "at least 0.5 s"],
        ),
        (
            vec!["--regenerate", "1-4", "--regenerate", "3-5"],
            vec!["overlap"],
        ),
        (
            vec!["--regenerate", "4-2"],
            vec!["4-2", "START must be before END"],
        ),
        (
            vec!["--regenerate", "1-2", "--system", "group"],
            vec!["a solo dance", "--system solo"],
        ),
    ] {
        let mut args = vec!["-q", "generate", "--edit", base.as_str()];
        args.extend(extra);
        args.extend(["-o", &none]);
        refused(&args, &words);
        assert!(!std::path::Path::new(&none).exists());
    }
    refused(
        &["-q", "generate", "--edit", &p("base.npz"), "-o", &none],
        &["--regenerate"],
    );
}

#[test]
fn a_continuation_starts_with_the_motions_last_second() {
    let dir = tempfile::tempdir().unwrap();
    let p = |n: &str| dir.path().join(n).to_str().unwrap().to_string();
    let s = song();
    ok(&dancegen(&[
        "-q",
        "generate",
        &s,
        "--start",
        "30",
        "--end",
        "36",
        "-o",
        &p("first.npz"),
        "-o",
        &p("first.npy"),
    ]));
    ok(&dancegen(&[
        "-q",
        "generate",
        &s,
        "--start",
        "35",
        "--end",
        "43",
        "--continue-from",
        &p("first.npz"),
        "-o",
        &p("next.npy"),
    ]));
    let (_, first) = npy(dir.path().join("first.npy").as_path());
    let (shape, next) = npy(dir.path().join("next.npy").as_path());
    assert_eq!(shape[0], 240);
    let from = first.len() / 72 - 30;
    let worst = (0..30 * 72)
        .map(|i| (first[from * 72 + i] - next[i]).abs())
        .fold(0.0, f64::max);
    assert!(worst <= 1e-4, "the kept second moved {worst} m");
    // A group continues a group: one dancer's motion is refused, the counts named.
    refused(
        &[
            "-q",
            "generate",
            &s,
            "--system",
            "group",
            "--dancers",
            "3",
            "--continue-from",
            &p("first.npz"),
            "-o",
            &p("g.npy"),
        ],
        &["--continue-from", "1 dancer, and this group dance has 3"],
    );
}

#[test]
fn kept_joints_come_from_the_given_motion_and_unknown_joints_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let p = |n: &str| dir.path().join(n).to_str().unwrap().to_string();
    let s = song();
    ok(&dancegen(&[
        "-q",
        "generate",
        &s,
        "--start",
        "30",
        "--end",
        "36",
        "-o",
        &p("moves.npz"),
        "-o",
        &p("moves.npy"),
    ]));
    // No --end: the dance lasts as long as the --from motion.
    ok(&dancegen(&[
        "-q",
        "generate",
        &s,
        "--start",
        "50",
        "--keep-joints",
        "lower",
        "--from",
        &p("moves.npz"),
        "--seed",
        "3",
        "-o",
        &p("kept.npy"),
    ]));
    let (shape, moves) = npy(dir.path().join("moves.npy").as_path());
    let (shape2, kept) = npy(dir.path().join("kept.npy").as_path());
    assert_eq!(shape, shape2);
    // Pelvis, hips, knees, ankles and feet stand where the motion's do.
    for f in 0..shape[0] {
        for j in [0, 1, 2, 4, 5, 7, 8, 10, 11] {
            for c in 0..3 {
                let i = f * 72 + 3 * j + c;
                assert!((moves[i] - kept[i]).abs() <= 1e-4, "frame {f} joint {j}");
            }
        }
    }
    let wrist_moved = (0..shape[0])
        .map(|f| (moves[f * 72 + 21 * 3 + 1] - kept[f * 72 + 21 * 3 + 1]).abs())
        .fold(0.0, f64::max);
    assert!(
        wrist_moved > 0.05,
        "the arms are the motion's ({wrist_moved} m)"
    );
    refused(
        &[
            "-q",
            "generate",
            &s,
            "--keep-joints",
            "left_knee,tail",
            "--from",
            &p("moves.npz"),
            "-o",
            &p("x.npy"),
        ],
        &["\"tail\"", "not a joint of the SMPL 24 skeleton"],
    );
    refused(
        &[
            "-q",
            "generate",
            &s,
            "--start",
            "30",
            "--end",
            "40",
            "--keep-joints",
            "arms",
            "--from",
            &p("moves.npz"),
            "-o",
            &p("x.npy"),
        ],
        &["--from", "moves.npz", "6.00 s of motion"],
    );
    assert!(!dir.path().join("x.npy").exists());
}

#[test]
fn a_keyframe_and_a_path_through_the_binary_and_their_bad_input_named() {
    let dir = tempfile::tempdir().unwrap();
    let p = |n: &str| dir.path().join(n).to_str().unwrap().to_string();
    let s = song();
    let make = |extra: &[&str], out: &str| {
        let mut args = vec!["-q", "generate", s.as_str(), "--end", "12"];
        args.extend_from_slice(extra);
        args.extend_from_slice(&["-o", out]);
        dancegen(&args)
    };
    ok(&make(&["-o", &p("pose.npz")], &p("pose.npy")));
    // Frame 90 of pose.npz, reached at 8 s with its floor position: every joint where it was.
    ok(&make(
        &[
            "--keyframe",
            &format!("{}:90@8", p("pose.npz")),
            "--keyframe-root",
            "--seed",
            "2",
        ],
        &p("kf.npy"),
    ));
    let (_, pose) = npy(dir.path().join("pose.npy").as_path());
    let (shape, kf) = npy(dir.path().join("kf.npy").as_path());
    assert_eq!(shape, vec![360, 24, 3]);
    let worst = (0..72)
        .map(|i| (kf[240 * 72 + i] - pose[90 * 72 + i]).abs())
        .fold(0.0, f64::max);
    assert!(worst <= 0.03, "a keyframed joint is {worst} m off");
    // A path: the pelvis follows it from 2 s to 9 s.
    std::fs::write(
        p("path.json"),
        r#"{"keyframes": [{"t": 2, "positions": [[0, 0]]}, {"t": 9, "positions": [[1, -0.5]]}]}"#,
    )
    .unwrap();
    ok(&make(&["--path", &p("path.json")], &p("path.npy")));
    let (_, path) = npy(dir.path().join("path.npy").as_path());
    let at = |f: usize| [path[f * 72], path[f * 72 + 2]];
    let (start, end) = (at(60), at(270));
    let miss = (start[0].hypot(start[1]), (end[0] - 1.0).hypot(end[1] + 0.5));
    assert!(
        miss.0 <= 0.1 && miss.1 <= 0.1,
        "the path is missed by {miss:?} m"
    );
    // Bad input: named, nothing written.
    let x = p("x.npy");
    for (extra, words) in [
        (
            vec![
                "--keyframe".to_string(),
                format!("{}:9999@3", p("pose.npz")),
            ],
            vec!["--keyframe", "no frame 9999", "360"],
        ),
        (
            vec!["--keyframe".to_string(), format!("{}@400", p("pose.npz"))],
            vec!["--keyframe", "outside the song"],
        ),
        (
            vec![
                "--keyframe".to_string(),
                format!("{}@3", p("pose.npz")),
                "--start".to_string(),
                "5".to_string(),
            ],
            vec!["--keyframe", "outside the danced part"],
        ),
        (
            vec![
                "--keyframe".to_string(),
                format!("{}@3", p("pose.npz")),
                "--keyframe-joints".to_string(),
                "left_wrist,wing".to_string(),
            ],
            vec!["--keyframe-joints", "\"wing\""],
        ),
        (
            vec!["--keyframe".to_string(), p("pose.npz")],
            vec!["--keyframe", "no @T"],
        ),
        (vec!["--path".to_string(), p("pose.npy")], vec!["pose.npy"]),
    ] {
        let extra: Vec<&str> = extra.iter().map(String::as_str).collect();
        let o = make(&extra, &x);
        assert!(!o.status.success(), "{extra:?} succeeded");
        let e = stderr(&o);
        for w in words {
            assert!(e.contains(w), "{extra:?}: {w:?} not in {e}");
        }
        assert!(!dir.path().join("x.npy").exists(), "{extra:?} wrote output");
    }
}

#[test]
fn a_duet_follower_is_edited_with_its_leader_given_again() {
    let dir = tempfile::tempdir().unwrap();
    let p = |n: &str| dir.path().join(n).to_str().unwrap().to_string();
    let s = song();
    let take = shared().join("data/cmu-salsa/60_13_scaled.bvh");
    ok(&dancegen(&[
        "-q",
        "convert",
        take.to_str().unwrap(),
        "--source-fps",
        "60",
        "--to",
        "smpl24",
        "--fps",
        "30",
        "-o",
        &p("lead.npz"),
    ]));
    ok(&dancegen(&[
        "-q",
        "generate",
        &s,
        "--leader",
        &p("lead.npz"),
        "-o",
        &p("follower.npz"),
        "-o",
        &p("follower.npy"),
    ]));
    refused(
        &[
            "-q",
            "generate",
            "--edit",
            &p("follower.npz"),
            "--regenerate",
            "5-9",
            "-o",
            &p("x.npy"),
        ],
        &["--edit", "follower.npz", "--leader FILE"],
    );
    ok(&dancegen(&[
        "-q",
        "generate",
        "--edit",
        &p("follower.npz"),
        "--leader",
        &p("lead.npz"),
        "--regenerate",
        "5-9",
        "--seed",
        "2",
        "-o",
        &p("edited.npy"),
    ]));
    let (shape, a) = npy(dir.path().join("follower.npy").as_path());
    let (shape2, b) = npy(dir.path().join("edited.npy").as_path());
    assert_eq!(shape, shape2);
    let per_frame = 72;
    for f in (0..shape[0]).filter(|f| !(150..270).contains(f)) {
        for i in 0..per_frame {
            let k = f * per_frame + i;
            assert!((a[k] - b[k]).abs() <= 1e-4, "frame {f} changed");
        }
    }
    let moved = (150 * per_frame..270 * per_frame)
        .map(|k| (a[k] - b[k]).abs())
        .fold(0.0, f64::max);
    assert!(moved > 0.05, "the range is the old one ({moved} m)");
    refused(
        &[
            "-q",
            "generate",
            &s,
            "--leader",
            &p("lead.npz"),
            "--keyframe",
            &format!("{}@3", p("follower.npz")),
            "-o",
            &p("x.npy"),
        ],
        &["--keyframe is not supported by --system duet"],
    );
    assert!(!dir.path().join("x.npy").exists());
}

#[test]
fn an_extended_dance_is_the_old_one_then_more_to_the_new_end() {
    let dir = tempfile::tempdir().unwrap();
    let p = |n: &str| dir.path().join(n).to_str().unwrap().to_string();
    let s = song();
    ok(&dancegen(&[
        "-q",
        "generate",
        &s,
        "--start",
        "40",
        "--end",
        "50",
        "-o",
        &p("a.npz"),
        "-o",
        &p("a.npy"),
    ]));
    ok(&dancegen(&[
        "-q",
        "generate",
        "--edit",
        &p("a.npz"),
        "--extend",
        "--end",
        "56",
        "--seed",
        "1",
        "-o",
        &p("b.npy"),
    ]));
    let (sa, a) = npy(dir.path().join("a.npy").as_path());
    let (sb, b) = npy(dir.path().join("b.npy").as_path());
    assert_eq!((sa[0], sb[0]), (300, 480));
    assert!(
        a.iter().zip(&b).all(|(x, y)| (x - y).abs() <= 1e-4),
        "the first 10 s changed"
    );
    refused(
        &[
            "-q",
            "generate",
            "--edit",
            &p("a.npz"),
            "--extend",
            "--end",
            "50.2",
            "-o",
            &p("x.npy"),
        ],
        &["--extend", "later --end"],
    );
    refused(
        &["-q", "generate", &s, "--extend", "-o", &p("x.npy")],
        &["--edit"],
    );
    assert!(!dir.path().join("x.npy").exists());
}

#[test]
fn a_group_is_edited_through_the_files_it_wrote() {
    let dir = tempfile::tempdir().unwrap();
    let p = |n: &str| dir.path().join(n).to_str().unwrap().to_string();
    let s = song();
    // `-o group.npz` writes group_0.npz … group_2.npz.
    ok(&dancegen(&[
        "-q",
        "generate",
        &s,
        "--system",
        "group",
        "--dancers",
        "3",
        "--start",
        "60",
        "--end",
        "72",
        "-o",
        &p("group.npz"),
        "-o",
        &p("group.npy"),
    ]));
    assert!(dir.path().join("group_2.npz").is_file());
    // The name given, or any dancer's file, names the group: no --system, --dancers or song.
    for edited in ["group.npz", "group_1.npz"] {
        let out = format!("v2-{}", edited.replace(".npz", ".npy"));
        ok(&dancegen(&[
            "-q",
            "generate",
            "--edit",
            &p(edited),
            "--regenerate",
            "4-7",
            "--seed",
            "3",
            "-o",
            &p(&out),
        ]));
        let (shape, old) = npy(&dir.path().join("group.npy"));
        let (shape2, new) = npy(&dir.path().join(&out));
        assert_eq!(shape, vec![3, 360, 24, 3]);
        assert_eq!(shape2, shape);
        let frame = 72;
        for d in 0..3 {
            let at = |f: usize| (d * 360 + f) * frame;
            for f in (0..360).filter(|f| !(120..210).contains(f)) {
                for i in at(f)..at(f + 1) {
                    assert!(
                        (old[i] - new[i]).abs() <= 1e-4,
                        "{edited}: dancer {d}, frame {f}"
                    );
                }
            }
        }
    }
    // A missing dancer's file is named; so are a group given to a solo edit and the wrong count.
    std::fs::rename(p("group_2.npz"), p("away.npz")).unwrap();
    refused(
        &[
            "generate",
            "--edit",
            &p("group_0.npz"),
            "--regenerate",
            "4-7",
            "-o",
            &p("x.npz"),
        ],
        &["group_2.npz", "is missing"],
    );
    std::fs::rename(p("away.npz"), p("group_2.npz")).unwrap();
    refused(
        &[
            "generate",
            "--edit",
            &p("group.npz"),
            "--regenerate",
            "4-7",
            "--dancers",
            "4",
            "-o",
            &p("x.npz"),
        ],
        &["--edit", "3 dancers", "has 4"],
    );
    refused(
        &[
            "generate",
            &s,
            "--start",
            "60",
            "--end",
            "66",
            "--continue-from",
            &p("group.npz"),
            "--system",
            "solo",
            "-o",
            &p("x.npz"),
        ],
        &["--continue-from", "3 dancers", "--system group"],
    );
    assert!(!dir.path().join("x.npz").exists() && !dir.path().join("x_0.npz").exists());
}

#[test]
fn a_holistic_dance_is_edited_with_its_fingers_and_face() {
    let dir = tempfile::tempdir().unwrap();
    let p = |n: &str| dir.path().join(n).to_str().unwrap().to_string();
    let s = song();
    ok(&dancegen(&[
        "-q",
        "generate",
        &s,
        "--system",
        "holistic",
        "--start",
        "60",
        "--end",
        "72",
        "-o",
        &p("h.npz"),
    ]));
    // The record gives the song, the start and the system; the .npz holds fingers and face.
    ok(&dancegen(&[
        "-q",
        "generate",
        "--edit",
        &p("h.npz"),
        "--regenerate",
        "4-7",
        "--seed",
        "3",
        "-o",
        &p("h2.npz"),
    ]));
    let read = |name: &str| {
        let m = dancegen_io::npz::read_npz_members(
            &dir.path().join(name),
            &["poses", dancegen_formats::smpl_npz::FACE_MEMBER],
        )
        .unwrap();
        (m[0].1.clone(), m[1].1.clone())
    };
    let ((poses, face), (poses2, face2)) = (read("h.npz"), read("h2.npz"));
    assert_eq!(poses.shape, vec![360, 156]);
    assert_eq!(poses2.shape, poses.shape);
    assert_eq!(face2.shape, vec![360, 52]);
    for f in (0..360).filter(|f| !(120..210).contains(f)) {
        assert_eq!(
            poses.data[f * 156..(f + 1) * 156],
            poses2.data[f * 156..(f + 1) * 156],
            "frame {f}"
        );
        assert_eq!(
            face.data[f * 52..(f + 1) * 52],
            face2.data[f * 52..(f + 1) * 52],
            "frame {f}"
        );
    }
    let moved = (120 * 156..210 * 156)
        .map(|i| (poses.data[i] - poses2.data[i]).abs())
        .fold(0.0, f64::max);
    assert!(moved > 0.05, "the range is the old one");
    // Kept arms fill the regenerated range: the arms are the old ones everywhere, the rest
    // of the range is new.
    ok(&dancegen(&[
        "-q",
        "generate",
        "--edit",
        &p("h.npz"),
        "--regenerate",
        "4-7",
        "--keep-joints",
        "arms",
        "--from",
        &p("h.npz"),
        "--seed",
        "4",
        "-o",
        &p("h3.npz"),
    ]));
    let (poses3, _) = read("h3.npz");
    let arms = [13, 14, 16, 17, 18, 19, 20, 21];
    for f in 0..360 {
        for j in arms {
            assert_eq!(
                poses3.data[f * 156 + 3 * j..f * 156 + 3 * j + 3],
                poses.data[f * 156 + 3 * j..f * 156 + 3 * j + 3],
                "frame {f} joint {j}"
            );
        }
    }
    let legs = (120..210)
        .flat_map(|f| [1, 2, 4, 5].map(|j| f * 156 + 3 * j))
        .flat_map(|at| at..at + 3)
        .map(|i| (poses.data[i] - poses3.data[i]).abs())
        .fold(0.0, f64::max);
    assert!(legs > 0.05, "the legs of the range are the old ones");
    // A keyframe where the dance is kept is refused, naming both, and nothing is written.
    refused(
        &[
            "generate",
            "--edit",
            &p("h.npz"),
            "--regenerate",
            "4-7",
            "--keyframe",
            &format!("{}@61", p("h.npz")),
            "-o",
            &p("x.npz"),
        ],
        &["--keyframe", "already given by --edit/--regenerate"],
    );
    assert!(!dir.path().join("x.npz").exists());
}

#[test]
fn the_readme_shows_the_table_of_edits_generate_help_prints() {
    let o = dancegen(&["generate", "--help"]);
    ok(&o);
    let help = String::from_utf8_lossy(&o.stdout);
    let readme = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../README.md"),
    )
    .unwrap();
    let table: Vec<&str> = help
        .lines()
        .skip_while(|l| !l.starts_with("Edits (which system supports what):"))
        .take_while(|l| !l.trim().is_empty())
        .collect();
    assert!(table.len() >= 6, "no table of edits in --help:\n{help}");
    for line in table {
        assert!(
            readme.lines().any(|r| r.trim_end() == line.trim_end()),
            "README.md does not have this line of `generate --help`'s table: {line:?}"
        );
    }
}
