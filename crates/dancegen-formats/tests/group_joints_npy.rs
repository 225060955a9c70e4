//! The `.npy` that `dancegen generate --dancers N` writes, `(N, T, J, 3)`, reads as N dancers'
//! joints: `--dancer` picks one, `--fps` resamples each, and writing it back keeps the shape.

use dancegen_formats::dispatch::{
    ConvertOptions, LoadedMotion, convert_motion, joint_positions, load_motion_file,
    save_motion_file,
};

/// Dancer `d`, frame `f`, joint `j`, axis `c` gets `1000 d + 10 f + j + c / 10`.
fn group(n: usize, t: usize, j: usize) -> Vec<f32> {
    let mut v = Vec::new();
    for d in 0..n {
        for f in 0..t {
            for k in 0..j {
                for c in 0..3 {
                    v.push((1000 * d + 10 * f + k) as f32 + c as f32 / 10.0);
                }
            }
        }
    }
    v
}

#[test]
fn a_group_joints_npy_is_read_picked_resampled_and_written_back() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("group.npy");
    let (n, t, j) = (3, 8, 24);
    dancegen_io::write_npy_f32(&path, &[n, t, j, 3], &group(n, t, j)).unwrap();

    let m = load_motion_file(&path).unwrap();
    assert!(matches!(
        m,
        LoadedMotion::Joints {
            dancers: 3,
            joints: 24,
            ..
        }
    ));
    assert_eq!(joint_positions(&path, &m).unwrap().0, vec![n, t, j, 3]);

    // --dancer 1: the second dancer's block alone, as a single (T, J, 3) motion.
    let one = convert_motion(
        &path,
        m.clone(),
        &ConvertOptions {
            dancer: Some(1),
            ..Default::default()
        },
    )
    .unwrap();
    let (shape, data) = joint_positions(&path, &one).unwrap();
    assert_eq!(shape, vec![t, j, 3]);
    assert_eq!(data[..3], [1000.0, 1000.1, 1000.2]);
    let e = convert_motion(
        &path,
        m.clone(),
        &ConvertOptions {
            dancer: Some(3),
            ..Default::default()
        },
    )
    .unwrap_err();
    assert!(
        e.to_string().contains("--dancer 3: the file has 3 dancers"),
        "{e}"
    );

    // Half the rate: every dancer keeps its own frames 0, 2, 4, 6.
    let half = convert_motion(
        &path,
        m.clone(),
        &ConvertOptions {
            fps: Some(15.0),
            ..Default::default()
        },
    )
    .unwrap();
    let (shape, data) = joint_positions(&path, &half).unwrap();
    assert_eq!(shape, vec![n, 4, j, 3]);
    let at = |d: usize, f: usize| data[((d * 4 + f) * j) * 3];
    assert_eq!([at(0, 1), at(2, 3)], [20.0, 2060.0]);

    // Written back as .npy: the same (N, T, J, 3) array.
    let out = dir.path().join("again.npy");
    save_motion_file(&out, &m, &ConvertOptions::default()).unwrap();
    let back = dancegen_io::read_npy(&out).unwrap();
    assert_eq!(back.shape, vec![n, t, j, 3]);
}

#[test]
fn other_shapes_are_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("five_d.npy");
    dancegen_io::write_npy_f32(&path, &[1, 2, 2, 24, 3], &vec![0.0; 288]).unwrap();
    let e = load_motion_file(&path).unwrap_err().to_string();
    assert!(
        e.contains("five_d.npy") && e.contains("(N, T, J, 3)"),
        "{e}"
    );
}
