//! Parity fixtures written by `tools/parity/*.py` (PyTorch CPU, run by developers, committed):
//! `tests/fixtures/parity/<name>.weights.safetensors` — the reference module's state dict
//! (PyTorch layout) — and `<name>.io.safetensors` — inputs `in.*`, outputs `out.*`, gradients
//! `grad.*`, and the JSON config in the header metadata under `config`.

#![allow(dead_code)]

use std::collections::HashMap;
use std::path::PathBuf;

use dancegen_nn::burn::tensor::{Device, Int, Tensor, TensorData};

pub fn fixture_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/parity")
}

pub struct Fixture {
    pub name: String,
    tensors: HashMap<String, (Vec<usize>, Vec<f32>)>,
    pub config: serde_json::Value,
}

impl Fixture {
    pub fn load(name: &str) -> Fixture {
        let path = fixture_dir().join(format!("{name}.io.safetensors"));
        let bytes = std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let (_, meta) = safetensors::SafeTensors::read_metadata(&bytes).unwrap();
        let config = meta
            .metadata()
            .as_ref()
            .and_then(|m| m.get("config"))
            .map(|c| serde_json::from_str(c).unwrap())
            .unwrap_or(serde_json::Value::Null);
        let st = safetensors::SafeTensors::deserialize(&bytes).unwrap();
        let mut tensors = HashMap::new();
        for (k, v) in st.tensors() {
            let data: Vec<f32> = match v.dtype() {
                safetensors::Dtype::F32 => v
                    .data()
                    .chunks_exact(4)
                    .map(|b| f32::from_le_bytes(b.try_into().unwrap()))
                    .collect(),
                safetensors::Dtype::I64 => v
                    .data()
                    .chunks_exact(8)
                    .map(|b| i64::from_le_bytes(b.try_into().unwrap()) as f32)
                    .collect(),
                safetensors::Dtype::BOOL => v.data().iter().map(|&b| f32::from(b)).collect(),
                d => panic!("{name}: tensor {k} has dtype {d:?}"),
            };
            tensors.insert(k.to_string(), (v.shape().to_vec(), data));
        }
        Fixture {
            name: name.to_string(),
            tensors,
            config,
        }
    }

    pub fn weights_path(&self) -> PathBuf {
        fixture_dir().join(format!("{}.weights.safetensors", self.name))
    }

    pub fn raw(&self, key: &str) -> &(Vec<usize>, Vec<f32>) {
        self.tensors
            .get(key)
            .unwrap_or_else(|| panic!("{}: no tensor {key}", self.name))
    }

    pub fn has(&self, key: &str) -> bool {
        self.tensors.contains_key(key)
    }

    pub fn tensor<const D: usize>(&self, key: &str, device: &Device) -> Tensor<D> {
        let (shape, data) = self.raw(key);
        assert_eq!(shape.len(), D, "{}: {key} has shape {shape:?}", self.name);
        Tensor::from_data(TensorData::new(data.clone(), shape.clone()), device)
    }

    pub fn int_tensor<const D: usize>(&self, key: &str, device: &Device) -> Tensor<D, Int> {
        let (shape, data) = self.raw(key);
        let ints: Vec<i64> = data.iter().map(|&v| v as i64).collect();
        Tensor::from_data(TensorData::new(ints, shape.clone()), device)
    }

    pub fn cfg_usize(&self, key: &str) -> usize {
        self.config[key]
            .as_u64()
            .unwrap_or_else(|| panic!("{}: config {key}", self.name)) as usize
    }

    pub fn cfg_f64(&self, key: &str) -> f64 {
        self.config[key]
            .as_f64()
            .unwrap_or_else(|| panic!("{}: config {key}", self.name))
    }
}

/// Asserts `actual` matches fixture tensor `key` within `rel` of the expected tensor's largest
/// magnitude; prints the error so the test log documents the agreement.
pub fn assert_close<const D: usize>(fx: &Fixture, key: &str, actual: Tensor<D>, rel: f64) {
    let (shape, expected) = fx.raw(key);
    assert_eq!(actual.dims().to_vec(), *shape, "{}: {key} shape", fx.name);
    let got: Vec<f32> = actual.into_data().try_into_vec::<f32>().unwrap();
    let scale = expected
        .iter()
        .fold(0f64, |m, &v| m.max(f64::from(v).abs()));
    let err = got.iter().zip(expected).fold(0f64, |m, (&a, &e)| {
        m.max((f64::from(a) - f64::from(e)).abs())
    });
    let r = err / scale.max(1e-30);
    println!(
        "{}: {key}: max abs err {err:.3e}, relative {r:.3e}",
        fx.name
    );
    assert!(
        r <= rel,
        "{}: {key} differs: max abs err {err:.3e} = {r:.3e} of max |expected| {scale:.3e}",
        fx.name
    );
}
