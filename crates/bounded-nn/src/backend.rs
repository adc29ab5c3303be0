//! The one place that touches Burn's backend choice and tensor read-back.

use burn::prelude::*;

use crate::NnError;

/// Burn's CPU device used for training and for Burn-side evaluation: Flex, burn 0.22's
/// pure-Rust CPU backend (NdArray is deprecated there). Measured on the 2-core machine with the
/// default network at batch 16384: 0.034 s per training iteration with Flex against 0.100 s
/// with NdArray (both with SIMD and rayon enabled).
pub fn cpu_device() -> Device {
    Device::flex()
}

/// Reads a float tensor back as a flat row-major vector.
pub(crate) fn read_f32<const D: usize>(tensor: Tensor<D>) -> Result<Vec<f32>, NnError> {
    tensor
        .try_into_data()
        .map_err(|e| NnError::Tensor(format!("{e:?}")))?
        .try_into_vec::<f32>()
        .map_err(|e| NnError::Tensor(format!("{e:?}")))
}
