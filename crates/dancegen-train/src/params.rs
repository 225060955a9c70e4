//! Module traversals by parameter path: the EMA of the weights, and parameter ids.
//!
//! Burn keys optimizer state by [`ParamId`], a random id drawn when a parameter is created. A
//! model rebuilt from its config on resume gets new ids, so a checkpoint stores each parameter's
//! id under its path and [`set_param_ids`] gives the rebuilt model its old ids back before the
//! optimizer record is loaded.

use std::collections::BTreeMap;

use dancegen_nn::burn;

use burn::module::{Module, ModuleMapper, ModuleVisitor, Param, ParamId};
use burn::tensor::Tensor;

/// Tracks the dotted path of the current parameter during a traversal.
#[derive(Default)]
struct PathStack(Vec<String>);

impl PathStack {
    fn enter(&mut self, name: &str) {
        self.0.push(name.to_string());
    }
    fn exit(&mut self) {
        self.0.pop();
    }
    fn join(&self) -> String {
        self.0.join(".")
    }
}

/// `path → id` of every float parameter.
pub fn param_ids<M: Module>(module: &M) -> BTreeMap<String, u64> {
    struct V(PathStack, BTreeMap<String, u64>);
    impl ModuleVisitor for V {
        fn enter_module(&mut self, name: &str, _: &str) {
            self.0.enter(name);
        }
        fn exit_module(&mut self, _: &str, _: &str) {
            self.0.exit();
        }
        fn visit_float<const D: usize>(&mut self, p: &Param<Tensor<D>>) {
            self.1.insert(self.0.join(), p.id.val());
        }
    }
    let mut v = V(PathStack::default(), BTreeMap::new());
    module.visit(&mut v);
    v.1
}

/// Gives each float parameter the id stored under its path. Errors name the parameters that
/// are missing from `ids` (a checkpoint of a different model).
pub fn set_param_ids<M: Module>(module: M, ids: &BTreeMap<String, u64>) -> Result<M, String> {
    struct Mp<'a>(PathStack, &'a BTreeMap<String, u64>, Vec<String>);
    impl ModuleMapper for Mp<'_> {
        fn enter_module(&mut self, name: &str, _: &str) {
            self.0.enter(name);
        }
        fn exit_module(&mut self, _: &str, _: &str) {
            self.0.exit();
        }
        fn map_float<const D: usize>(&mut self, p: Param<Tensor<D>>) -> Param<Tensor<D>> {
            let path = self.0.join();
            match self.1.get(&path) {
                Some(&id) => {
                    let (_, t, mapper) = p.consume();
                    Param::from_mapped_value(ParamId::from(id), t, mapper)
                }
                None => {
                    self.2.push(path);
                    p
                }
            }
        }
    }
    let mut m = Mp(PathStack::default(), ids, Vec::new());
    let module = module.map(&mut m);
    if m.2.is_empty() {
        Ok(module)
    } else {
        Err(format!("no parameter id recorded for {}", m.2.join(", ")))
    }
}

/// Every float parameter's value flattened to one dimension (detached), by path, and whether it
/// is trained (requires a gradient) rather than a buffer such as a [`RunningState`].
///
/// [`RunningState`]: burn::module::RunningState
fn flat_values<M: Module>(module: &M) -> BTreeMap<String, (Tensor<1>, bool)> {
    struct V(PathStack, BTreeMap<String, (Tensor<1>, bool)>);
    impl ModuleVisitor for V {
        fn enter_module(&mut self, name: &str, _: &str) {
            self.0.enter(name);
        }
        fn exit_module(&mut self, _: &str, _: &str) {
            self.0.exit();
        }
        fn visit_float<const D: usize>(&mut self, p: &Param<Tensor<D>>) {
            let t = p.val();
            let trained = t.is_require_grad();
            let n = t.shape().num_elements();
            self.1
                .insert(self.0.join(), (t.detach().reshape([n]), trained));
        }
    }
    let mut v = V(PathStack::default(), BTreeMap::new());
    module.visit(&mut v);
    v.1
}

/// Makes every [`RunningState`] of `module` hold its latest value.
///
/// A running state updated during a forward pass (the VQ's EMA codebook) keeps the new value
/// in a per-thread slot until the next `value_sync`; visiting the module (saving it, copying it)
/// sees the previous value. `Module::valid` syncs every running state in place as a side effect;
/// its returned copy is dropped.
///
/// [`RunningState`]: burn::module::RunningState
pub fn sync_running_states<M: Module>(module: &M) {
    let _ = module.valid();
}

/// The exponential moving average of a model's weights (EDGE: `ema ← β·ema + (1 − β)·θ` every
/// step, `Stanford-TML/EDGE:model/diffusion.py` `EMA.update_model_average`).
///
/// Only trained parameters are averaged; buffers ([`RunningState`]s such as an EMA codebook)
/// are copied from the model, so the average stays consistent with the quantizer it decodes
/// with. The average is a separate module of the model's type (built fresh, so it shares no
/// running state with the model) whose parameters never require gradients.
///
/// [`RunningState`]: burn::module::RunningState
#[derive(Clone, Debug)]
pub struct Ema<M> {
    pub model: M,
    pub decay: f64,
}

impl<M: Module> Ema<M> {
    /// Starts the average at `model`'s current values, in `fresh` (a newly built module of the
    /// same configuration).
    pub fn new(fresh: M, model: &M, decay: f64) -> Self {
        let mut e = Self {
            model: fresh.set_require_grad(false),
            decay,
        };
        e.blend(model, 0.0);
        e
    }

    /// The average restarted at `model`'s values.
    pub fn reset(&mut self, model: &M) {
        self.blend(model, 0.0);
    }

    /// One update towards `model` (call after [`sync_running_states`]).
    pub fn update(&mut self, model: &M) {
        self.blend(model, self.decay);
    }

    fn blend(&mut self, model: &M, decay: f64) {
        struct Mp {
            path: PathStack,
            new: BTreeMap<String, (Tensor<1>, bool)>,
            decay: f64,
        }
        impl ModuleMapper for Mp {
            fn enter_module(&mut self, name: &str, _: &str) {
                self.path.enter(name);
            }
            fn exit_module(&mut self, _: &str, _: &str) {
                self.path.exit();
            }
            fn map_float<const D: usize>(&mut self, p: Param<Tensor<D>>) -> Param<Tensor<D>> {
                let Some((new, trained)) = self.new.remove(&self.path.join()) else {
                    return p;
                };
                let decay = if trained { self.decay } else { 0.0 };
                p.map(|old| {
                    let shape = old.shape();
                    let new = new.reshape(shape);
                    if decay == 0.0 {
                        new
                    } else {
                        (old.detach().mul_scalar(decay) + new.mul_scalar(1.0 - decay)).detach()
                    }
                })
            }
        }
        let mut m = Mp {
            path: PathStack::default(),
            new: flat_values(model),
            decay,
        };
        self.model = self.model.clone().map(&mut m);
    }
}
