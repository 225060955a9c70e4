//! Checkpoints and exact resume: an interrupted-and-resumed run ends with bit-identical weights,
//! EMA weights and optimizer state to an uninterrupted one; a checkpoint survives a load/save
//! round trip; damaged checkpoints give errors naming the file.

mod common;

use std::collections::BTreeMap;
use std::path::Path;

use dancegen_nn::burn;

use burn::module::{Module, ModuleVisitor, Param};
use burn::optim::{GradientsParams, ModuleOptimizer};
use burn::tensor::{Tensor, TensorData};
use dancegen_nn::weights::{self, Layout};
use dancegen_train::TrainTask;
use dancegen_train::tasks::MotionAutoencoderTask;
use dancegen_train::trainer::{latest_checkpoint, load_checkpoint, save_checkpoint};
use dancegen_train::{RunOptions, TrainConfig, files, resume, train};

fn config(dir: &Path, steps: u64, seed: u64) -> TrainConfig {
    let text = common::tiny_config(dir, steps, seed);
    TrainConfig::parse(&text, dir).unwrap()
}

fn task(c: &TrainConfig) -> MotionAutoencoderTask {
    MotionAutoencoderTask::from_table(c.model_params(), 139, c.data.window).unwrap()
}

fn quiet(stop_at: Option<u64>) -> RunOptions {
    RunOptions {
        quiet: true,
        stop_at,
    }
}

/// Every float parameter and buffer of a module, by path.
fn tensors<M: Module>(m: &M) -> BTreeMap<String, TensorData> {
    struct V(Vec<String>, BTreeMap<String, TensorData>);
    impl ModuleVisitor for V {
        fn enter_module(&mut self, name: &str, _: &str) {
            self.0.push(name.into());
        }
        fn exit_module(&mut self, _: &str, _: &str) {
            self.0.pop();
        }
        fn visit_float<const D: usize>(&mut self, p: &Param<Tensor<D>>) {
            self.1.insert(self.0.join("."), p.val().into_data());
        }
    }
    let mut v = V(Vec::new(), BTreeMap::new());
    m.visit(&mut v);
    v.1
}

fn assert_bit_identical(a: &BTreeMap<String, TensorData>, b: &BTreeMap<String, TensorData>) {
    assert_eq!(a.keys().collect::<Vec<_>>(), b.keys().collect::<Vec<_>>());
    for (name, ta) in a {
        let (x, y) = (
            ta.try_to_vec::<f32>().unwrap(),
            b[name].try_to_vec::<f32>().unwrap(),
        );
        assert_eq!(ta.shape(), b[name].shape(), "{name}");
        let differ = x
            .iter()
            .zip(&y)
            .filter(|(p, q)| p.to_bits() != q.to_bits())
            .count();
        assert_eq!(differ, 0, "{name}: {differ} of {} values differ", x.len());
    }
}

/// One optimizer step with gradients made from the weights (`0.1·θ + 0.01`): equal results
/// from equal weights mean equal optimizer state.
fn probe_step<M: Module>(mut optim: ModuleOptimizer, model: M) -> BTreeMap<String, TensorData> {
    struct G<'a>(&'a mut GradientsParams);
    impl ModuleVisitor for G<'_> {
        fn visit_float<const D: usize>(&mut self, p: &Param<Tensor<D>>) {
            let v = p.val();
            if v.is_require_grad() {
                self.0
                    .register(p.id, v.inner().mul_scalar(0.1).add_scalar(0.01));
            }
        }
    }
    let mut grads = GradientsParams::new();
    model.visit(&mut G(&mut grads));
    assert!(grads.len() > 10);
    tensors(&optim.step(1e-3, model, grads))
}

#[test]
fn interrupted_and_resumed_run_is_bit_identical_to_an_uninterrupted_one() {
    let tmp = tempfile::tempdir().unwrap();
    let straight = tmp.path().join("straight");
    let interrupted = tmp.path().join("interrupted");
    let steps = 12;

    let c = config(&straight, steps, 7);
    let s = train(&task(&c), &c, &quiet(None)).unwrap();
    assert!(s.finished && s.step == steps);

    // Stop after step 6 (between the checkpoints at 4 and 8), then resume twice: the first
    // resume stops at 10, the second finishes. A resume starts from the latest checkpoint.
    let c2 = config(&interrupted, steps, 7);
    let s = train(&task(&c2), &c2, &quiet(Some(6))).unwrap();
    assert!(!s.finished && s.step == 6);
    assert!(!interrupted.join(files::WEIGHTS).exists());
    let s = resume(&task(&c2), &interrupted, &quiet(Some(10))).unwrap();
    assert_eq!((s.start_step, s.step), (6, 10));
    let s = resume(&task(&c2), &interrupted, &quiet(None)).unwrap();
    assert!(s.finished && s.start_step == 10 && s.step == steps);

    let device = dancegen_nn::device::training();
    let load = |dir: &Path, c: &TrainConfig| {
        let ck = latest_checkpoint(dir).unwrap();
        assert!(ck.ends_with(format!("step_{steps}")));
        load_checkpoint(&task(c), c, &ck, &device).unwrap()
    };
    let (a, b) = (load(&straight, &c), load(&interrupted, &c2));
    let (wa, wb) = (tensors(&a.model), tensors(&b.model));
    assert!(wa.len() > 10, "{} tensors", wa.len());
    assert_bit_identical(&wa, &wb);
    assert_bit_identical(
        &tensors(a.ema.as_ref().unwrap()),
        &tensors(b.ema.as_ref().unwrap()),
    );
    assert_eq!(a.state.data, b.state.data);
    // The optimizer state too: one more step with the same gradients lands on the same weights.
    assert_bit_identical(&probe_step(a.optim, a.model), &probe_step(b.optim, b.model));
    // And the final model (the EMA weights) and normaliser.
    let final_model = |dir: &Path| {
        let fresh = task(&c).init(&dancegen_nn::device::inference());
        tensors(&weights::load(fresh, &dir.join(files::WEIGHTS), Layout::Burn).unwrap())
    };
    let fa = final_model(&straight);
    assert_bit_identical(&fa, &final_model(&interrupted));
    assert_bit_identical(&fa, &tensors(a.ema.as_ref().unwrap()));
    let norm = |dir: &Path| std::fs::read(dir.join(files::NORMALIZER)).unwrap();
    assert!(norm(&straight) == norm(&interrupted));

    // The comparison can fail: another seed trains other weights, and training moved them.
    let other = tmp.path().join("other");
    let c3 = config(&other, 4, 8);
    train(&task(&c3), &c3, &quiet(None)).unwrap();
    let o = load_checkpoint(
        &task(&c3),
        &c3,
        &latest_checkpoint(&other).unwrap(),
        &device,
    )
    .unwrap();
    let wo = tensors(&o.model);
    assert!(wo.iter().any(|(k, v)| v != &wa[k]));
    let first =
        load_checkpoint(&task(&c), &c, &straight.join("checkpoints/step_4"), &device).unwrap();
    let w4 = tensors(&first.model);
    let moved = wa.keys().filter(|k| w4[*k] != wa[*k]).count();
    assert!(
        moved * 2 > wa.len(),
        "only {moved} of {} tensors changed between steps 4 and 12",
        wa.len()
    );
    // The log of the resumed run holds each logged step once.
    let log = std::fs::read_to_string(interrupted.join(files::LOG)).unwrap();
    let steps_logged: Vec<&str> = log
        .lines()
        .skip(1)
        .map(|l| l.split(',').next().unwrap())
        .collect();
    assert_eq!(steps_logged, ["2", "4", "6", "8", "10", "12"]);
}

#[test]
fn checkpoint_round_trip_restores_everything_and_damage_is_named() {
    let tmp = tempfile::tempdir().unwrap();
    let run = tmp.path().join("run");
    let c = config(&run, 8, 3);
    train(&task(&c), &c, &quiet(Some(4))).unwrap();
    let ck = latest_checkpoint(&run).unwrap();
    assert!(ck.ends_with("step_4"));
    for f in [files::WEIGHTS, files::EMA, files::OPTIMIZER, files::STATE] {
        assert!(ck.join(f).is_file(), "{f}");
    }
    assert!(run.join(files::CONFIG).is_file() && run.join(files::NORMALIZER).is_file());
    assert!(run.join(files::LOG).is_file() && run.join(files::LOSS_PNG).is_file());

    // Load, save elsewhere, load again: the same weights, EMA, optimizer state and position.
    // (The files' bytes may differ: safetensors headers and optimizer records are written in
    // hash-map order.)
    let device = dancegen_nn::device::training();
    let loaded = load_checkpoint(&task(&c), &c, &ck, &device).unwrap();
    let copy = tmp.path().join("copy");
    std::fs::create_dir_all(copy.join(files::CHECKPOINTS)).unwrap();
    save_checkpoint(
        &copy,
        &loaded.model,
        loaded.ema.as_ref(),
        &loaded.optim,
        &loaded.state,
    )
    .unwrap();
    let again = load_checkpoint(&task(&c), &c, &copy.join("checkpoints/step_4"), &device).unwrap();
    assert_bit_identical(&tensors(&loaded.model), &tensors(&again.model));
    assert_bit_identical(
        &tensors(loaded.ema.as_ref().unwrap()),
        &tensors(again.ema.as_ref().unwrap()),
    );
    assert_eq!(loaded.state.data, again.state.data);
    assert_eq!(loaded.state.param_ids, again.state.param_ids);
    let state_a = std::fs::read(ck.join(files::STATE)).unwrap();
    let state_b = std::fs::read(copy.join("checkpoints/step_4").join(files::STATE)).unwrap();
    assert!(state_a == state_b, "state.json changed in the round trip");
    assert_bit_identical(
        &probe_step(loaded.optim, loaded.model),
        &probe_step(again.optim, again.model),
    );

    // A truncated optimizer record: the error names the file.
    let op = ck.join(files::OPTIMIZER);
    let bytes = std::fs::read(&op).unwrap();
    std::fs::write(&op, &bytes[..bytes.len() / 2]).unwrap();
    let e = resume(&task(&c), &run, &quiet(None))
        .unwrap_err()
        .to_string();
    assert!(e.contains("optimizer.bpk"), "{e}");
    std::fs::write(&op, &bytes).unwrap();

    // Weights of another model: the error names the file and the tensor.
    let w = ck.join(files::WEIGHTS);
    let good = std::fs::read(&w).unwrap();
    let small = tmp.path().join("small");
    let mut c_small = config(&small, 2, 3);
    c_small
        .model
        .get_mut("codec")
        .unwrap()
        .as_table_mut()
        .unwrap()
        .insert("width".into(), 16.into());
    let t_small = MotionAutoencoderTask::from_table(c_small.model_params(), 139, 16).unwrap();
    train(&t_small, &c_small, &quiet(None)).unwrap();
    std::fs::copy(small.join(files::WEIGHTS), &w).unwrap();
    let e = resume(&task(&c), &run, &quiet(None))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("model.safetensors") && e.contains("encoder"),
        "{e}"
    );
    std::fs::write(&w, &good).unwrap();

    // Garbage state.json.
    std::fs::write(ck.join(files::STATE), b"{ not json").unwrap();
    let e = resume(&task(&c), &run, &quiet(None))
        .unwrap_err()
        .to_string();
    assert!(e.contains("state.json") && e.contains("corrupt"), "{e}");
}

#[test]
fn ema_is_a_copy_of_the_model_until_its_start_step() {
    let tmp = tempfile::tempdir().unwrap();
    let device = dancegen_nn::device::training();
    let steps = 8;
    let run = |name: &str, start: u64| {
        let dir = tmp.path().join(name);
        let text = common::tiny_config(&dir, steps, 5)
            .replace("decay = 0.9\n", &format!("decay = 0.9\nstart = {start}\n"));
        let c = TrainConfig::parse(&text, &dir).unwrap();
        train(&task(&c), &c, &quiet(None)).unwrap();
        let ck =
            load_checkpoint(&task(&c), &c, &latest_checkpoint(&dir).unwrap(), &device).unwrap();
        (tensors(&ck.model), tensors(ck.ema.as_ref().unwrap()))
    };
    // Copied through the last step: the average is the model.
    let (model, ema) = run("copy", steps);
    assert_bit_identical(&model, &ema);
    // Averaged over the last two steps only: same model (the EMA does not feed back into
    // training), an average that differs from it.
    let (model2, ema2) = run("late", steps - 2);
    assert_bit_identical(&model, &model2);
    assert!(
        ema2.iter().any(|(k, v)| v != &model2[k]),
        "averaging after the start step changed nothing"
    );
}
