//! `dancegen models` and `dancegen bundle`: finding, installing and assembling models.

use std::path::PathBuf;

use clap::{Args, Subcommand};

#[derive(Args, Debug)]
pub struct ModelsArgs {
    #[command(subcommand)]
    pub command: Option<ModelsCommand>,
    /// Print the list as JSON.
    #[arg(long)]
    pub json: bool,
}

#[derive(Subcommand, Debug)]
pub enum ModelsCommand {
    /// The models found on the search path, and the folders searched (the default).
    List {
        /// Print the list as JSON.
        #[arg(long)]
        json: bool,
    },
    /// Copy models (folders holding model.toml) into the data folder, where every dancegen
    /// binary of this user finds them.
    Install {
        /// A folder of models or one model folder (default: the models/ folder of the
        /// checkout this binary was built from).
        #[arg(long, value_name = "DIR")]
        from: Option<PathBuf>,
        /// Destination folder of models (default: the platform data folder).
        #[arg(long, value_name = "DIR")]
        to: Option<PathBuf>,
    },
}

#[derive(Args, Debug)]
pub struct BundleArgs {
    /// Finished `lodgepp_vqvae` run directory (solo model).
    #[arg(long, value_name = "RUN", requires_all = ["gpt", "pddm"], conflicts_with_all = ["hfsq", "ldm"])]
    pub vqvae: Option<PathBuf>,
    /// Finished `lodgepp_gpt` run directory (solo model).
    #[arg(long, value_name = "RUN", requires = "vqvae")]
    pub gpt: Option<PathBuf>,
    /// Finished `lodgepp_pddm` run directory (solo model).
    #[arg(long, value_name = "RUN", requires = "vqvae")]
    pub pddm: Option<PathBuf>,
    /// Finished `reactdance_hfsq` run directory (duet model).
    #[arg(long, value_name = "RUN", requires = "ldm")]
    pub hfsq: Option<PathBuf>,
    /// Finished `reactdance_ldm` run directory (duet model), or a duet model directory: its
    /// latent model, normaliser and sampling settings are kept, its autoencoder replaced.
    #[arg(long, value_name = "RUN", requires = "hfsq")]
    pub ldm: Option<PathBuf>,
    /// Finished `tcdiffpp_group` run directory (group model).
    #[arg(long, value_name = "RUN", conflicts_with_all = ["vqvae", "hfsq"])]
    pub group: Option<PathBuf>,
    /// Finished `soulnet_vq` run directory (holistic model; with --holistic-mmr and
    /// --holistic-generator, or with --holistic-model).
    #[arg(long, value_name = "RUN", conflicts_with_all = ["vqvae", "hfsq", "group"])]
    pub holistic_vq: Option<PathBuf>,
    /// Finished `soulnet_mmr` run directory (holistic model).
    #[arg(long, value_name = "RUN", requires_all = ["holistic_vq", "holistic_generator"])]
    pub holistic_mmr: Option<PathBuf>,
    /// Finished `soulnet_magm` run directory (holistic model; with --holistic-vq and
    /// --holistic-mmr, or with --holistic-model).
    #[arg(long, value_name = "RUN", conflicts_with_all = ["vqvae", "hfsq", "group"])]
    pub holistic_generator: Option<PathBuf>,
    /// A holistic model directory whose other networks, normaliser and sampling are kept: its
    /// part autoencoder replaced by --holistic-vq's (a decoder fine-tuned with `[model]
    /// decoders_only`, say) and/or its generator by --holistic-generator's (one trained with
    /// `[model] vq` and `mmr` naming this model).
    #[arg(long, value_name = "MODEL_DIR", conflicts_with = "holistic_mmr")]
    pub holistic_model: Option<PathBuf>,
    /// Model name written to model.toml (default: lodgepp-small, reactdance-small,
    /// tcdiffpp-small or soulnet-small).
    #[arg(long)]
    pub name: Option<String>,
    #[arg(long)]
    pub default_genre: Option<String>,
    /// Output model directory.
    #[arg(short, long, value_name = "DIR")]
    pub output: PathBuf,
}
