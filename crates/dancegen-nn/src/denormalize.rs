//! A mean/std normaliser undone on tensors, differentiably: for losses measured in real units
//! (metres, m/s) on a network's normalised output (the duet follower's and the holistic body's
//! foot velocity losses).

use burn::tensor::{Device, Tensor, TensorData};

/// The first `dims` channels' mean and std of a normaliser.
#[derive(Clone, Debug)]
pub struct Denormalizer {
    mean: Vec<f32>,
    std: Vec<f32>,
}

impl Denormalizer {
    /// The first `dims` channels of a normaliser's `mean` and `std` (which may have more).
    pub fn first(mean: &[f64], std: &[f64], dims: usize) -> Result<Self, String> {
        if mean.len() < dims || std.len() < dims {
            return Err(format!(
                "the normaliser has {} means and {} stds, {dims} are needed",
                mean.len(),
                std.len()
            ));
        }
        Ok(Self {
            mean: mean[..dims].iter().map(|&v| v as f32).collect(),
            std: std[..dims].iter().map(|&v| v as f32).collect(),
        })
    }

    /// Channels it undoes.
    pub fn dims(&self) -> usize {
        self.mean.len()
    }

    /// Normalised `[B, T, D ≥ dims]` → the first `dims` channels in their units,
    /// `x · std + mean`.
    pub fn apply(&self, x: Tensor<3>) -> Tensor<3> {
        let [b, t, _] = x.dims();
        let d = self.dims();
        let device: Device = x.device();
        let row = |v: &[f32]| {
            Tensor::<1>::from_data(TensorData::new(v.to_vec(), [d]), &device)
                .reshape([1, 1, d])
                .expand([b, t, d])
        };
        x.narrow(2, 0, d) * row(&self.std) + row(&self.mean)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::device;

    #[test]
    fn undoes_the_first_channels_and_names_a_short_normaliser() {
        let dev = device::inference();
        let d = Denormalizer::first(&[1.0, -2.0, 9.0], &[2.0, 0.5, 9.0], 2).unwrap();
        let x = Tensor::<3>::from_data(
            TensorData::new(vec![0.0f32, 2.0, 7.0, 1.0, -4.0, 7.0], [1, 2, 3]),
            &dev,
        );
        let y: Vec<f32> = d.apply(x).into_data().try_to_vec::<f32>().unwrap();
        assert_eq!(y, vec![1.0, -1.0, 3.0, -4.0]);
        let e = Denormalizer::first(&[0.0; 3], &[1.0; 2], 3).unwrap_err();
        assert!(
            e.contains("3 means and 2 stds") && e.contains("3 are needed"),
            "{e}"
        );
    }
}
