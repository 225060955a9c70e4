//! The motion autoencoder (`dancegen_nn::autoencoder::MotionAutoencoder`: T2M-GPT / MoMask
//! style conv encoder → quantizer → conv decoder) trained on windows of real motion with its own
//! loss (reconstruction + velocity + commitment).

use dancegen_nn::autoencoder::{MotionAutoencoder, MotionAutoencoderConfig};
use dancegen_nn::burn::tensor::Device;
use dancegen_nn::conv::ConvCodecConfig;
use dancegen_nn::quant::QuantizerConfig;
use dancegen_nn::quant::vq::EmaVqConfig;

use crate::data::Batch;
use crate::task::{Losses, TrainTask};

/// `[model] kind`.
pub const KIND: &str = "motion_autoencoder";

/// See the module documentation.
#[derive(Clone, Debug)]
pub struct MotionAutoencoderTask {
    pub config: MotionAutoencoderConfig,
    table: toml::Table,
}

impl MotionAutoencoderTask {
    /// From the `[model]` table without `kind` (the fields of `MotionAutoencoderConfig`), for
    /// `dims`-wide motion windows of `window` frames.
    ///
    /// Burn's `Config` derive does not apply its `#[config(default)]`s when deserialising, so
    /// the defaults are filled in here (user keys win): the autoencoder's and the codec's
    /// defaults, the codec's `input_dim` / `output_dim` from the data, and the VQ's.
    pub fn from_table(table: toml::Table, dims: usize, window: usize) -> Result<Self, String> {
        let de = |e: toml::de::Error| format!("[model]: {}", e.message());
        let ser = |e: toml::ser::Error| format!("[model]: {e}");
        let codec_user = sub_table(&table, "codec")?;
        let codec_default = toml::Table::try_from(ConvCodecConfig::new(dims, dims)).map_err(ser)?;
        let codec: ConvCodecConfig = toml::Value::Table(merge(codec_default, codec_user))
            .try_into()
            .map_err(|e: toml::de::Error| format!("[model.codec]: {}", e.message()))?;
        let quant_user = sub_table(&table, "quantizer")?;
        let quant_filled = match (
            quant_user.get("kind").and_then(|k| k.as_str()),
            quant_user.get("nb_code").and_then(|v| v.as_integer()),
            quant_user.get("code_dim").and_then(|v| v.as_integer()),
        ) {
            (Some("vq"), Some(k), Some(d)) if k > 0 && d > 0 => {
                let mut t =
                    toml::Table::try_from(EmaVqConfig::new(k as usize, d as usize)).map_err(ser)?;
                t.insert("kind".into(), "vq".into());
                merge(t, quant_user)
            }
            _ => quant_user,
        };
        let quantizer: QuantizerConfig = toml::Value::Table(quant_filled.clone())
            .try_into()
            .map_err(|e: toml::de::Error| format!("[model.quantizer]: {}", e.message()))?;
        let mut filled =
            toml::Table::try_from(MotionAutoencoderConfig::new(codec, quantizer)).map_err(ser)?;
        // The quantizer as the user wrote it (+ defaults), with its `kind` tag.
        filled.insert("quantizer".into(), quant_filled.into());
        let mut user = table;
        user.remove("codec");
        user.remove("quantizer");
        let table = merge(filled, user);
        let config: MotionAutoencoderConfig =
            toml::Value::Table(table.clone()).try_into().map_err(de)?;
        // Burn's configs ignore unknown keys; a misspelt `widht` must not silently train the
        // default width.
        let known = toml::Table::try_from(&config).map_err(ser)?;
        let mut unknown = Vec::new();
        unknown_keys(&table, &known, "model", &mut unknown);
        if !unknown.is_empty() {
            return Err(format!("unknown keys: {}", unknown.join(", ")));
        }
        let c = &config.codec;
        if c.input_dim != dims || c.output_dim != dims {
            return Err(format!(
                "[model] codec input_dim / output_dim are {} / {}, the data has {dims} dims per frame",
                c.input_dim, c.output_dim
            ));
        }
        if c.code_dim != config.quantizer.dim() {
            return Err(format!(
                "[model] codec code_dim {} differs from the quantizer's width {}",
                c.code_dim,
                config.quantizer.dim()
            ));
        }
        let down = c.downsampling();
        if down == 0 || !window.is_multiple_of(down) {
            return Err(format!(
                "[data] window {window} is not a multiple of the codec's downsampling {down}"
            ));
        }
        Ok(Self { config, table })
    }
}

/// `t[key]` as a table (empty if absent).
fn sub_table(t: &toml::Table, key: &str) -> Result<toml::Table, String> {
    match t.get(key) {
        None => Ok(toml::Table::new()),
        Some(toml::Value::Table(s)) => Ok(s.clone()),
        Some(v) => Err(format!(
            "[model] {key} must be a table, not {}",
            v.type_str()
        )),
    }
}

/// Keys of `user` (as `[prefix] key` paths) that `known` does not have.
fn unknown_keys(user: &toml::Table, known: &toml::Table, prefix: &str, out: &mut Vec<String>) {
    for (k, v) in user {
        match (v, known.get(k)) {
            (_, None) => out.push(format!("[{prefix}] {k}")),
            (toml::Value::Table(u), Some(toml::Value::Table(kn))) => {
                unknown_keys(u, kn, &format!("{prefix}.{k}"), out)
            }
            _ => {}
        }
    }
}

/// `base` with every key of `over` replacing (tables: merging into) its own.
fn merge(mut base: toml::Table, over: toml::Table) -> toml::Table {
    for (k, v) in over {
        let v = match (base.remove(&k), v) {
            (Some(toml::Value::Table(b)), toml::Value::Table(o)) => toml::Value::Table(merge(b, o)),
            (_, v) => v,
        };
        base.insert(k, v);
    }
    base
}

impl TrainTask for MotionAutoencoderTask {
    type Model = MotionAutoencoder;

    fn kind(&self) -> &'static str {
        KIND
    }

    fn init(&self, device: &Device) -> MotionAutoencoder {
        self.config.init(device)
    }

    fn loss(&self, model: &MotionAutoencoder, batch: &Batch) -> Losses {
        autoencoder_losses(model, batch.motion.clone())
    }

    fn model_config(&self) -> toml::Table {
        self.table.clone()
    }
}

/// The autoencoder's loss on `x` `[B, T, C]` with its logged parts (reconstruction, velocity,
/// commitment, codebook perplexity where the quantizer has one).
pub fn autoencoder_losses(
    model: &MotionAutoencoder,
    x: dancegen_nn::burn::tensor::Tensor<3>,
) -> Losses {
    let l = model.loss(x);
    let mut parts = vec![
        ("recon", l.recon),
        ("velocity", l.velocity),
        ("commit", l.commit),
    ];
    if let Some(p) = l.output.quant.perplexity {
        parts.push(("perplexity", p));
    }
    Losses {
        total: l.total,
        parts,
    }
}
