//! Safe pickle reader and AIST++ / GDance loaders: real AIST++ files, hand-built pickles and
//! error paths.

use std::path::PathBuf;

use dancegen_formats::aistpp::{self, AistppError};
use dancegen_formats::pickle::{self, ArrayData, DType, PickleErrorKind, PickleValue};

const SEQS: [(&str, usize); 3] = [
    ("gBR_sBM_cAll_d04_mBR2_ch08", 576),
    ("gBR_sBM_cAll_d06_mBR2_ch06", 576),
    ("gJS_sFM_cAll_d02_mJS4_ch09", 1919),
];

fn data_dir() -> PathBuf {
    PathBuf::from("/work/shared/data/aistpp")
}

fn motion_path(seq: &str) -> PathBuf {
    data_dir().join("motions").join(format!("{seq}.pkl"))
}

fn keypoints_path(seq: &str) -> PathBuf {
    data_dir().join("keypoints3d").join(format!("{seq}.pkl"))
}

fn have_data() -> bool {
    let ok = motion_path(SEQS[0].0).exists();
    if !ok {
        eprintln!("AIST++ sample data not found; skipping");
    }
    ok
}

// ---------------------------------------------------------------------------------------------
// A tiny test-only pickle writer (protocol 4 opcodes, as numpy + pickle.dump write them).

struct W(Vec<u8>);

impl W {
    fn new() -> Self {
        W(vec![0x80, 4])
    }
    fn op(&mut self, b: &[u8]) -> &mut Self {
        self.0.extend_from_slice(b);
        self
    }
    fn s(&mut self, s: &str) -> &mut Self {
        assert!(s.len() < 256);
        self.0.push(0x8c);
        self.0.push(s.len() as u8);
        self.0.extend_from_slice(s.as_bytes());
        self
    }
    fn int(&mut self, i: i32) -> &mut Self {
        self.0.push(b'J');
        self.0.extend_from_slice(&i.to_le_bytes());
        self
    }
    fn float(&mut self, f: f64) -> &mut Self {
        self.0.push(b'G');
        self.0.extend_from_slice(&f.to_be_bytes());
        self
    }
    fn bytes(&mut self, b: &[u8]) -> &mut Self {
        self.0.push(b'B');
        self.0.extend_from_slice(&(b.len() as u32).to_le_bytes());
        self.0.extend_from_slice(b);
        self
    }
    fn global(&mut self, module: &str, name: &str) -> &mut Self {
        self.s(module).s(name).op(&[0x93])
    }
    fn dtype(&mut self, code: &str, endian: &str) -> &mut Self {
        self.global("numpy", "dtype")
            .s(code)
            .op(b"K\x00K\x01\x87R(K\x03")
            .s(endian)
            .op(b"NNN")
            .int(-1)
            .int(-1)
            .op(b"K\x00tb")
    }
    /// `_reconstruct(ndarray, (0,), b'b')` + BUILD `(1, shape, dtype, fortran, raw)`.
    fn ndarray(
        &mut self,
        shape: &[i32],
        code: &str,
        endian: &str,
        fortran: bool,
        raw: &[u8],
    ) -> &mut Self {
        self.global("numpy.core.multiarray", "_reconstruct")
            .global("numpy", "ndarray")
            .op(b"K\x00\x85C\x01b\x87R\x94(K\x01(");
        for &d in shape {
            self.int(d);
        }
        self.op(b"t").dtype(code, endian);
        self.op(if fortran { &[0x88] } else { &[0x89] });
        self.bytes(raw).op(b"tb")
    }
    fn done(&mut self) -> Vec<u8> {
        self.0.push(b'.');
        self.0.clone()
    }
}

fn f32_le(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

fn f64_be(v: &[f64]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_be_bytes()).collect()
}

fn parse_err(bytes: &[u8]) -> pickle::PickleError {
    match pickle::parse(bytes) {
        Ok(v) => panic!("expected an error, got {v:?}"),
        Err(e) => e,
    }
}

// ---------------------------------------------------------------------------------------------
// Real AIST++ files.

#[test]
fn real_motions_load_with_expected_shapes() {
    if !have_data() {
        return;
    }
    for (seq, n) in SEQS {
        let m = aistpp::load_motion(motion_path(seq)).unwrap();
        assert_eq!(m.frames(), n, "{seq}");
        assert_eq!(m.poses.len(), n * 72, "{seq}");
        assert_eq!(m.trans.len(), n * 3, "{seq}");
        assert_eq!(m.fps, 60);
        assert!(
            m.scaling > 0.0 && m.scaling.is_finite(),
            "{seq}: {}",
            m.scaling
        );
        assert!(
            m.poses.iter().chain(&m.trans).all(|x| x.is_finite()),
            "{seq}"
        );
        let loss = m.loss.expect("smpl_loss present");
        assert!(loss.is_finite());
        // Axis-angle magnitudes are plausible radians.
        assert!(m.poses.iter().all(|x| x.abs() < 10.0), "{seq}");
        let tm = m.trans_metres();
        let max_abs = tm.iter().fold(0f32, |a, x| a.max(x.abs()));
        assert!(max_abs < 10.0, "{seq}: trans in metres up to {max_abs}");
        eprintln!(
            "{seq}: frames {n}, scaling {:.4}, loss {loss:.4}, max |trans_m| {max_abs:.3}",
            m.scaling
        );

        // Raw tree: dtypes as stored.
        let bytes = std::fs::read(motion_path(seq)).unwrap();
        let v = pickle::parse(&bytes).unwrap();
        match v.get("smpl_poses") {
            Some(PickleValue::NdArray(a)) => {
                assert_eq!(a.dtype(), DType::F32);
                assert_eq!(a.shape, vec![n, 72]);
                assert!(!a.fortran_order);
            }
            other => panic!("{other:?}"),
        }
        match v.get("smpl_scaling") {
            Some(PickleValue::NdArray(a)) => assert_eq!(a.shape, vec![1]),
            other => panic!("{other:?}"),
        }
        assert!(matches!(v.get("smpl_loss"), Some(PickleValue::Float(_))));
    }
}

#[test]
fn real_keypoints_load_with_expected_shapes() {
    if !have_data() {
        return;
    }
    for (seq, n) in SEQS {
        let k = aistpp::load_keypoints(keypoints_path(seq)).unwrap();
        assert_eq!(k.frames(), n, "{seq}");
        assert_eq!(k.keypoints3d.len(), n * 17 * 3);
        assert_eq!(k.keypoints3d_optim.len(), n * 17 * 3);
        assert!(k.keypoints3d_optim.iter().all(|x| x.is_finite()), "{seq}");
        let nan_raw = k.keypoints3d.iter().filter(|x| !x.is_finite()).count();
        eprintln!("{seq}: keypoints3d non-finite values: {nan_raw}");
        let bytes = std::fs::read(keypoints_path(seq)).unwrap();
        match pickle::parse(&bytes).unwrap().get("keypoints3d_optim") {
            Some(PickleValue::NdArray(a)) => {
                assert_eq!(a.dtype(), DType::F64);
                assert_eq!(a.shape, vec![n, 17, 3]);
            }
            other => panic!("{other:?}"),
        }
    }
}

/// Without FK: the SMPL pelvis is `smpl_trans + J_pelvis_rest * scaling` (the root rotation
/// turns about the pelvis), and the COCO hip midpoint (joints 11, 12) should be close to it.
#[test]
fn hip_midpoint_matches_smpl_pelvis() {
    if !have_data() {
        return;
    }
    const PELVIS_REST: [f64; 3] = [-0.0021, -0.2444, 0.0282];
    for (seq, n) in SEQS {
        let m = aistpp::load_motion(motion_path(seq)).unwrap();
        let k = aistpp::load_keypoints(keypoints_path(seq)).unwrap();
        assert_eq!(k.frames(), n);
        let s = f64::from(m.scaling);
        let mut d: Vec<f64> = (0..n)
            .map(|f| {
                let kp = |j: usize, c: usize| k.keypoints3d_optim[(f * 17 + j) * 3 + c];
                (0..3)
                    .map(|c| {
                        let hip_mid = 0.5 * (kp(11, c) + kp(12, c));
                        let pelvis = f64::from(m.trans[f * 3 + c]) + PELVIS_REST[c] * s;
                        (hip_mid - pelvis).powi(2)
                    })
                    .sum::<f64>()
                    .sqrt()
            })
            .collect();
        let mut mean = [0f64; 3];
        for f in 0..n {
            for (c, m_c) in mean.iter_mut().enumerate() {
                let kp = |j: usize| k.keypoints3d_optim[(f * 17 + j) * 3 + c];
                let pelvis = f64::from(m.trans[f * 3 + c]) + PELVIS_REST[c] * s;
                *m_c += (0.5 * (kp(11) + kp(12)) - pelvis) / n as f64;
            }
        }
        eprintln!("{seq}: mean (hip midpoint - pelvis) = {mean:.2?} cm");
        d.sort_by(f64::total_cmp);
        let median = d[n / 2];
        let p95 = d[n * 95 / 100];
        eprintln!("{seq}: hip-midpoint vs pelvis distance median {median:.2} cm, p95 {p95:.2} cm");
        assert!(median < 10.0, "{seq}: median {median} cm");
    }
}

#[test]
fn every_prefix_of_a_real_file_errors_without_panicking() {
    if !have_data() {
        return;
    }
    let bytes = std::fs::read(motion_path(SEQS[0].0)).unwrap();
    // Cuts inside the header, inside array data and just before STOP.
    let cuts = (0..400).chain([bytes.len() / 2, bytes.len() - 2, bytes.len() - 1]);
    for cut in cuts {
        let e = parse_err(&bytes[..cut]);
        assert!(
            matches!(
                e.kind,
                PickleErrorKind::Truncated { .. } | PickleErrorKind::LengthTooLarge { .. }
            ),
            "cut {cut}: {e}"
        );
    }
    let err = aistpp::parse_motion("cut.pkl", &bytes[..1000]).unwrap_err();
    assert!(err.to_string().contains("cut.pkl"), "{err}");
}

// ---------------------------------------------------------------------------------------------
// Hand-built pickles.

fn gdance_fixture() -> Vec<u8> {
    let (p, t) = (2usize, 5usize);
    let poses: Vec<f32> = (0..p * t * 72).map(|i| i as f32 * 0.001).collect();
    let trans: Vec<f64> = (0..p * t * 3).map(|i| i as f64 * 0.5).collect();
    let betas: Vec<f32> = (0..p * 10).map(|i| -(i as f32)).collect();
    let mut w = W::new();
    w.op(b"}\x94(")
        .s("smpl_poses")
        .ndarray(&[p as i32, t as i32, 72], "f4", "<", false, &f32_le(&poses))
        .s("root_trans")
        .ndarray(&[p as i32, t as i32, 3], "f8", ">", false, &f64_be(&trans))
        .s("smpl_betas")
        .ndarray(&[p as i32, 10], "f4", "<", false, &f32_le(&betas))
        .s("meta")
        .op(b"]\x94(")
        .s("dancer_a")
        .s("dancer_b")
        .op(b"e")
        .s("loss")
        .float(1.25)
        .op(b"u");
    w.done()
}

#[test]
fn gdance_fixture_loads() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("group.pkl");
    std::fs::write(&path, gdance_fixture()).unwrap();
    let g = aistpp::load_gdance(&path).unwrap();
    assert_eq!((g.persons, g.frames, g.fps), (2, 5, 30));
    assert_eq!(g.poses.len(), 2 * 5 * 72);
    assert_eq!(g.poses[7], 0.007);
    assert_eq!(g.root_trans.len(), 30);
    assert_eq!(g.root_trans[29], 14.5); // big-endian f8 decoded
    assert_eq!(g.person_trans(1).unwrap()[0], 7.5);
    assert_eq!(g.person_poses(1).unwrap().len(), 360);
    assert!(g.person_poses(2).is_none());
    let (bshape, b) = g.betas.unwrap();
    assert_eq!(bshape, vec![2, 10]);
    assert_eq!(b[19], -19.0);

    let v = pickle::parse(&gdance_fixture()).unwrap();
    assert_eq!(
        v.get("meta"),
        Some(&PickleValue::List(vec![
            PickleValue::Str("dancer_a".into()),
            PickleValue::Str("dancer_b".into())
        ]))
    );
    assert_eq!(v.get("loss"), Some(&PickleValue::Float(1.25)));

    // Missing key: error names the file and the key.
    let mut w = W::new();
    w.op(b"}(")
        .s("smpl_poses")
        .ndarray(&[1, 1, 72], "f4", "<", false, &[0u8; 288])
        .op(b"u");
    std::fs::write(&path, w.done()).unwrap();
    let e = aistpp::load_gdance(&path).unwrap_err().to_string();
    assert!(e.contains("group.pkl") && e.contains("root_trans"), "{e}");

    // Missing file.
    let e = aistpp::load_motion(dir.path().join("nope.pkl")).unwrap_err();
    assert!(matches!(e, AistppError::Io { .. }));
    assert!(e.to_string().contains("nope.pkl"));
}

#[test]
fn fortran_order_numpy_scalar_and_frombuffer() {
    // 2×3 array stored in Fortran order: memory [a00 a10 a01 a11 a02 a12].
    let mem: Vec<f32> = vec![0.0, 10.0, 1.0, 11.0, 2.0, 12.0];
    let mut w = W::new();
    w.ndarray(&[2, 3], "f4", "<", true, &f32_le(&mem));
    let v = pickle::parse(&w.done()).unwrap();
    let PickleValue::NdArray(a) = v else { panic!() };
    assert!(a.fortran_order);
    assert_eq!(a.to_f32_vec(), vec![0.0, 1.0, 2.0, 10.0, 11.0, 12.0]);
    assert_eq!(
        a.to_c_order().data,
        ArrayData::F32(vec![0.0, 1.0, 2.0, 10.0, 11.0, 12.0])
    );

    // numpy scalar: scalar(dtype('f8'), b'...') as pickled for np.float64 values.
    let mut w = W::new();
    w.global("numpy.core.multiarray", "scalar")
        .dtype("f8", "<")
        .op(b"C\x08")
        .op(&2.5f64.to_le_bytes())
        .op(b"\x86R");
    assert_eq!(pickle::parse(&w.done()).unwrap(), PickleValue::Float(2.5));

    // Protocol 5 in-band: _frombuffer(bytearray, dtype, shape, 'C'), with GLOBAL (text) opcode.
    let mut w = W(vec![0x80, 5]);
    w.op(b"cnumpy._core.numeric\n_frombuffer\n(")
        .op(&[0x96])
        .op(&4u64.to_le_bytes())
        .op(&[1, 2, 3, 4])
        .dtype("u1", "|")
        .op(b"K\x02K\x02\x86")
        .s("C")
        .op(b"tR");
    let v = pickle::parse(&w.done()).unwrap();
    let PickleValue::NdArray(a) = v else {
        panic!("{v:?}")
    };
    assert_eq!(a.shape, vec![2, 2]);
    assert_eq!(a.data, ArrayData::U8(vec![1, 2, 3, 4]));
}

// ---------------------------------------------------------------------------------------------
// Error paths.

#[test]
fn unknown_opcode_is_reported_with_offset() {
    let e = parse_err(&[0x80, 4, b'N', 0xff]);
    assert_eq!(e.offset, 3);
    assert_eq!(e.kind, PickleErrorKind::UnknownOpcode { opcode: 0xff });
    assert!(e.to_string().contains("byte 3"), "{e}");
    // A real opcode outside the numpy subset.
    let e = parse_err(&[0x80, 4, b'N', 0x81]);
    assert!(
        matches!(
            e.kind,
            PickleErrorKind::UnsupportedOpcode { name: "NEWOBJ", .. }
        ),
        "{e}"
    );
}

#[test]
fn forbidden_globals_are_rejected() {
    let e = parse_err(b"\x80\x02cos\nsystem\n(S'echo hi'\ntR.");
    assert_eq!(e.offset, 2);
    assert_eq!(
        e.kind,
        PickleErrorKind::ForbiddenGlobal {
            module: "os".into(),
            name: "system".into()
        }
    );
    assert!(e.to_string().contains("os.system"), "{e}");
    let mut w = W::new();
    w.global("builtins", "eval");
    let e = parse_err(&w.done());
    assert!(e.to_string().contains("builtins.eval"), "{e}");
    // numpy, but not a reconstruction callable.
    let mut w = W::new();
    w.global("numpy", "load");
    assert!(matches!(
        parse_err(&w.done()).kind,
        PickleErrorKind::ForbiddenGlobal { .. }
    ));
    // Error propagates through the loader with the file name.
    let e = aistpp::parse_motion("evil.pkl", b"\x80\x02cos\nsystem\n.").unwrap_err();
    assert!(
        e.to_string().contains("evil.pkl") && e.to_string().contains("os.system"),
        "{e}"
    );
}

#[test]
fn truncated_and_oversized_inputs() {
    assert!(matches!(
        parse_err(&[]).kind,
        PickleErrorKind::Truncated { .. }
    ));
    assert!(matches!(
        parse_err(&[0x80, 4, b'N']).kind,
        PickleErrorKind::Truncated { .. }
    ));
    // BINBYTES declaring 2 GiB with 3 bytes of input: no allocation, clear error.
    let e = parse_err(b"\x80\x04B\xff\xff\xff\x7fabc.");
    assert_eq!(
        e.kind,
        PickleErrorKind::LengthTooLarge {
            what: "BINBYTES",
            declared: 0x7fff_ffff,
            remaining: 4
        }
    );
    let e = parse_err(b"\x80\x04\x8e\xff\xff\xff\xff\xff\xff\xff\xff.");
    assert!(
        matches!(e.kind, PickleErrorKind::LengthTooLarge { .. }),
        "{e}"
    );
    // Every prefix of a small fixture errors (never panics).
    let full = gdance_fixture();
    for cut in 0..full.len() {
        assert!(pickle::parse(&full[..cut]).is_err(), "cut {cut}");
    }
}

#[test]
fn shape_bytes_mismatch_and_absurd_shapes() {
    let mut w = W::new();
    w.ndarray(&[2, 3], "f4", "<", false, &[0u8; 20]);
    let e = parse_err(&w.done());
    assert_eq!(
        e.kind,
        PickleErrorKind::ShapeMismatch {
            shape: vec![2, 3],
            itemsize: 4,
            bytes: 20
        }
    );
    // Product overflows usize.
    let mut w = W::new();
    w.ndarray(
        &[i32::MAX, i32::MAX, i32::MAX, i32::MAX, i32::MAX],
        "f8",
        "<",
        false,
        &[0u8; 8],
    );
    assert!(matches!(
        parse_err(&w.done()).kind,
        PickleErrorKind::ShapeMismatch { .. }
    ));
    // Negative dimension.
    let mut w = W::new();
    w.ndarray(&[-1], "f8", "<", false, &[0u8; 8]);
    assert!(matches!(
        parse_err(&w.done()).kind,
        PickleErrorKind::ShapeMismatch { .. }
    ));
    // Unsupported dtype.
    let mut w = W::new();
    w.ndarray(&[1], "c16", "<", false, &[0u8; 16]);
    assert!(matches!(
        parse_err(&w.done()).kind,
        PickleErrorKind::UnsupportedArray { .. }
    ));
    // Loader-level shape check names the file and key.
    let mut w = W::new();
    w.op(b"}(")
        .s("smpl_poses")
        .ndarray(&[2, 71], "f4", "<", false, &[0u8; 2 * 71 * 4])
        .op(b"u");
    let e = aistpp::parse_motion("bad.pkl", &w.done())
        .unwrap_err()
        .to_string();
    assert!(e.contains("bad.pkl") && e.contains("smpl_poses"), "{e}");
}

#[test]
fn memo_miss_stack_underflow_and_protocol() {
    let e = parse_err(b"\x80\x04h\x05.");
    assert_eq!(e.kind, PickleErrorKind::MemoMiss { index: 5 });
    assert_eq!(e.offset, 2);
    let e = parse_err(b"\x80\x04j\x00\x01\x00\x00.");
    assert_eq!(e.kind, PickleErrorKind::MemoMiss { index: 256 });
    assert!(matches!(
        parse_err(b"\x80\x04R.").kind,
        PickleErrorKind::StackUnderflow { .. }
    ));
    assert!(matches!(
        parse_err(b"\x80\x04.").kind,
        PickleErrorKind::StackUnderflow { .. }
    ));
    assert!(matches!(
        parse_err(b"\x80\x04N\x85\x85t.").kind,
        PickleErrorKind::MissingMark { .. }
    ));
    // REDUCE on something that is not an allowed callable.
    assert!(matches!(
        parse_err(b"\x80\x04N)R.").kind,
        PickleErrorKind::TypeMismatch { .. }
    ));
    // SETITEMS on a list, odd item count.
    assert!(matches!(
        parse_err(b"\x80\x04](NNu.").kind,
        PickleErrorKind::TypeMismatch { .. }
    ));
    assert!(matches!(
        parse_err(b"\x80\x04}(Nu.").kind,
        PickleErrorKind::TypeMismatch { .. }
    ));
    // Protocol 0/1 and unknown protocols.
    assert!(matches!(
        parse_err(b"(dp0\n.").kind,
        PickleErrorKind::UnsupportedProtocol { .. }
    ));
    assert!(matches!(
        parse_err(b"\x80\x01N.").kind,
        PickleErrorKind::UnsupportedProtocol { .. }
    ));
    assert!(matches!(
        parse_err(b"\x80\x09N.").kind,
        PickleErrorKind::UnsupportedProtocol { .. }
    ));
    // Unbuilt array / bare global at STOP.
    let mut w = W::new();
    w.global("numpy", "ndarray");
    assert!(matches!(
        parse_err(&w.done()).kind,
        PickleErrorKind::BadResult { .. }
    ));
    // Self-referencing list: append the list to itself → depth error, not a stack overflow.
    let e = parse_err(b"\x80\x04]\x94h\x00a.");
    assert_eq!(e.kind, PickleErrorKind::TooDeep);
}

/// Memo sharing cannot be abused for exponential expansion or quadratic argument copying.
#[test]
fn shared_objects_cannot_blow_up() {
    // L0 = []; L(k+1) = [Lk, Lk]  -> 2^100 leaves if expanded naively.
    let mut b = vec![0x80, 4, b']', 0x94];
    for k in 0..100u8 {
        b.extend_from_slice(&[b'(', b'h', k, b'h', k, b'l', 0x94]);
    }
    b.push(b'.');
    assert_eq!(parse_err(&b).kind, PickleErrorKind::ExpansionLimit);
    // A memoised 100k-item tuple used as REDUCE arguments is refused without copying it.
    let mut w = W::new();
    w.op(b"(");
    for _ in 0..100_000 {
        w.op(b"N");
    }
    w.op(b"t\x94").global("numpy", "dtype").op(b"h\x00R");
    let e = parse_err(&w.done());
    assert!(
        matches!(e.kind, PickleErrorKind::TypeMismatch { .. }),
        "{e}"
    );
    assert!(e.to_string().contains("100000 items"), "{e}");
    // Re-building an array from a memoised 1 MiB buffer over and over is stopped early.
    let mut w = W::new();
    w.global("numpy.core.multiarray", "_reconstruct")
        .op(b"\x94")
        .global("numpy", "ndarray")
        .op(b"K\x00\x85C\x01b\x87\x94(K\x01(")
        .int(262_144)
        .op(b"t")
        .dtype("f4", "<")
        .op(b"\x89")
        .bytes(&vec![0u8; 1 << 20])
        .op(b"t\x940");
    for _ in 0..100 {
        w.op(b"h\x00h\x01Rh\x02b0");
    }
    w.op(b"N");
    assert_eq!(parse_err(&w.done()).kind, PickleErrorKind::ExpansionLimit);
}

/// Deterministic byte mutations of valid pickles never panic.
#[test]
fn mutations_never_panic() {
    let mut inputs = vec![gdance_fixture()];
    if have_data() {
        let b = std::fs::read(motion_path(SEQS[0].0)).unwrap();
        inputs.push(b[..b.len().min(400)].to_vec());
    }
    let mut state: u64 = 0x9e37_79b9_7f4a_7c15;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    let mut ok = 0usize;
    for input in &inputs {
        for _ in 0..3000 {
            let mut m = input.clone();
            for _ in 0..(1 + next() % 4) {
                let i = (next() % m.len() as u64) as usize;
                m[i] = next() as u8;
            }
            if pickle::parse(&m).is_ok() {
                ok += 1;
            }
        }
    }
    eprintln!("mutations that still parsed: {ok}");
}
