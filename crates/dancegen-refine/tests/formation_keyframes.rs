//! FORMATION.json: parsing, every rejection (each naming its field), and sampling.

use dancegen_refine::formation::keyframes::{Formation, FormationProblem, Keyframe};
use dancegen_refine::formation::min_jerk::min_jerk_point;

const FILE: &str = "show/FORMATION.json";

fn parse(json: &str, dancers: usize) -> Formation {
    Formation::parse(FILE, json, dancers, 30.0).unwrap_or_else(|e| panic!("{e}"))
}

/// The error message for `json`, checked to name the file and every one of `names`.
fn rejects(json: &str, dancers: usize, names: &[&str]) -> FormationProblem {
    let err = Formation::parse(FILE, json, dancers, 30.0).expect_err(json);
    let message = err.to_string();
    assert!(message.starts_with(FILE), "{message}");
    for name in names {
        assert!(message.contains(name), "{message:?} does not name {name:?}");
    }
    err.problem
}

const SWAP: &str = r#"{"keyframes": [
    {"t": 0.0, "positions": [[-0.9, 0.0], [0.0, 0.0], [0.9, 0.0]]},
    {"t": 1.0, "positions": [[-0.9, 0.0], [0.0, 0.0], [0.9, 0.0]]},
    {"t": 3.0, "positions": [[0.9, 0.0], null, [-0.9, 0.5]]},
    {"t": 4.0, "positions": [[0.9, 0.0], [0.0, -1.0], [-0.9, 0.5]]}
]}"#;

#[test]
fn sampling_follows_the_contract() {
    let formation = parse(SWAP, 3);
    assert_eq!(formation.dancers(), 3);
    assert_eq!(formation.keyframes().len(), 4);
    let tracks = formation.sample(30.0, 150);
    assert_eq!(tracks.len(), 3);
    assert!(tracks.iter().all(|t| t.len() == 150));
    // Keyframe frames are exact.
    assert_eq!(tracks[0][0], Some([-0.9, 0.0]));
    assert_eq!(tracks[0][90], Some([0.9, 0.0]));
    assert_eq!(tracks[2][120], Some([-0.9, 0.5]));
    // Between given keyframes: the minimum-jerk path over the frames between.
    for (i, &sample) in tracks[0][30..=90].iter().enumerate() {
        let expected = min_jerk_point([-0.9, 0.0], [0.9, 0.0], i as f64 / 60.0);
        assert_eq!(sample, Some(expected), "frame {}", 30 + i);
    }
    assert_eq!(
        tracks[0][15],
        Some([-0.9, 0.0]),
        "holding still is a path too"
    );
    // Dancer 1 is null at t = 3: free in both segments touching it, given on its other frames.
    assert_eq!(tracks[1][30], Some([0.0, 0.0]));
    assert!(tracks[1][31..120].iter().all(Option::is_none));
    assert_eq!(tracks[1][120], Some([0.0, -1.0]));
    // After the last keyframe everyone is free.
    assert!(tracks.iter().all(|t| t[121..].iter().all(Option::is_none)));
    // Orders, as the audience sees them.
    assert_eq!(formation.start_order(), Some(vec![0, 1, 2]));
    assert_eq!(formation.end_order(), Some(vec![2, 1, 0]));
    // Fewer frames than the song: later keyframes are dropped, not a panic.
    let short = formation.sample(30.0, 60);
    assert_eq!(
        short[0][59],
        Some(min_jerk_point([-0.9, 0.0], [0.9, 0.0], 29.0 / 60.0))
    );
    assert!(
        formation
            .sample(f64::NAN, 10)
            .iter()
            .flatten()
            .all(Option::is_none)
    );
}

#[test]
fn rounding_and_single_keyframes() {
    // 0.049 s at 30 fps is frame 1.47 → 1; 0.05 s is 1.5 → 2 (halves round away from zero).
    let json = r#"{"keyframes": [
        {"t": 0.049, "positions": [[0.0, 0.0], null]},
        {"t": 0.05, "positions": [[1.0, 0.0], [5.0, 5.0]]}
    ]}"#;
    let tracks = parse(json, 2).sample(30.0, 5);
    assert_eq!(
        tracks[0],
        vec![None, Some([0.0, 0.0]), Some([1.0, 0.0]), None, None]
    );
    // Dancer 1 is given once: constrained on that frame only.
    assert_eq!(tracks[1], vec![None, None, Some([5.0, 5.0]), None, None]);
    // Two keyframes on one frame: the later one is kept there.
    let json = r#"{"keyframes": [
        {"t": 0.0, "positions": [[0.0, 0.0]]},
        {"t": 0.01, "positions": [[1.0, 0.0]]}
    ]}"#;
    assert_eq!(
        parse(json, 1).sample(30.0, 2)[0],
        vec![Some([1.0, 0.0]), None]
    );
    let one = parse(
        r#"{"keyframes": [{"t": 30, "positions": [null, [0, 0]]}]}"#,
        2,
    );
    assert_eq!(one.start_order(), None);
    assert_eq!(one.sample(30.0, 901)[1][900], Some([0.0, 0.0]));
}

#[test]
fn paths_between_keyframes_can_be_checked_for_collisions() {
    // Dancers 0 and 2 exchange places on straight paths between t = 1 and t = 3 and meet in the
    // middle (frame 60) while dancer 1 is free there.
    let crossing = parse(SWAP, 3)
        .closest_constrained_approach(30.0, 150)
        .unwrap();
    assert_eq!((crossing.pair.a, crossing.pair.b), (0, 2));
    assert!(
        crossing.pair.distance < 0.3 && (55..=65).contains(&crossing.frame),
        "{crossing:?}"
    );
    let still = r#"{"keyframes": [
        {"t": 0, "positions": [[0, 0], [1, 0]]}, {"t": 2, "positions": [[0, 1], [1, 1]]}
    ]}"#;
    let apart = parse(still, 2)
        .closest_constrained_approach(30.0, 61)
        .unwrap();
    assert!((apart.pair.distance - 1.0).abs() < 1e-12);
    assert_eq!(parse(still, 2).closest_constrained_approach(30.0, 0), None);
}

#[test]
fn round_trips_through_json() {
    let formation = parse(SWAP, 3);
    let json = serde_json::to_string(&formation).unwrap();
    assert_eq!(parse(&json, 3), formation);
}

#[test]
fn every_error_names_its_field() {
    let one = |t: &str, positions: &str| {
        format!(r#"{{"keyframes": [{{"t": {t}, "positions": {positions}}}]}}"#)
    };
    assert!(matches!(
        rejects("{\"keyframes\": [", 1, &["not valid JSON", "line 1"]),
        FormationProblem::Json(_)
    ));
    rejects("[]", 1, &["(top level)", "expected an object"]);
    rejects("{}", 1, &["keyframes is missing"]);
    rejects(r#"{"keyframes": {}}"#, 1, &["keyframes: expected a list"]);
    rejects(
        r#"{"keyframes": [], "fps": 30}"#,
        1,
        &["fps: unknown field"],
    );
    assert_eq!(
        rejects(r#"{"keyframes": []}"#, 1, &["keyframes", "empty"]),
        FormationProblem::NoKeyframes
    );
    rejects(
        r#"{"keyframes": [3]}"#,
        1,
        &["keyframes[0]: expected an object", "the number 3"],
    );
    rejects(
        r#"{"keyframes": [{"time": 0, "t": 0, "positions": [null]}]}"#,
        1,
        &["keyframes[0].time: unknown field"],
    );
    rejects(
        r#"{"keyframes": [{"positions": [null]}]}"#,
        1,
        &["keyframes[0].t is missing"],
    );
    rejects(
        r#"{"keyframes": [{"t": 0}]}"#,
        1,
        &["keyframes[0].positions is missing"],
    );
    rejects(
        &one("\"1.5\"", "[null]"),
        1,
        &["keyframes[0].t: expected a time", "the text \"1.5\""],
    );
    rejects(
        &one("0", "null"),
        1,
        &["keyframes[0].positions: expected a list"],
    );
    rejects(
        &one("0", "[[1, 2, 3]]"),
        1,
        &["keyframes[0].positions[0]: expected [x, z]", "a list of 3"],
    );
    rejects(
        &one("0", "[[1, \"a\"]]"),
        1,
        &["keyframes[0].positions[0][1]: expected z"],
    );
    rejects(
        &one("0", "[[1, 2]]"),
        2,
        &["keyframes[0].positions: 1 positions for 2 dancers"],
    );
    rejects(
        &one("-0.5", "[null]"),
        1,
        &["keyframes[0].t", "-0.5", "before the start"],
    );
    rejects(
        &one("31", "[null]"),
        1,
        &["keyframes[0].t", "31", "after the end of the song (30 s)"],
    );
    // JSON has no NaN or infinity, and overflowing literals are refused by the parser.
    rejects(&one("1e999", "[null]"), 1, &["not valid JSON"]);
    let twice = r#"{"keyframes": [
        {"t": 2, "positions": [null]}, {"t": 4, "positions": [null]}, {"t": 4, "positions": [null]}
    ]}"#;
    let problem = rejects(
        twice,
        1,
        &[
            "keyframes[2].t",
            "previous keyframe's t = 4",
            "strictly increase",
        ],
    );
    assert!(matches!(
        problem,
        FormationProblem::TimeNotIncreasing { .. }
    ));
    let close = r#"{"keyframes": [
        {"t": 0, "positions": [[0, 0], [2, 0], [3, 0]]},
        {"t": 1, "positions": [[0, 0], null, [0.12, 0.16]]}
    ]}"#;
    let problem = rejects(
        close,
        3,
        &[
            "keyframes[1].positions[0] and keyframes[1].positions[2]",
            "dancers 0 and 2",
            "0.200 m",
            "0.45 m",
        ],
    );
    assert_eq!(
        problem,
        FormationProblem::TooClose {
            field: "keyframes[1].positions".into(),
            a: 0,
            b: 2,
            distance: 0.2
        }
    );
    // Exactly the collision distance is allowed.
    parse(&one("0", "[[0, 0], [0.45, 0]]"), 2);
}

#[test]
fn keyframes_built_in_code_are_checked_too() {
    let keyframe = |t: f64, p: Option<[f64; 2]>| Keyframe {
        t,
        positions: vec![p],
    };
    let check = |keyframes: Vec<Keyframe>, song: f64, names: &[&str]| {
        let message = Formation::new("generator", keyframes, 1, song)
            .unwrap_err()
            .to_string();
        assert!(message.starts_with("generator: "), "{message}");
        for name in names {
            assert!(message.contains(name), "{message:?} does not name {name:?}");
        }
    };
    check(
        vec![keyframe(f64::NAN, None)],
        10.0,
        &["keyframes[0].t", "not a finite"],
    );
    check(
        vec![keyframe(0.0, None), keyframe(f64::INFINITY, None)],
        10.0,
        &["keyframes[1].t", "inf"],
    );
    check(
        vec![keyframe(1.0, Some([0.0, f64::NAN]))],
        10.0,
        &["keyframes[0].positions[0][1]", "NaN"],
    );
    check(vec![keyframe(0.0, None)], f64::NAN, &["song duration"]);
    let ok = Formation::new("generator", vec![keyframe(0.0, Some([0.0, 0.0]))], 1, 0.0).unwrap();
    assert_eq!(ok.end_order(), Some(vec![0]));
}

#[test]
fn reading_a_missing_file_names_it() {
    let path = std::path::Path::new("/nonexistent/FORMATION.json");
    let message = Formation::read(path, 2, 10.0).unwrap_err().to_string();
    assert!(
        message.starts_with("/nonexistent/FORMATION.json: cannot read"),
        "{message}"
    );
}
