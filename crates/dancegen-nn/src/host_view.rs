//! Reading an inference tensor's `f32`s on the host without copying them.
//!
//! `Tensor::into_data` copies a buffer that anything else still holds (a module's weights,
//! an activation that feeds the query, key and value projections) and then copies it again
//! into an aligned allocation (burn-flex 0.22). The host kernels ([`crate::host_linear`],
//! [`crate::host_attention`]) only read their inputs, so they take this view instead: the
//! flex tensor's own storage, shared through its reference count.

use burn::tensor::{DType, Device, Tensor, TensorData};
use burn_flex::{Flex, FlexTensor};

/// Whether a tensor can take the host path: plain `f32` on the flex CPU backend (a GPU
/// tensor keeps Burn's op), no autodiff.
pub fn eligible<const D: usize>(t: &Tensor<D>) -> bool {
    !t.is_autodiff() && t.dtype() == DType::F32 && t.device() == Device::flex()
}

/// The row-major `f32`s of an [`eligible`] tensor.
#[derive(Clone, Debug)]
pub enum HostF32 {
    /// A contiguous flex tensor, read where it lies.
    Shared(FlexTensor),
    /// A copy (a strided view, or a tensor the flex backend did not give up).
    Copied(TensorData),
}

impl HostF32 {
    /// Views `t` ([`eligible`]); copies only when its layout is not contiguous.
    pub fn new<const D: usize>(t: &Tensor<D>) -> Self {
        match t.clone().try_into_primitive::<Flex>() {
            Ok(flex) if flex.layout().is_contiguous() => HostF32::Shared(flex),
            _ => HostF32::Copied(t.clone().into_data()),
        }
    }

    /// The elements in row-major order.
    pub fn as_slice(&self) -> &[f32] {
        match self {
            HostF32::Shared(flex) => {
                let start = flex.layout().start_offset();
                let n = flex.layout().num_elements();
                &flex.storage::<f32>()[start..start + n]
            }
            HostF32::Copied(data) => data.as_slice::<f32>().expect("eligible tensors are f32"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn views_shared_narrowed_and_transposed_tensors_in_row_major_order() {
        let dev = Device::flex();
        let xs: Vec<f32> = (0..24).map(|i| i as f32).collect();
        let t = Tensor::<2>::from_data(TensorData::new(xs.clone(), [4, 6]), &dev);
        let kept = t.clone();
        assert!(matches!(HostF32::new(&t), HostF32::Shared(_)));
        assert_eq!(HostF32::new(&t).as_slice(), &xs[..]);
        // Rows 1..3: contiguous at an offset.
        assert_eq!(
            HostF32::new(&t.clone().narrow(0, 1, 2)).as_slice(),
            &xs[6..18]
        );
        // A transpose is strided: copied, in the transposed order.
        let tt = t.swap_dims(0, 1);
        let want: Vec<f32> = (0..6)
            .flat_map(|c| (0..4).map(move |r| (r * 6 + c) as f32))
            .collect();
        assert_eq!(HostF32::new(&tt).as_slice(), &want[..]);
        let kept: Vec<f32> = kept.into_data().try_into_vec().unwrap();
        assert_eq!(kept, xs);
    }
}
