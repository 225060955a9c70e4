//! Fine-tuning a duet autoencoder's decoders (`[model] init_from`, `decoders_only`) with the
//! foot velocity loss: the encoders and quantizers come out bit for bit as they went in (so a
//! latent model trained on them stays valid), the decoders learn, the loss is logged, and a
//! start from weights of other data, or `decoders_only` alone, is refused with a named error.
//! `assemble_duet_bundle` then swaps the autoencoder of a duet model directory.

use std::collections::BTreeMap;
use std::path::Path;

use dancegen_formats::smpl_npz::{SmplNpzOptions, write_smpl_npz};
use dancegen_motion::repr::SmplMotion;
use dancegen_nn::burn::module::{Module, ModuleVisitor, Param};
use dancegen_nn::burn::tensor::Tensor;
use dancegen_nn::device;
use dancegen_nn::weights::{self, Layout};
use dancegen_train::tasks::reactdance::{assemble_duet_bundle, load_hfsq};
use dancegen_train::tasks::train_config;
use dancegen_train::{RunOptions, TrainConfig, files};

const T: usize = 120;

/// A dancer stepping and turning: smooth, varied joint angles and a wandering root.
fn dancer(phase: f64, turn: f64, scale: f64) -> SmplMotion {
    let mut poses = Vec::with_capacity(T * 72);
    let mut trans = Vec::with_capacity(T * 3);
    for f in 0..T {
        let t = f as f64 / 30.0;
        for j in 0..24 {
            let a = scale * 0.4 * (3.0 * t + phase + j as f64).sin();
            let b = scale * 0.3 * (2.0 * t + 0.5 * j as f64).cos();
            let c = scale * 0.2 * (5.0 * t + phase).sin();
            let yaw = if j == 0 { turn * t } else { 0.0 };
            poses.extend([a as f32, (b + yaw) as f32, c as f32]);
        }
        trans.extend([
            (0.5 * (t + phase).sin()) as f32,
            (0.9 + 0.05 * (4.0 * t).sin()) as f32,
            (0.3 * t + phase) as f32,
        ]);
    }
    SmplMotion::new(30.0, poses, trans).unwrap()
}

/// Two couples in `dir/motion` (followers) and `dir/leader`.
fn write_data(dir: &Path, scale: f64) {
    for sub in ["motion", "leader"] {
        std::fs::create_dir_all(dir.join(sub)).unwrap();
    }
    let opts = SmplNpzOptions::default();
    for (k, phase) in [0.3, 1.7].into_iter().enumerate() {
        let name = format!("couple_{k}.npz");
        write_smpl_npz(
            &dir.join("motion").join(&name),
            &dancer(phase, 1.5, scale),
            &opts,
        )
        .unwrap();
        write_smpl_npz(
            &dir.join("leader").join(&name),
            &dancer(phase + 0.9, -2.0, scale),
            &opts,
        )
        .unwrap();
    }
}

fn config(data: &Path, run: &Path, model_extra: &str, foot: f64) -> String {
    format!(
        r#"
[run]
dir = "{run}"
seed = 3
steps = 4
checkpoint_every = 4
log_every = 1
keep_checkpoints = 0

[data]
paths = ["{data}/motion"]
leader = "{data}/leader"
representation = "duet"
heading_sigma = 8.0
fps = 30
window = 32
stride = 8
batch_size = 4
normalizer = "mean_std"

[model]
kind = "reactdance_hfsq"
{model_extra}

[model.autoencoder]
width = 16
depth = 1
down_t = 2
groups = 1
levels = [5, 5]
num_levels = 2
foot_velocity_weight = {foot}

[optimizer]
kind = "adamw"
lr = 1e-2
weight_decay = 0.0

[schedule]
warmup_steps = 0
decay = "constant"
"#,
        run = run.display(),
        data = data.display(),
    )
}

fn train(text: &str, base: &Path) -> Result<(), String> {
    let config = TrainConfig::parse(text, base)?;
    let path = base.join("config.toml");
    train_config(
        &config,
        &path,
        &RunOptions {
            quiet: true,
            stop_at: None,
        },
    )
    .map(|_| ())
    .map_err(|e| e.to_string())
}

/// Every float parameter of a module, by path.
fn tensors<M: Module>(m: &M) -> BTreeMap<String, Vec<f32>> {
    struct V(Vec<String>, BTreeMap<String, Vec<f32>>);
    impl ModuleVisitor for V {
        fn enter_module(&mut self, name: &str, _: &str) {
            self.0.push(name.to_string());
        }
        fn exit_module(&mut self, _: &str, _: &str) {
            self.0.pop();
        }
        fn visit_float<const D: usize>(&mut self, p: &Param<Tensor<D>>) {
            let v = p
                .val()
                .into_data()
                .convert::<f32>()
                .try_to_vec::<f32>()
                .unwrap();
            self.1.insert(self.0.join("."), v);
        }
    }
    let mut v = V(Vec::new(), BTreeMap::new());
    m.visit(&mut v);
    v.1
}

/// Equal within half-precision rounding (weights are stored in f16 where burn-store's
/// adapter lists the layer).
fn close(a: &[f32], b: &[f32]) -> bool {
    a.len() == b.len()
        && a.iter()
            .zip(b)
            .all(|(x, y)| (x - y).abs() <= 1e-3 * y.abs().max(1.0))
}

fn assert_close(a: &BTreeMap<String, Vec<f32>>, b: &BTreeMap<String, Vec<f32>>, what: &str) {
    assert_eq!(a.len(), b.len(), "{what}: parameter count");
    for (name, v) in a {
        assert!(close(v, &b[name]), "{what}: {name} differs");
    }
}

#[test]
fn decoders_only_keeps_the_latent_and_trains_the_decoders() {
    let tmp = tempfile::tempdir().unwrap();
    let (data, base) = (tmp.path().join("data"), tmp.path());
    write_data(&data, 1.0);
    let first = base.join("first");
    train(&config(&data, &first, "", 0.0), base).unwrap();

    // Refused: decoders_only without init_from.
    let e = train(
        &config(&data, &base.join("bad"), "decoders_only = true", 1.0),
        base,
    )
    .unwrap_err();
    assert!(e.contains("init_from"), "{e}");

    let tuned = base.join("tuned");
    let extra = format!("init_from = \"{}\"\ndecoders_only = true", first.display());
    train(&config(&data, &tuned, &extra, 1.0), base).unwrap();
    let log = std::fs::read_to_string(tuned.join(files::LOG)).unwrap();
    assert!(
        log.lines().next().unwrap().contains("foot_velocity"),
        "{log}"
    );

    let dev = device::inference();
    let (_, a) = load_hfsq(&first, &dev).unwrap();
    let (_, b) = load_hfsq(&tuned, &dev).unwrap();
    let (a, b) = (tensors(&a), tensors(&b));
    assert_eq!(a.keys().collect::<Vec<_>>(), b.keys().collect::<Vec<_>>());
    let (mut kept, mut changed) = (0, 0);
    for (name, va) in &a {
        let same = va == &b[name];
        if name.contains("decoder") {
            changed += usize::from(!same);
        } else {
            assert!(same, "{name} changed under decoders_only");
            kept += 1;
        }
    }
    assert!(kept > 0, "no encoder parameters found");
    assert!(changed > 0, "the decoders did not learn");
}

#[test]
fn init_from_weights_of_other_data_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let base = tmp.path();
    let (data, other) = (base.join("data"), base.join("other"));
    write_data(&data, 1.0);
    write_data(&other, 0.5);
    let first = base.join("first");
    train(&config(&data, &first, "", 0.0), base).unwrap();
    let extra = format!("init_from = \"{}\"", first.display());
    let e = train(&config(&other, &base.join("second"), &extra, 0.0), base).unwrap_err();
    assert!(
        e.contains("normaliser") && e.contains(&first.display().to_string()),
        "{e}"
    );
    assert!(!base.join("second").join(files::CONFIG).exists());
}

/// A duet model directory from the autoencoder run `run`, with a fresh latent model and
/// non-default sampling settings.
fn write_bundle(run: &Path, out: &Path) {
    use dancegen_reactdance::bundle::{BundleConfig, KIND, files as bf};
    use dancegen_reactdance::config::{DenoiserConfig, SamplingDefaults};
    let dev = device::inference();
    let (ae_cfg, ae) = load_hfsq(run, &dev).unwrap();
    let denoiser = DenoiserConfig {
        d_model: 16,
        n_layers: 1,
        n_heads: 2,
        d_ff: 32,
        block_tokens: 8,
        ..Default::default()
    };
    std::fs::create_dir_all(out).unwrap();
    let net = denoiser.init(ae_cfg.latent_dim(), ae_cfg.frames_per_token(), &dev);
    let f32s = weights::Storage::F32;
    weights::save_as(&ae, &out.join(bf::HFSQ), Layout::Burn, &[], f32s).unwrap();
    weights::save_as(&net, &out.join(bf::DENOISER), Layout::Burn, &[], f32s).unwrap();
    std::fs::copy(run.join(files::NORMALIZER), out.join(bf::NORMALIZER)).unwrap();
    let config = BundleConfig {
        kind: KIND.into(),
        name: "tiny".into(),
        fps: 30.0,
        heading_sigma: 8.0,
        autoencoder: ae_cfg,
        denoiser,
        sampling: SamplingDefaults {
            guidance: vec![1.25, 0.75],
            ..Default::default()
        },
    };
    std::fs::write(out.join(bf::MODEL_TOML), toml::to_string(&config).unwrap()).unwrap();
}

#[test]
fn a_bundle_keeps_its_latent_model_when_its_autoencoder_is_swapped() {
    use dancegen_reactdance::bundle::DuetModel;
    let tmp = tempfile::tempdir().unwrap();
    let base = tmp.path();
    let data = base.join("data");
    write_data(&data, 1.0);
    let run = base.join("run");
    train(&config(&data, &run, "", 0.0), base).unwrap();
    let bundle = base.join("bundle");
    write_bundle(&run, &bundle);

    // The decoders fine-tuned from the bundle itself, then put back under its latent model.
    let tuned = base.join("tuned");
    let extra = format!("init_from = \"{}\"\ndecoders_only = true", bundle.display());
    train(&config(&data, &tuned, &extra, 1.0), base).unwrap();
    let out = base.join("out");
    assemble_duet_bundle(&tuned, &bundle, &out, "swapped").unwrap();

    let dev = device::inference();
    let before = DuetModel::load(&bundle, &dev).unwrap();
    let after = DuetModel::load(&out, &dev).unwrap();
    assert_eq!(after.config.name, "swapped");
    assert_eq!(after.config.sampling.guidance, vec![1.25, 0.75]);
    assert_eq!(after.config.autoencoder.foot_velocity_weight, 1.0);
    // The bundle's latent model, stored again in half precision.
    assert_close(
        &tensors(&after.denoiser),
        &tensors(&before.denoiser),
        "denoiser",
    );
    let (_, tuned_ae) = load_hfsq(&tuned, &dev).unwrap();
    let (a, b) = (tensors(&after.autoencoder), tensors(&before.autoencoder));
    assert_close(&a, &tensors(&tuned_ae), "autoencoder");
    let decoders = a
        .iter()
        .filter(|(name, v)| name.contains("decoder") && !close(v, &b[*name]))
        .count();
    assert!(decoders > 0, "the swapped bundle has the old decoders");

    // Refused: an autoencoder of another architecture under this latent model.
    let shipped = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models/reactdance-small");
    let e = assemble_duet_bundle(&run, &shipped, &base.join("bad"), "x")
        .unwrap_err()
        .to_string();
    assert!(e.contains("architecture"), "{e}");
    assert!(!base.join("bad").join("model.toml").exists());
}
