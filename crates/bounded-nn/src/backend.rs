//! The one place that touches Burn's backend choice and tensor read-back.

use burn::prelude::*;

use crate::NnError;

/// Burn's CPU device used for training and for Burn-side evaluation.
///
/// burn 0.22 marks its NdArray backend deprecated in favour of Flex; the workspace pins the
/// `ndarray` feature, so the choice is isolated here.
#[allow(deprecated)]
pub fn cpu_device() -> Device {
    Device::ndarray()
}

/// Reads a float tensor back as a flat row-major vector.
pub(crate) fn read_f32<const D: usize>(tensor: Tensor<D>) -> Result<Vec<f32>, NnError> {
    tensor
        .try_into_data()
        .map_err(|e| NnError::Tensor(format!("{e:?}")))?
        .try_into_vec::<f32>()
        .map_err(|e| NnError::Tensor(format!("{e:?}")))
}
