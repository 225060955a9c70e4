//! The seam between the training loop and a model: each dance system implements [`TrainTask`]
//! for its model and loss, and gets data, optimizers, schedules, EMA, checkpoints, exact resume
//! and logging from [`crate::train`].

use dancegen_nn::burn;

use burn::module::Module;
use burn::store::ModuleSnapshot;
use burn::tensor::{Device, Tensor};

use crate::data::{Batch, Normalizer};

/// The losses of one batch: `total` is differentiated, `parts` are logged (as scalars).
pub struct Losses {
    pub total: Tensor<1>,
    pub parts: Vec<(&'static str, Tensor<1>)>,
}

/// A model plus its training loss.
pub trait TrainTask {
    type Model: Module + ModuleSnapshot + Clone + Send + 'static;

    /// The `[model] kind` this task answers to, written to `model.toml`.
    fn kind(&self) -> &'static str;

    /// A freshly initialised model on `device` (the training device: autodiff). Random
    /// initialisation draws from the device's generator, which the trainer seeds first.
    fn init(&self, device: &Device) -> Self::Model;

    /// A fresh model for a new run whose data `normalizer` maps: for models that carry the
    /// statistics inside (e.g. to run forward kinematics on their own de-normalised output).
    /// Checkpoints restore those from the weights, so resuming uses [`TrainTask::init`].
    fn init_with_data(&self, device: &Device, normalizer: &Normalizer) -> Self::Model {
        let _ = normalizer;
        self.init(device)
    }

    /// Checks a new run's data against what the task was told to start from (e.g. weights
    /// trained with another normaliser), before anything is initialised: a clear error instead
    /// of a model that reads its data in the wrong units.
    fn check_data(&self, normalizer: &Normalizer) -> Result<(), String> {
        let _ = normalizer;
        Ok(())
    }

    /// The loss of `model` on `batch` (`[B, window, dims]`, normalised).
    fn loss(&self, model: &Self::Model, batch: &Batch) -> Losses;

    /// The model's configuration as a TOML table (without `kind`), saved next to its weights.
    fn model_config(&self) -> toml::Table;
}
